"""SDO server speed, in one run: the device's protocol core on its own (criterion), then our simulated device against
python canopen's LocalNode as SDO servers, with the same client and the same workload.

Usage (via bench/run.sh, i.e. cargo xtask bench): bench/sdo_server.py [--quick] [--skip-criterion]

1. `cargo bench -p canopener-device --bench sdo_server`: a booted `Device` fed request frames directly (no bus, no
   clock); frames handled per second of CPU time, requests plus responses. Skipped with --skip-criterion.
2. For each run: a fresh `canopener bus serve` hub on a free port with both servers on it, each on a bus of its
   own at node 34 (`canopener sim EDS`, and bench/sdo_local_node.py, a python canopen LocalNode from the same EDS),
   and one client process, bench/sdo_workload.py (python canopen RemoteNodes), that interleaves them transfer by
   transfer (see its doc for the workload and how each transfer is verified). On this shared 2-core VM a round
   trip costs about 0.1 ms more while the machine is otherwise idle (halted vCPUs are slow to wake) than while
   other work keeps it busy, so separate runs per server differed by up to 3x from one minute to the next;
   interleaved, both servers see the same moments. Which server comes first alternates within and across runs.
   Both python processes set TCP_NODELAY (python-can's `tcp_tune=True`), as canopener's side does; one extra run
   with python-can's default socket (Nagle's algorithm on) shows what that costs.
Each figure is the median of RUNS runs (3, or 1 with --quick), with min-max over the runs.
The physical limits at 1 Mbit/s assume zero turnaround time: 125-bit SDO frames as in BENCHMARKS.md (the interop
notes' typical SDO frame), and the exact lengths of the very frames of each transfer that the criterion bench
prints (`canopener_can::bits`).

EDS: CANopenNode-style `base.eds` of gocanopen in the corpus (corpus/eds, vendored): it has an UNSIGNED32 (2007h) and a DOMAIN (200Fh) that are writable, which both servers hold.
Results: bench-results/sdo_server.json and bench-results/sdo_server.md.
"""

import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import corpus_eds, machine, transfer_stats  # noqa: E402  (shared with the other bench scripts)

ROOT = Path(__file__).resolve().parent.parent
BIN = ROOT / "target/release/canopener"
OUT_DIR = ROOT / "bench-results"
PY = sys.executable
QUICK = "--quick" in sys.argv
SKIP_CRITERION = "--skip-criterion" in sys.argv
RUNS = 1 if QUICK else 3
EXPEDITED_ROUNDS = 300 if QUICK else 1000
LARGE_ROUNDS = 5 if QUICK else 20
NODE_ID = 0x22
LARGE = 889
SERVERS = ["canopener", "python"]
SERVER_NAMES = {"canopener": "canopener sim", "python": "python canopen LocalNode"}
EXPEDITED = ["expedited_upload", "expedited_download"]
BULK = ["segmented_download", "segmented_upload", "block_download", "block_upload"]
LABELS = {
    "expedited_upload": "expedited upload 1018h:01",
    "expedited_download": "expedited download UNSIGNED32 2007h",
    "segmented_download": "segmented download, 889 bytes",
    "segmented_upload": "segmented upload, 889 bytes",
    "block_download": "block download, 889 bytes",
    "block_upload": "block upload, 889 bytes",
}
# The criterion benchmark of each transfer kind (bench function names in crates/canopener-device/benches).
CRITERION = {
    "expedited_upload": "expedited_upload_1018h01",
    "expedited_download": "expedited_download_u32",
    "segmented_download": "segmented_download_889",
    "segmented_upload": "segmented_upload_889",
    "block_download": "block_download_889",
    "block_upload": "block_upload_889",
}
# Frames of each transfer (CiA 301 §7.2.4): expedited 2; segmented 2 + 2 x 127; block download initiate 2 +
# 127 segments + 1 ack + end 2; block upload the same plus the "start upload" frame.
FRAMES = {"expedited_upload": 2, "expedited_download": 2, "segmented_download": 256, "segmented_upload": 256,
          "block_download": 132, "block_upload": 133}
TYPICAL_SDO_FRAME_BITS = 125
BITRATE = 1_000_000


def log(text):
    print(text, file=sys.stderr, flush=True)


# --- 1. the protocol core under criterion -------------------------------------------------------------------------

def criterion_target_dir():
    return Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "criterion"


def run_criterion():
    cmd = ["cargo", "bench", "--locked", "-p", "canopener-device", "--bench", "sdo_server", "--", "--noplot"]
    if QUICK:
        cmd += ["--warm-up-time", "1", "--measurement-time", "2"]
    log("criterion: " + " ".join(cmd))
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        # A failed verification inside the bench lands here: report it, never a number.
        return {"error": (done.stderr.strip().splitlines() or ["cargo bench failed"])[-20:]}
    wire = {}
    for match in re.finditer(r"^wire (\S+): (\d+) frames, (\d+) bits$", done.stderr, re.MULTILINE):
        wire[match.group(1)] = {"frames": int(match.group(2)), "bits": int(match.group(3))}
    results = {}
    for kind, name in CRITERION.items():
        estimates = json.loads((criterion_target_dir() / "sdo_server" / name / "new/estimates.json").read_text())
        # Criterion reports the slope of its linear sampling when it has one, otherwise the mean.
        estimate = estimates.get("slope") or estimates["mean"]
        frames = wire.get(name, {}).get("frames", FRAMES[kind])
        point = estimate["point_estimate"]
        low, high = estimate["confidence_interval"]["lower_bound"], estimate["confidence_interval"]["upper_bound"]
        results[kind] = {"bench": f"sdo_server/{name}", "frames": frames, "transfer_ns": point,
                         "transfer_ns_ci": [low, high], "frames_per_s": frames / point * 1e9,
                         "frames_per_s_ci": [frames / high * 1e9, frames / low * 1e9],
                         "wire_bits": wire.get(name, {}).get("bits")}
    return {"results": results}


# --- 2. the two servers on a hub, one client ---------------------------------------------------------------------

class Hub:
    def __init__(self):
        self.proc = subprocess.Popen([BIN, "bus", "serve", "--listen", "127.0.0.1:0"], stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL, text=True)
        first = self.proc.stdout.readline()
        self.port = int(first.rsplit(":", 1)[1])

    def close(self):
        self.proc.terminate()
        self.proc.wait(10)


def json_line(proc, timeout=600):
    deadline = time.time() + timeout
    while time.time() < deadline:
        line = proc.stdout.readline()
        if not line:
            raise RuntimeError(f"{proc.args} ended: {proc.stderr.read() if proc.stderr else ''}")
        try:
            return json.loads(line)
        except ValueError:
            continue
    raise RuntimeError(f"timeout waiting for {proc.args}")


def start_server(server, hub, channel, eds, logfile, socket_mode):
    if server == "canopener":
        # The simulator logs every SDO download on stderr; a file keeps a full pipe from stalling it.
        return subprocess.Popen([BIN, "sim", eds, "--bus", f"socketcand://127.0.0.1:{hub.port}/{channel}",
                                 "--node-id", str(NODE_ID)], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=logfile)
    proc = subprocess.Popen([PY, "-u", ROOT / "bench/sdo_local_node.py", "127.0.0.1", str(hub.port), channel,
                             str(NODE_ID), eds, socket_mode], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=logfile, text=True)
    if not json_line(proc, 60).get("ready"):
        raise RuntimeError("sdo_local_node.py did not get ready")
    return proc


def stop_server(server, proc):
    if server == "canopener":
        proc.terminate()
    else:
        proc.stdin.close()
    try:
        proc.wait(20)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def one_run(eds, order, socket_mode="tune"):
    """Both servers on one fresh hub, each on a bus of its own, and one client interleaving them; returns the
    client's summary per server."""
    hub = Hub()
    channels = {server: f"can{idx}" for idx, server in enumerate(order)}
    servers = {}
    with tempfile.TemporaryFile(mode="w+") as server_log:
        try:
            for server in order:
                servers[server] = start_server(server, hub, channels[server], eds, server_log, socket_mode)
            client = subprocess.run([PY, "-u", ROOT / "bench/sdo_workload.py", "127.0.0.1", str(hub.port),
                                     str(NODE_ID), eds, str(EXPEDITED_ROUNDS), str(LARGE_ROUNDS), socket_mode,
                                     *channels.values()], capture_output=True, text=True, timeout=1800)
        finally:
            for server, proc in servers.items():
                stop_server(server, proc)
            hub.close()
        server_log.seek(0)
        tail = server_log.read().strip().splitlines()[-5:]
    lines = [line for line in client.stdout.splitlines() if line.startswith("{")]
    if not lines:
        raise RuntimeError(f"sdo_workload.py printed nothing: {client.stderr[-2000:]}")
    raw = json.loads(lines[-1])
    if not raw["requests_answered"]:
        raise RuntimeError(f"a server never answered; the servers' last log lines: {tail}")
    return {server: summarize(raw["results"][channel]) for server, channel in channels.items()}


def summarize(results):
    return {kind: transfer_stats(result, kind in EXPEDITED, LARGE) for kind, result in results.items()}


def spread(runs, server, kind, key):
    values = [run[server][kind][key] for run in runs if key in run[server].get(kind, {})]
    if not values:
        return None
    return {"median": statistics.median(values), "min": min(values), "max": max(values), "runs": len(values)}


def limits(criterion):
    """Wire time and the rate it allows at 1 Mbit/s with zero turnaround: 125-bit frames, and the exact frames."""
    out = {}
    for kind, frames in FRAMES.items():
        typical_s = frames * TYPICAL_SDO_FRAME_BITS / BITRATE
        entry = {"frames": frames, "typical_wire_ms": typical_s * 1e3}
        bits = (criterion or {}).get(kind, {}).get("wire_bits")
        if bits:
            entry["exact_bits"] = bits
            entry["exact_wire_ms"] = bits / BITRATE * 1e3
        for suffix, seconds in [("typical", typical_s), ("exact", bits / BITRATE if bits else None)]:
            if seconds is None:
                continue
            if kind in EXPEDITED:
                entry[f"{suffix}_transfers_per_s"] = 1 / seconds
            else:
                entry[f"{suffix}_kB_per_s"] = LARGE / seconds / 1e3
        out[kind] = entry
    return out


# --- the report -------------------------------------------------------------------------------------------------

def fmt(value, digits=0):
    if value is None:
        return "–"
    return f"{value:,.{digits}f}".replace(",", " ")


def fmt_spread(entry, digits):
    if entry is None:
        return None
    text = fmt(entry["median"], digits)
    if entry["runs"] > 1:
        text += f" ({fmt(entry['min'], digits)}–{fmt(entry['max'], digits)})"
    return text


def failures(runs, server, kind):
    errors = [run[server][kind]["error"] for run in runs if run[server][kind]["error"]]
    failed = sum(run[server][kind]["failed"] for run in runs)
    ok = sum(run[server][kind]["ok"] for run in runs)
    return ok, failed, errors


def cell(runs, server, kind, key, digits, unit=""):
    ok, failed, errors = failures(runs, server, kind)
    if server == "python" and kind.startswith("block") and not ok:
        if key == "median_ms":
            return "n/a"
        return "n/a (python LocalNode has no block server: " + (errors[0] if errors else "failed") + ")"
    text = fmt_spread(spread(runs, server, kind, key), digits)
    if text and unit:
        text += " " + unit
    if failed:
        text = (text + " " if text else "") + f"**{failed} failed**: {errors[0]}"
    return text or "–"


def markdown(report):
    m = report["machine"]
    lines = [f"One run of `bench/sdo_server.py` on {m['date']}: {m['cpu']}, {m['cores']} cores, load average "
             f"{m['load_average_1min']} before and {m['load_average_after']} after the run; python {m['python']}, "
             f"python-can {m['python_can']}, canopen {m['canopen']}; {m['rustc']}. EDS: gocanopen's `base.eds` "
             f"(corpus), node {NODE_ID:#04x}."]
    criterion = report.get("criterion", {})
    if "results" in criterion:
        lines += ["", "**The device's protocol core** (criterion, "
                  "`cargo bench -p canopener-device --bench sdo_server`): a booted `Device` fed the request frames "
                  "directly, every response checked before timing; frames = requests fed + responses drained, i.e. "
                  "the transfer's frames on the wire.", "",
                  "| transfer | frames | CPU time per transfer | frames/s handled | "
                  "wire time at 1 Mbit/s (exact frames) | × faster than the wire |", "|---|---:|---:|---:|---:|---:|"]
        for kind in EXPEDITED + BULK:
            r = criterion["results"][kind]
            wire_ms = r["wire_bits"] / BITRATE * 1e3 if r["wire_bits"] else None
            lo, hi = r["frames_per_s_ci"]
            lines.append(f"| {LABELS[kind]} | {r['frames']} | {fmt(r['transfer_ns'] / 1e3, 2)} µs | "
                         f"**{fmt(r['frames_per_s'] / 1e6, 2)} M** ({fmt(lo / 1e6, 2)}–{fmt(hi / 1e6, 2)} M) | "
                         f"{fmt(wire_ms, 3)} ms ({r['wire_bits']} bits) | "
                         f"{fmt(wire_ms * 1e6 / r['transfer_ns'] if wire_ms else None)}× |")
    elif criterion:
        lines += ["", f"**The device's protocol core**: cargo bench FAILED: {' / '.join(criterion['error'])}"]
    runs = report["runs"]
    lim = report["limits"]
    lines += ["", "**Our simulated device against python canopen's LocalNode as SDO server**: the same python "
              "canopen RemoteNode client in its own process, through a `canopener bus serve` hub, "
              f"{EXPEDITED_ROUNDS} expedited and {LARGE_ROUNDS} large transfers of each kind per run, every "
              f"transfer's data verified; median of {len(runs)} run(s) (min–max). kB = 1000 bytes.", "",
              f"| transfer | {SERVER_NAMES['canopener']} | {SERVER_NAMES['python']} | ratio ours/python | "
              "physical limit at 1 Mbit/s (125-bit frames; exact frames) |", "|---|---|---|---:|---|"]

    def ratio(kind, key):
        ours, theirs = spread(runs, "canopener", kind, key), spread(runs, "python", kind, key)
        if not ours or not theirs:
            return "–"
        return f"**{ours['median'] / theirs['median']:.2f}×**"

    for kind in EXPEDITED:
        limit = lim[kind]
        exact = f"; {fmt(limit['exact_transfers_per_s'])}/s" if "exact_transfers_per_s" in limit else ""
        lines.append(f"| {LABELS[kind]}, median latency | {cell(runs, 'canopener', kind, 'median_ms', 3, 'ms')} | "
                     f"{cell(runs, 'python', kind, 'median_ms', 3, 'ms')} | | "
                     f"{fmt(limit['typical_wire_ms'], 3)} ms wire time |")
        lines.append(f"| … transfers/s | {cell(runs, 'canopener', kind, 'transfers_per_s', 0)} | "
                     f"{cell(runs, 'python', kind, 'transfers_per_s', 0)} | {ratio(kind, 'transfers_per_s')} | "
                     f"≈ {fmt(limit['typical_transfers_per_s'])}/s{exact} |")
    for kind in BULK:
        limit = lim[kind]
        exact = (f"; {fmt(limit['exact_wire_ms'], 1)} ms = {fmt(limit['exact_kB_per_s'], 1)} kB/s"
                 if "exact_wire_ms" in limit else "")
        lines.append(f"| {LABELS[kind]}, kB/s | {cell(runs, 'canopener', kind, 'kB_per_s', 1)} | "
                     f"{cell(runs, 'python', kind, 'kB_per_s', 1)} | {ratio(kind, 'kB_per_s')} | "
                     f"{fmt(limit['typical_wire_ms'], 1)} ms = {fmt(limit['typical_kB_per_s'], 1)} kB/s{exact} |")
        lines.append(f"| … median time | {cell(runs, 'canopener', kind, 'median_ms', 2, 'ms')} | "
                     f"{cell(runs, 'python', kind, 'median_ms', 2, 'ms')} | | {limit['frames']} frames |")
    lines += ["", "Fastest single transfer over all runs (ms).", "",
              f"| transfer | {SERVER_NAMES['canopener']} | {SERVER_NAMES['python']} | ratio python/ours (time) |",
              "|---|---:|---:|---:|"]
    for kind in EXPEDITED + BULK:
        best = [min((run[server][kind]["min_ms"] for run in runs if "min_ms" in run[server][kind]), default=None)
                for server in SERVERS]
        quotient = f"{best[1] / best[0]:.2f}×" if None not in best else "–"
        lines.append(f"| {LABELS[kind]} | {fmt(best[0], 3)} | {fmt(best[1], 3) if best[1] is not None else 'n/a'} | "
                     f"{quotient} |")
    default = report.get("default_socket")
    if default:
        lines += ["", "With python-can's default socket in the python processes (no `tcp_tune`: Nagle's algorithm on, "
                  "delayed ACKs), one run, median ms:", "",
                  f"| transfer | {SERVER_NAMES['canopener']} | {SERVER_NAMES['python']} |", "|---|---:|---:|"]
        for kind in EXPEDITED + BULK:
            row = [fmt(default[server][kind].get("median_ms"), 3 if kind in EXPEDITED else 2)
                   if default[server][kind]["ok"] else "n/a" for server in SERVERS]
            lines.append(f"| {LABELS[kind]} | {row[0]} | {row[1]} |")
    every_run = runs + ([default] if default else [])
    bad = [(server, kind, r["error"]) for run in every_run for server in SERVERS for kind, r in run[server].items()
           if r["error"] and not (server == "python" and kind.startswith("block"))]
    lines += ["", "Every transfer was verified: uploads against the expected bytes, each expedited and block download "
              "read back untimed, each segmented download by the segmented upload that follows it. " +
              ("All were correct." if not bad else "FAILURES: " + "; ".join(f"{s} {k}: {e}" for s, k, e in bad)),
              "", "Reading: the client (python canopen and python-can in one process) and the hub are the same in both "
              "columns, so their cost is in both and the ratios understate the difference between the servers. "
              + block_note(every_run) +
              "The physical limits assume zero turnaround time; the criterion table's frames are "
              "requests plus responses, and the core's cost is per received frame (the block upload receives 4 of "
              "its 133 frames)."]
    return "\n".join(lines) + "\n"


def block_note(runs):
    """What the python server did with block transfers in these runs, from their recorded errors (nothing is said
    about a run that did not show it)."""
    errors = sorted({run["python"][kind]["error"] for run in runs for kind in run["python"]
                     if kind.startswith("block") and run["python"][kind]["error"]})
    if not errors:
        return ""
    return ("python canopen's LocalNode did not complete the block transfers (no n/a above is a slow result); "
            "the client reported: " + "; ".join(str(e) for e in errors) + ". ")


def main():
    eds = str(corpus_eds("samsamfire__gocanopen__pkg__od__base.eds", "sdo_server.py"))
    if not BIN.is_file():
        sys.exit(f"sdo_server.py: {BIN} is missing; run `cargo build --release -p canopener-cli` (bench/run.sh does)")
    report = {"machine": machine(), "runs_per_figure": RUNS, "node_id": NODE_ID, "eds": eds,
              "expedited_rounds": EXPEDITED_ROUNDS, "large_rounds": LARGE_ROUNDS, "large_bytes": LARGE}
    if not SKIP_CRITERION:
        report["criterion"] = run_criterion()
    runs = []
    for run_idx in range(RUNS):
        # Which server the client meets first in a round (and which bus it gets) alternates from run to run.
        order = SERVERS if run_idx % 2 == 0 else SERVERS[::-1]
        log(f"run {run_idx + 1}/{RUNS}: {' and '.join(SERVER_NAMES[s] for s in order)}, interleaved")
        runs.append(one_run(eds, order))
    report["runs"] = runs
    log("one run with python-can's default socket")
    report["default_socket"] = one_run(eds, SERVERS, "default")
    report["limits"] = limits(report.get("criterion", {}).get("results"))
    report["machine"]["load_average_after"] = round(os.getloadavg()[0], 2)
    OUT_DIR.mkdir(exist_ok=True)
    (OUT_DIR / "sdo_server.json").write_text(json.dumps(report, indent=1))
    text = markdown(report)
    (OUT_DIR / "sdo_server.md").write_text(text)
    log(f"wrote {OUT_DIR / 'sdo_server.json'} and {OUT_DIR / 'sdo_server.md'}")
    print(text)


if __name__ == "__main__":
    main()
