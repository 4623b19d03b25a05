//! `canopener bus serve`: the socketcand-compatible hub, until Ctrl-C or SIGTERM.

use std::io::Write;

use canopener_hub::{Hub, HubConfig};

use crate::bus::args::ServeArgs;
use crate::error::{CliError, CliResult, stdout_error};

pub(crate) fn run(args: ServeArgs) -> CliResult {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|err| CliError::Internal(anyhow::anyhow!("cannot start the async runtime: {err}")))?;
    runtime.block_on(serve(args))
}

async fn serve(args: ServeArgs) -> CliResult {
    let mut config = HubConfig::new(args.listen);
    config.raw_grace = args.raw_grace;
    config.stall_timeout = args.stall_timeout;
    config.echo = args.echo;
    let hub = Hub::bind(config).await.map_err(|err| {
        CliError::Bus(canopener_transport::TransportError::Io {
            endpoint: format!("socketcand://{}", args.listen),
            operation: "listening",
            hint: "is another hub already using this port? pick another with --listen 127.0.0.1:PORT",
            source: err,
        })
    })?;
    let addr = hub.local_addr();
    {
        // The first stdout line is machine-readable on purpose: scripts and tests wait for it.
        let mut out = std::io::stdout().lock();
        writeln!(out, "canopener hub listening on socketcand://{addr}").map_err(stdout_error)?;
        writeln!(
            out,
            "  connect with --bus socketcand://{addr}/can0, or python-can: \
             can.Bus(interface=\"socketcand\", host=\"{}\", port={}, channel=\"can0\")",
            addr.ip(),
            addr.port()
        )
        .map_err(stdout_error)?;
        out.flush().map_err(stdout_error)?;
    }
    let stats = hub.stats();
    let stats_every = args.stats_every;
    let reporter = async move {
        if stats_every.is_zero() {
            return std::future::pending::<()>().await;
        }
        let mut ticker = tokio::time::interval(stats_every);
        ticker.tick().await;
        loop {
            ticker.tick().await;
            eprintln!("{}", stats_line(&stats.snapshot()));
        }
    };
    tokio::select! {
        result = hub.run() => result.map_err(|err| CliError::Internal(anyhow::anyhow!("the hub stopped: {err}"))),
        () = reporter => Ok(()),
        () = shutdown_signal() => {
            eprintln!("stopping the hub");
            Ok(())
        }
    }
}

async fn shutdown_signal() {
    let ctrl_c = async {
        if tokio::signal::ctrl_c().await.is_err() {
            std::future::pending::<()>().await;
        }
    };
    #[cfg(unix)]
    let terminate = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut signal) => {
                signal.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let terminate = std::future::pending::<()>();
    tokio::select! {
        () = ctrl_c => {},
        () = terminate => {},
    }
}

fn stats_line(stats: &canopener_hub::HubStats) -> String {
    format!(
        "hub: {} clients ({} since start, {} dropped), {} buses, {} frames in, {} deliveries out, \
         {} garbage elements",
        stats.clients_active,
        stats.clients_connected,
        stats.clients_dropped,
        stats.buses_active,
        stats.frames_in,
        stats.frames_out,
        stats.garbage_elements
    )
}
