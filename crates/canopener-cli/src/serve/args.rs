//! Command-line grammar of `canopener serve`.

use std::net::SocketAddr;
use std::path::PathBuf;

use clap::Args;

#[derive(Debug, Args)]
pub(crate) struct ServeArgs {
    /// The address to listen on. Anything but loopback needs the token (printed at start, or
    /// --token-file).
    #[arg(long, value_name = "ADDRESS", default_value = "127.0.0.1:8080")]
    pub(crate) listen: SocketAddr,
    /// The system to monitor: a Nodelist.graphml or nodelist.cpj (its DCFs beside it).
    #[arg(long, value_name = "FILE")]
    pub(crate) nodelist: Option<PathBuf>,
    /// A bus: `SPEC` for the monitor's network, `N=SPEC` for network N (repeat per network). Runs
    /// from /test can use them too.
    #[arg(long = "bus", value_name = "SPEC|N=SPEC")]
    pub(crate) buses: Vec<String>,
    /// Where the monitor is connected: a vertex id or NodeName (default: the master, else the lowest
    /// node-ID).
    #[arg(long, value_name = "VERTEX", requires = "nodelist")]
    pub(crate) at: Option<String>,
    /// Keep the run history and uploaded descriptions in DIR (SQLite); without it nothing is stored.
    #[arg(long, value_name = "DIR")]
    pub(crate) data: Option<PathBuf>,
    /// Read the access token from FILE (at least 16 letters, digits, - or _) instead of making one.
    #[arg(long, value_name = "FILE")]
    pub(crate) token_file: Option<PathBuf>,
    /// The largest upload accepted: bytes, or with KiB or MiB.
    #[arg(long, value_name = "SIZE", default_value = "16MiB", value_parser = parse_size)]
    pub(crate) max_upload: usize,
}

/// `16MiB`, `512KiB`, `1000`.
pub(crate) fn parse_size(text: &str) -> Result<usize, String> {
    let text = text.trim();
    let (number, factor) = if let Some(n) = text.strip_suffix("MiB") {
        (n, 1024 * 1024)
    } else if let Some(n) = text.strip_suffix("KiB") {
        (n, 1024)
    } else {
        (text, 1)
    };
    let n: usize = number
        .trim()
        .parse()
        .map_err(|_| format!("{text:?} is not a size: give bytes, or a number with KiB or MiB (16MiB)"))?;
    n.checked_mul(factor)
        .filter(|n| *n > 0)
        .ok_or_else(|| format!("{text:?}: give a size above 0 that fits the machine"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_take_kib_and_mib() {
        assert_eq!(parse_size("16MiB"), Ok(16 * 1024 * 1024));
        assert_eq!(parse_size("512KiB"), Ok(512 * 1024));
        assert_eq!(parse_size("1000"), Ok(1000));
        assert!(parse_size("0").is_err());
        assert!(parse_size("lots").unwrap_err().contains("not a size"));
    }
}
