//! `canopener node dump`: every readable entry an EDS lists, read from a device over SDO into a DCF
//! (CiA 306 §5). `canopener_master::dcf_dump` plans the reads and builds the DCF (its module docs say
//! which entries and which notations), `canopener_link::node_dump` reads and writes; this module
//! checks the arguments and reports.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use canopener_files::same_file;
use canopener_link::link::Link;
use canopener_link::node_dump::{DumpError, dcf_time, read_entries, write_dcf};
use canopener_master::dcf_dump::{DcfOptions, DumpTally, build_dcf, plan};
use serde_json::json;

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult};
use crate::master::args::NodeDumpArgs;
use crate::master::link::open_session;
use crate::master::output::{count_bar, millis, output_error, print_json, refuse_existing, session_error};
use crate::output::print_stdout;
use canopener_runtime::description::read_description;

pub(crate) fn run(args: NodeDumpArgs) -> CliResult {
    if args.output.is_none() && args.master.format == OutputFormat::Json {
        return Err(CliError::Usage(
            "--format json needs -o FILE: without it the DCF itself goes to stdout; e.g. \
             canopener node dump --node 5 --eds device.eds -o node5.dcf --format json"
                .to_owned(),
        ));
    }
    if let Some(out) = &args.output {
        if same_file(out, &args.eds) {
            return Err(CliError::Usage(format!(
                "-o {} is the EDS itself; write the DCF elsewhere, e.g. -o node{}.dcf",
                out.display(),
                args.target.node
            )));
        }
        refuse_existing(out, args.force)?;
    }
    let node = args.target.node;
    let input = read_description(&args.eds)?;
    let plan = plan(&input.eds);
    let mut session = open_session(&args.master, node, "node dump")?;
    let started = session.link_mut().now();
    let to_read = plan.iter().filter(|entry| entry.skip.is_none()).count();
    let bar = count_bar(
        to_read as u64,
        "{spinner} reading {pos}/{len} entries {wide_bar} {eta} {msg}",
    );
    let readings = read_entries(&mut session, &plan, |entry| {
        bar.set_message(entry.label());
        bar.inc(1);
    });
    bar.finish_and_clear();
    let readings = readings.map_err(|err| match err {
        DumpError::Session(err) => session_error(node, err),
        other => CliError::Device(other.to_string()),
    })?;
    let elapsed = session.link_mut().now().saturating_duration_since(started);
    let options = DcfOptions {
        node,
        bitrate: args.bitrate,
        eds_path: &args.eds,
        output: args.output.as_deref(),
        now: dcf_time(),
    };
    let dcf = build_dcf(&input.eds, input.document.as_ref(), &plan, &readings, options)
        .map_err(|err| CliError::output("encoding the DCF", std::io::Error::other(err.to_string())))?;
    match &args.output {
        Some(out) => {
            for (file, _) in &dcf.sidecars {
                refuse_existing(file, args.force)?;
            }
            write_dcf(out, &dcf, args.force).map_err(|err| output_error(&err.file, err.source))?;
            match args.master.format {
                OutputFormat::Json => {
                    print_json(&summary_json(&dcf.summary, node, out, elapsed, &dcf.sidecars))
                }
                OutputFormat::Text => print_stdout(&summary_text(
                    &dcf.summary,
                    node,
                    &out.display().to_string(),
                    elapsed,
                )),
            }
        }
        None => {
            print_stdout(&String::from_utf8_lossy(&dcf.bytes))?;
            eprint!("{}", summary_text(&dcf.summary, node, "stdout", elapsed));
            Ok(())
        }
    }
}

fn summary_text(summary: &DumpTally, node: u8, to: &str, elapsed: Duration) -> String {
    let mut out = format!(
        "node {node}: {} entries read into {to} in {:.1} s",
        summary.read,
        elapsed.as_secs_f64()
    );
    let _ = write!(
        out,
        "; {} aborted (recorded as comments), {} skipped",
        summary.aborted.len(),
        summary.skipped.len()
    );
    if !summary.not_representable.is_empty() {
        let _ = write!(
            out,
            ", {} without a CiA 306 notation (comments)",
            summary.not_representable.len()
        );
    }
    out.push('\n');
    for (entry, _, why) in &summary.aborted {
        let _ = writeln!(out, "  {entry}: {why}");
    }
    out
}

fn summary_json(
    summary: &DumpTally,
    node: u8,
    out: &Path,
    elapsed: Duration,
    sidecars: &[(PathBuf, Vec<u8>)],
) -> serde_json::Value {
    json!({
        "node": node,
        "file": out.display().to_string(),
        "read": summary.read,
        "aborted": summary.aborted.iter().map(|(entry, code, why)| json!({
            "entry": entry,
            "abort_code": format!("{code:08X}"),
            "message": why,
        })).collect::<Vec<_>>(),
        "skipped": summary.skipped.iter().map(|(entry, why)| json!({"entry": entry, "reason": why})).collect::<Vec<_>>(),
        "not_representable": summary.not_representable.iter().map(|(entry, why)| json!({"entry": entry, "reason": why})).collect::<Vec<_>>(),
        "upload_files": sidecars.iter().map(|(file, data)| json!({"file": file.display().to_string(), "bytes": data.len()})).collect::<Vec<_>>(),
        "elapsed_ms": millis(elapsed),
    })
}
