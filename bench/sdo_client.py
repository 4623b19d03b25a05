"""SDO client speed, in one run: our SdoClient against the wire on the bit-accurate virtual bus, then our client against
python canopen's client over the hub, with the same server and the same workload.

Usage (via bench/run.sh, i.e. cargo xtask bench): bench/sdo_client.py [--quick]
        bench/sdo_client.py client HOST PORT CHANNEL NODE_ID EDS KIND ROUNDS FIRST_ROUND   (the python client)

1. `sdo_throughput virtual` (crates/canopener-master/examples): canopener_master's SdoClient and a canopener_device
   Device on a 1 Mbit/s canopener_bus_engine BusEngine, on virtual time with zero processing time, so every figure is protocol
   efficiency against the wire: frames per transfer, exact stuffed bits, wire utilisation, and the rate as a share of
   the interop notes' §4 limits (1 Mbit/s, zero turnaround). The virtual figures are the same in every run (the run is
   deterministic; the script checks that); the wall-clock speed of the simulation is the median over the runs.
2. For each run: a fresh `canopener bus serve` hub on a free port and one `canopener sim` server on it (gocanopen's
   `base.eds` from the corpus, node 34 = 22h, as bench/sdo_server.py uses), then our client (`sdo_throughput hub`)
   and python canopen's RemoteNode client (this script in `client` mode) take turns on the same bus, each turn a
   fresh process that connects, runs 1/CHUNKS of one kind's rounds (10 turns each) and disconnects, so only one
   client is ever connected and neither pays for the other's traffic. Which goes first alternates from chunk to
   chunk: on this shared 2-core VM one client's whole batch ran up to 5x slower than a batch a second later, and
   short alternating turns let both clients see the same moments. The ratio is taken per run (paired) and then the
   median over the runs.
   Workload per kind, every transfer verified untimed: expedited upload of 1018h:01 (against the EDS value),
   expedited download of 4 bytes to the UNSIGNED32 2007h (read back), 889 bytes segmented and block (blksize 127,
   CRC requested) to and from the DOMAIN 200Fh (each download read back, each upload preceded by a segmented
   download of fresh bytes). Both clients set TCP_NODELAY (python-can's `tcp_tune=True`) and wait 1 s per answer.
Each figure is the median of RUNS runs (3, or 1 with --quick), with min-max over the runs.
Results: bench-results/sdo_client.json and bench-results/sdo_client.md.
"""

import json
import os
import statistics
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import corpus_eds, machine, transfer_stats  # noqa: E402  (shared with the other bench scripts)

ROOT = Path(__file__).resolve().parent.parent
BIN = ROOT / "target/release/canopener"
EXAMPLE = ROOT / "target/release/examples/sdo_throughput"
OUT_DIR = ROOT / "bench-results"
PY = sys.executable
QUICK = "--quick" in sys.argv
RUNS = 1 if QUICK else 3
EXPEDITED_ROUNDS = 300 if QUICK else 1000
LARGE_ROUNDS = 5 if QUICK else 50
CHUNKS = 10
NODE_ID = 0x22
LARGE = 889
IDENTITY = (0x1018, 1)
U32 = (0x2007, 0)
DOMAIN = (0x200F, 0)
CLIENTS = ["canopener", "python"]
CLIENT_NAMES = {"canopener": "canopener SdoClient", "python": "python canopen SdoClient"}
EXPEDITED = ["expedited_upload", "expedited_download"]
BULK = ["segmented_download", "segmented_upload", "block_download", "block_upload"]
KINDS = EXPEDITED + BULK
LABELS = {
    "expedited_upload": "expedited upload 1018h:01",
    "expedited_download": "expedited download UNSIGNED32 2007h",
    "segmented_download": "segmented download, 889 bytes",
    "segmented_upload": "segmented upload, 889 bytes",
    "block_download": "block download, 889 bytes",
    "block_upload": "block upload, 889 bytes",
}
READY_TIMEOUT_S = 15.0


def log(text):
    print(text, file=sys.stderr, flush=True)


# --- the python client (client mode, its own process) -------------------------------------------------------------

def payload(round_idx):
    """The bytes of round `round_idx`, the same as the Rust client's: printable, different every round."""
    return bytes(0x41 + (i + round_idx) % 26 for i in range(LARGE))


def word(round_idx):
    return struct.pack("<I", (0x9E3779B9 * (round_idx + 1)) & 0xFFFFFFFF)


def python_client(host, port, channel, node_id, eds, kind, rounds, first_round):
    import logging

    import canopen
    from canopen.sdo.exceptions import SdoAbortedError

    logging.getLogger("canopen").setLevel(logging.CRITICAL)
    logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)
    network = canopen.Network()
    network.connect(interface="socketcand", host=host, port=port, channel=channel, tcp_tune=True)
    node = canopen.RemoteNode(node_id, eds)
    network.add_node(node)
    sdo = node.sdo
    sdo.RESPONSE_TIMEOUT = 1.0  # as canopener's SdoClient (DEFAULT_TIMEOUT)
    identity_var = node.object_dictionary.get_variable(*IDENTITY)
    identity = identity_var.encode_raw(identity_var.value if identity_var.value is not None else identity_var.default)

    def describe(exc):
        if isinstance(exc, SdoAbortedError):
            return f"SdoAbortedError 0x{exc.code:08X}"
        return f"{type(exc).__name__}: {exc}"

    def check(got, expected):
        if bytes(got) != expected:
            raise ValueError(f"wrong data: {len(got)} bytes, expected {len(expected)}")

    def block_download(data):
        with sdo.open(*DOMAIN, mode="wb", size=len(data), block_transfer=True) as stream:
            stream.write(data)

    def block_upload():
        with sdo.open(*DOMAIN, mode="rb", block_transfer=True) as stream:
            return stream.read()

    def one_round(round_idx):
        """Returns the seconds the timed transfer took; setup and check are untimed."""
        if kind == "expedited_upload":
            start = time.perf_counter()
            got = sdo.upload(*IDENTITY)
            took = time.perf_counter() - start
            check(got, identity)
        elif kind == "expedited_download":
            value = word(round_idx)
            start = time.perf_counter()
            sdo.download(*U32, value)
            took = time.perf_counter() - start
            check(sdo.upload(*U32), value)
        elif kind in ("segmented_download", "block_download"):
            data = payload(round_idx)
            start = time.perf_counter()
            if kind == "block_download":
                block_download(data)
            else:
                sdo.download(*DOMAIN, data)
            took = time.perf_counter() - start
            check(sdo.upload(*DOMAIN), data)
        else:
            data = payload(round_idx)
            sdo.download(*DOMAIN, data)
            start = time.perf_counter()
            got = block_upload() if kind == "block_upload" else sdo.upload(*DOMAIN)
            took = time.perf_counter() - start
            check(got, data)
        return took

    result = {"client": "python", "kind": kind, "ok": 0, "failed": 0, "error": None, "times_s": []}
    deadline = time.monotonic() + READY_TIMEOUT_S
    while True:
        try:
            sdo.upload(*IDENTITY)
            break
        except Exception as exc:  # not connected or not booted yet
            if time.monotonic() >= deadline:
                result["error"] = f"the server did not answer within {READY_TIMEOUT_S} s: {describe(exc)}"
                result["failed"] = 1
                rounds = 0
                break
            time.sleep(0.05)
    for round_idx in range(first_round, first_round + rounds):
        try:
            result["times_s"].append(one_round(round_idx))
        except Exception as exc:  # every failure is a result to report; nothing wrong is timed as a success
            result["error"] = describe(exc)
            result["failed"] = 1
            break
    result["ok"] = len(result["times_s"])
    network.disconnect()
    print(json.dumps(result), flush=True)
    return 0


# --- the driver ---------------------------------------------------------------------------------------------------

def build_example():
    cmd = ["cargo", "build", "--release", "--locked", "-p", "canopener-master", "--example", "sdo_throughput"]
    log("build: " + " ".join(cmd))
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit("sdo_client.py: building the example failed:\n" + done.stderr[-3000:])


def run_virtual():
    runs = []
    for _ in range(RUNS):
        done = subprocess.run([EXAMPLE, "virtual"], capture_output=True, text=True, timeout=600)
        if done.returncode != 0:
            # A failed verification inside the simulation lands here: report it, never a number.
            return {"error": done.stderr.strip()[-2000:]}
        runs.append(json.loads(done.stdout))
    first = runs[0]
    # Virtual time is deterministic: everything but the wall-clock figures must repeat exactly.
    wall_keys = {"wall_s", "frames_per_wall_s"}
    for run in runs[1:]:
        for a, b in zip(first["scenarios"], run["scenarios"]):
            if {k: v for k, v in a.items() if k not in wall_keys} != {k: v for k, v in b.items() if k not in wall_keys}:
                return {"error": f"virtual runs differ in {a['kind']} of {a['bytes']} bytes"}
    for idx, scenario in enumerate(first["scenarios"]):
        speeds = [run["scenarios"][idx]["frames_per_wall_s"] for run in runs]
        scenario["frames_per_wall_s"] = statistics.median(speeds)
        scenario["frames_per_wall_s_range"] = [min(speeds), max(speeds)]
    totals = [run["total"]["frames_per_wall_s"] for run in runs]
    first["total"]["frames_per_wall_s"] = statistics.median(totals)
    first["total"]["frames_per_wall_s_range"] = [min(totals), max(totals)]
    first["total"]["wall_s"] = statistics.median(run["total"]["wall_s"] for run in runs)
    first["runs"] = len(runs)
    return first


class Hub:
    def __init__(self):
        self.proc = subprocess.Popen([BIN, "bus", "serve", "--listen", "127.0.0.1:0"], stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL, text=True)
        first = self.proc.stdout.readline()
        try:
            self.port = int(first.rsplit(":", 1)[1])
        except (IndexError, ValueError):
            self.close()
            raise RuntimeError(f"unexpected first line from the hub: {first!r}")

    def close(self):
        self.proc.terminate()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def run_client(client, hub, channel, eds, kind, rounds, first_round):
    if client == "canopener":
        cmd = [EXAMPLE, "hub", f"socketcand://127.0.0.1:{hub.port}/{channel}", str(NODE_ID), eds, kind, str(rounds),
               str(first_round)]
    else:
        cmd = [PY, "-u", Path(__file__).resolve(), "client", "127.0.0.1", str(hub.port), channel, str(NODE_ID), eds,
               kind, str(rounds), str(first_round)]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    except subprocess.TimeoutExpired:
        return {"client": client, "kind": kind, "ok": 0, "failed": 1, "error": "client timed out", "times_s": []}
    try:
        return json.loads(done.stdout)
    except ValueError:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        return {"client": client, "kind": kind, "ok": 0, "failed": 1, "error": tail, "times_s": []}


def one_run(eds, run_idx):
    """One hub, one simulated server; the two clients take turns chunk by chunk. Returns {client: {kind: summary}}."""
    hub = Hub()
    raw = {client: {} for client in CLIENTS}
    with tempfile.TemporaryFile(mode="w+") as server_log:
        # The simulator logs every SDO download on stderr; a file keeps a full pipe from stalling it.
        server = subprocess.Popen([BIN, "sim", eds, "--bus", f"socketcand://127.0.0.1:{hub.port}/can0",
                                   "--node-id", str(NODE_ID)], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                  stderr=server_log)
        try:
            for kind_idx, kind in enumerate(KINDS):
                rounds = EXPEDITED_ROUNDS if kind in EXPEDITED else LARGE_ROUNDS
                log(f"  {kind}: {rounds} transfers per client in {CHUNKS} turns each")
                for chunk, (first, count) in enumerate(chunks(rounds)):
                    order = CLIENTS if (run_idx + kind_idx + chunk) % 2 == 0 else CLIENTS[::-1]
                    for client in order:
                        merge(raw[client], kind, run_client(client, hub, "can0", eds, kind, count, first))
        finally:
            server.terminate()
            try:
                server.wait(20)
            except subprocess.TimeoutExpired:
                server.kill()
                server.wait()
            hub.close()
    return {client: {kind: summarize(kind, result) for kind, result in kinds.items()} for client, kinds in raw.items()}


def chunks(rounds):
    """(first round, rounds) of each turn: CHUNKS turns as equal as possible, none empty."""
    n_chunks = min(CHUNKS, rounds)
    bounds = [rounds * idx // n_chunks for idx in range(n_chunks + 1)]
    return [(lo, hi - lo) for lo, hi in zip(bounds, bounds[1:])]


def merge(results, kind, chunk):
    """Adds one turn's results; after a failure the kind stays failed and later turns only add to the count."""
    entry = results.setdefault(kind, {"ok": 0, "failed": 0, "error": None, "times_s": []})
    entry["ok"] += chunk["ok"]
    entry["failed"] += chunk["failed"]
    entry["error"] = entry["error"] or chunk["error"]
    entry["times_s"] += chunk["times_s"]


def summarize(kind, raw):
    return transfer_stats(raw, kind in EXPEDITED, LARGE)


def spread(runs, client, kind, key):
    values = [run[client][kind][key] for run in runs if key in run[client].get(kind, {})]
    if not values:
        return None
    return {"median": statistics.median(values), "min": min(values), "max": max(values), "runs": len(values)}


# --- the report -------------------------------------------------------------------------------------------------

def fmt(value, digits=0):
    if value is None:
        return "–"
    return f"{value:,.{digits}f}".replace(",", " ")


def fmt_spread(entry, digits, scale=1.0):
    if entry is None:
        return "–"
    text = fmt(entry["median"] * scale, digits)
    if entry["runs"] > 1:
        text += f" ({fmt(entry['min'] * scale, digits)}–{fmt(entry['max'] * scale, digits)})"
    return text


def virtual_markdown(virtual):
    if "error" in virtual:
        return ["**SdoClient on the bit-accurate virtual bus**: FAILED: " + virtual["error"]]
    lines = ["**SdoClient on the bit-accurate virtual bus** (`cargo run --release -p canopener-master --example "
             "sdo_throughput -- virtual`): canopener_master's `SdoClient` and a canopener_device `Device` (checker "
             "fixture `base.eds` at node 22h plus a DOMAIN and an UNSIGNED32) on a 1 Mbit/s `canopener_bus_engine::BusEngine`, "
             "virtual time, zero processing time on both sides, blksize 127 with CRC. Every frame is arbitrated and "
             "lasts its exact stuffed length. Reference limits: interop notes §4 at 1 Mbit/s, zero turnaround, "
             "typical (best–worst) = 125 (111–135)-bit frames; the segmented and block references are "
             "long-transfer rates. Exact-frame limit: the same frames back to back on the wire.", "",
             "| transfer | frames per transfer (= CiA 301 count) | bits/frame | time per transfer | rate | "
             "reference limit, typical (best–worst) | % of typical | % of exact-frame limit | wire utilisation | "
             "simulated frames/s (wall) |",
             "|---|---:|---:|---:|---:|---|---:|---:|---:|---:|"]
    for s in virtual["scenarios"]:
        expedited = s["unit"] == "transfers/s"
        rate = f"{fmt(s['measured'])} /s" if expedited else f"{fmt(s['measured'] / 1e3, 2)} kB/s"
        ref = s["reference_limit"]
        if expedited:
            reference = f"{fmt(ref['typical'])} /s ({fmt(ref['best'])}–{fmt(ref['worst'])})"
        else:
            reference = (f"{fmt(ref['typical'] / 1e3, 2)} kB/s ({fmt(ref['best'] / 1e3, 2)}–"
                         f"{fmt(ref['worst'] / 1e3, 2)})")
        frames = fmt(s["frames_per_transfer"], 0)
        if round(s["frames_per_transfer"]) != s["expected_frames_per_transfer"]:
            frames += f" (expected {s['expected_frames_per_transfer']})"
        kind = s["kind"].replace("_", " ")
        label = kind if expedited else f"{kind}, {fmt(s['bytes'])} bytes"
        lines.append(f"| {label} | {frames} | {s['bits_per_frame']:.1f} | {fmt(s['ms_per_transfer'] * 1e3, 1)} µs | "
                     f"**{rate}** | {reference} | {s['pct_of_reference_typical']:.1f} % | "
                     f"{s['pct_of_exact_frames_limit']:.2f} % | {100 * s['wire_utilisation']:.2f} % | "
                     f"{fmt(s['frames_per_wall_s'] / 1e6, 2)} M |")
    total = virtual["total"]
    lo, hi = total["frames_per_wall_s_range"]
    lines += ["", f"The whole simulated workload ({fmt(total['frames'])} frames, {virtual['runs']} run(s)) took "
              f"{fmt(total['wall_s'] * 1e3, 1)} ms of wall-clock time: **{fmt(total['frames_per_wall_s'] / 1e6, 2)} M "
              f"frames/s** ({fmt(lo / 1e6, 2)}–{fmt(hi / 1e6, 2)} M) for the client, the device and the bus engine "
              "together on one core. Every transfer was verified (uploads against the value set in the device, "
              "downloads against the device's dictionary)."]
    return lines


def virtual_rate(virtual, kind):
    """The 889-byte (or expedited) rate the same kind reached on the 1 Mbit/s virtual bus, for the hub table."""
    for s in virtual.get("scenarios", []):
        if s["kind"] == kind and (kind in EXPEDITED or s["bytes"] == LARGE):
            return s
    return None


def hub_markdown(report):
    runs = report["runs"]
    virtual = report["virtual"]
    lines = ["**Our SdoClient against python canopen's SdoClient, real time over the hub**: one `canopener bus serve` "
             "hub and one `canopener sim` server (gocanopen's `base.eds`, node 22h) per run; our client "
             "(`sdo_throughput hub`, wall clock) and python canopen's `RemoteNode` take turns on the same bus, each "
             f"turn a fresh process that connects, runs 1/{CHUNKS} of one kind's transfers and disconnects (who goes "
             "first alternates from turn to turn); both with TCP_NODELAY and a 1 s answer timeout. "
             f"{EXPEDITED_ROUNDS} expedited and {LARGE_ROUNDS} large transfers per kind and client per run; "
             f"median of {len(runs)} run(s) (min–max); the ratio is taken per run, then the median (min–max) over "
             "the runs. kB = 1000 bytes. The hub does not pace frames to a "
             "bit rate, so both clients may beat a real bus; the last column is what our client reaches on the "
             "1 Mbit/s virtual bus above.", "",
             f"| transfer | {CLIENT_NAMES['canopener']} | {CLIENT_NAMES['python']} | ours vs python | "
             "1 Mbit/s wire (virtual bus) |", "|---|---|---|---:|---|"]

    def ratio(kind, key, invert=False):
        """ours/python per run (python/ours for times), then the median over the runs."""
        values = []
        for run in runs:
            ours, theirs = run["canopener"][kind].get(key), run["python"][kind].get(key)
            if ours and theirs:
                values.append(theirs / ours if invert else ours / theirs)
        if not values:
            return "–"
        value = statistics.median(values)
        text = f"**{value:.2f}×** faster" if value >= 1 else f"{1 / value:.2f}× slower"
        if len(values) > 1:
            text += f" ({min(values):.2f}–{max(values):.2f})"
        return text

    def cell(client, kind, key, digits, scale=1.0, unit=""):
        text = fmt_spread(spread(runs, client, kind, key), digits, scale)
        if unit and text != "–":
            text += " " + unit
        failed = [run[client][kind] for run in runs if run[client][kind]["failed"]]
        if failed:
            text += f" **{len(failed)} run(s) failed**: {failed[0]['error']}"
        return text

    for kind in EXPEDITED:
        wire = virtual_rate(virtual, kind)
        lines.append(f"| {LABELS[kind]}, median latency | {cell('canopener', kind, 'median_ms', 1, 1e3, 'µs')} | "
                     f"{cell('python', kind, 'median_ms', 1, 1e3, 'µs')} | {ratio(kind, 'median_ms', True)} | "
                     f"{fmt(wire['ms_per_transfer'] * 1e3, 1) + ' µs' if wire else '–'} |")
        lines.append(f"| … p99 latency | {cell('canopener', kind, 'p99_ms', 1, 1e3, 'µs')} | "
                     f"{cell('python', kind, 'p99_ms', 1, 1e3, 'µs')} | | |")
        lines.append(f"| … transfers/s | {cell('canopener', kind, 'transfers_per_s', 0)} | "
                     f"{cell('python', kind, 'transfers_per_s', 0)} | {ratio(kind, 'transfers_per_s')} | "
                     f"{fmt(wire['transfers_per_s']) + ' /s' if wire else '–'} |")
    for kind in BULK:
        wire = virtual_rate(virtual, kind)
        lines.append(f"| {LABELS[kind]}, kB/s | {cell('canopener', kind, 'kB_per_s', 1)} | "
                     f"{cell('python', kind, 'kB_per_s', 1)} | {ratio(kind, 'kB_per_s')} | "
                     f"{fmt(wire['measured'] / 1e3, 1) + ' kB/s' if wire else '–'} |")
        lines.append(f"| … median time | {cell('canopener', kind, 'median_ms', 2, 1.0, 'ms')} | "
                     f"{cell('python', kind, 'median_ms', 2, 1.0, 'ms')} | | "
                     f"{fmt(wire['ms_per_transfer'], 2) + ' ms' if wire else '–'} |")
    bad = [(client, kind, r["error"]) for run in runs for client in CLIENTS for kind, r in run[client].items()
           if r["error"]]
    lines += ["", "Every transfer was verified untimed: the expedited upload against the EDS value, each download read "
              "back with a normal upload, each upload preceded by a segmented download of bytes that differ from round "
              "to round. " + ("All were correct." if not bad else
                              "FAILURES: " + "; ".join(f"{c} {k}: {e}" for c, k, e in bad)),
              "", "Reading: the server, the hub and the loopback TCP hops are the same in both columns, so their cost "
              "is in both and the ratios understate the difference between the clients themselves."]
    return lines


def markdown(report):
    m = report["machine"]
    lines = [f"One run of `bench/sdo_client.py` on {m['date']}: {m['cpu']}, {m['cores']} cores, load average "
             f"{m['load_average_1min']} before and {m['load_average_after']} after the run; python {m['python']}, "
             f"python-can {m['python_can']}, canopen {m['canopen']}; {m['rustc']}.", ""]
    lines += virtual_markdown(report["virtual"])
    lines += [""] + hub_markdown(report)
    return "\n".join(lines) + "\n"


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "client":
        host, port, channel, node_id, eds, kind, rounds, first_round = sys.argv[2:10]
        return python_client(host, int(port), channel, int(node_id, 0), eds, kind, int(rounds), int(first_round))
    eds = str(corpus_eds("samsamfire__gocanopen__pkg__od__base.eds", "sdo_client.py"))
    if not BIN.is_file():
        sys.exit(f"sdo_client.py: {BIN} is missing; run `cargo build --release -p canopener-cli` (bench/run.sh does)")
    build_example()
    report = {"machine": machine(), "runs_per_figure": RUNS, "node_id": NODE_ID, "eds": eds,
              "expedited_rounds": EXPEDITED_ROUNDS, "large_rounds": LARGE_ROUNDS, "large_bytes": LARGE}
    log("virtual bus: sdo_throughput virtual")
    report["virtual"] = run_virtual()
    runs = []
    for run_idx in range(RUNS):
        log(f"run {run_idx + 1}/{RUNS}: both clients against one canopener sim over the hub")
        runs.append(one_run(eds, run_idx))
    report["runs"] = runs
    report["machine"]["load_average_after"] = round(os.getloadavg()[0], 2)
    OUT_DIR.mkdir(exist_ok=True)
    (OUT_DIR / "sdo_client.json").write_text(json.dumps(report, indent=1))
    text = markdown(report)
    (OUT_DIR / "sdo_client.md").write_text(text)
    log(f"wrote {OUT_DIR / 'sdo_client.json'} and {OUT_DIR / 'sdo_client.md'}")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
