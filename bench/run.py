"""The hub benchmarks of BENCHMARKS.md ("The hub against a Python hub", "How many saturated 1 Mbit/s buses one hub
carries", "python-can and python canopen through each hub"), in one go, with their tables.

Usage (via bench/run.sh, i.e. `cargo xtask bench`): bench/run.py [--quick]
Each figure is the median of RUNS runs (3, or 1 with --quick) with the fastest and slowest run as its range, unless
the table says otherwise (the bus-capacity rows and the reconnect row are one run each). Results:
bench-results/results.json (every run's raw output) and bench-results/hub.md (the tables, as BENCHMARKS.md has them).
"""

import json
import os
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import corpus_eds, machine  # noqa: E402  (shared with the other bench scripts)

ROOT = Path(__file__).resolve().parent.parent
BIN = ROOT / "target/release/canopener"
LOAD = ROOT / "target/release/examples/hub_load"
PEERS = ROOT / "crates/canopener-cli/tests/python"
EDS = corpus_eds("canopen-python__canopen__test__sample.eds", "run.py")
PY = sys.executable
# DLC-8 frames/s on a saturated 1 Mbit/s bus: 111-bit frames without stuff bits (canopener_can::bits).
SATURATED_DLC8 = 9009
# The bus-capacity test's pace: the 1 Mbit/s limit for 113-bit DLC-8 frames. The counter payloads hub_load sends
# are 121.4 bits on average (cargo run -p canopener-can --example can_limits), so each paced bus carries more
# frames than a real 1 Mbit/s bus could: a saturated bus at least.
BUS_RATE = 8849
QUICK = "--quick" in sys.argv
RUNS = 1 if QUICK else 3


def log(text):
    print(text, file=sys.stderr, flush=True)


def free_port():
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


class Hub:
    """`canopener bus serve` or the Python baseline hub, as a subprocess."""

    def __init__(self, kind):
        self.kind = kind
        if kind == "canopener":
            self.proc = subprocess.Popen([BIN, "bus", "serve", "--listen", "127.0.0.1:0"], stdout=subprocess.PIPE, text=True)
            first = self.proc.stdout.readline()
            self.port = int(first.rsplit(":", 1)[1])
        else:
            self.port = free_port()
            self.proc = subprocess.Popen([PY, ROOT / "bench/baseline_hub.py", str(self.port)], stdout=subprocess.PIPE, text=True)
            self.proc.stdout.readline()

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


def peer(script, *args):
    return subprocess.Popen([PY, "-u", PEERS / script, *map(str, args)], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def go(*procs):
    for proc in procs:
        assert json_line(proc)["ready"]
    for proc in procs:
        proc.stdin.write("go\n")
        proc.stdin.flush()


def hub_load(*args, hub=None):
    cmd = [LOAD] + (["--hub", f"127.0.0.1:{hub.port}"] if hub else []) + list(map(str, args))
    return json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout.strip().splitlines()[-1])


def median_of(fn, runs=RUNS):
    """`fn` run `runs` times: {"runs": [each run's result]}; the tables take median and range from spread()."""
    return {"runs": [fn() for _ in range(runs)]}


def spread(entry, key):
    """(median, min, max) of `key` over an entry's runs, or None when no run has it."""
    values = [run[key] for run in entry["runs"] if run.get(key) is not None]
    if not values:
        return None
    return statistics.median(values), min(values), max(values)


def num(value, digits=0):
    """A number with thin thousands separators, as BENCHMARKS.md writes them."""
    return f"{value:,.{digits}f}".replace(",", " ")


def cell(entry, key, digits=0, unit="", scale=1.0, bold=False):
    """`median (min–max)` of a key, scaled (1e-3 for k), or "–"."""
    got = spread(entry, key) if entry else None
    if got is None:
        return "–"
    median, low, high = (v * scale for v in got)
    text = f"{num(median, digits)}{unit}"
    if bold:
        text = f"**{text}**"
    if len(entry["runs"]) > 1:
        # Thousands keep their unit in the range, as in "5 052 k (5 031 k–5 073 k)".
        end = unit if unit.strip() == "k" else ""
        text += f" ({num(low, digits)}{end}–{num(high, digits)}{end})"
    return text


def ratio(ours, theirs, key, higher_is_better=True, bold=False):
    a, b = spread(ours, key) if ours else None, spread(theirs, key) if theirs else None
    if not a or not b or not a[0] or not b[0]:
        return "–"
    value = a[0] / b[0] if higher_is_better else b[0] / a[0]
    return f"**{value:.2f}×**" if bold else f"{value:.2f}×"


def markdown(r):
    """The hub tables of BENCHMARKS.md from one run's results; every number in them is computed here."""
    m = r["machine"]
    samples = lambda entry: spread(entry, "samples")[0] if spread(entry, "samples") else 0  # noqa: E731
    lines = [f"One run of `bench/run.py` on {m['date']}: {m['cpu']}, {m['cores']} cores, load average "
             f"{m['load_average_1min']} at the start; python {m['python']}, python-can {m['python_can']}, canopen "
             f"{m['canopen']}; {m['rustc']}. Each figure is the median of {r['runs']} run(s) (min–max) unless the "
             "row says otherwise.", "", "### Rust clients (socketcand over TCP loopback)", "",
             "| measurement | canopener hub | Python baseline hub | ratio |", "|---|---|---|---|"]
    k = 1e-3
    lines.append("| throughput, 2 clients (1 → 1), frames/s delivered | "
                 f"{cell(r['throughput_2'], 'delivered_per_second', 0, ' k', k, True)} | "
                 f"{cell(r['py_throughput_2'], 'delivered_per_second', 0, ' k', k)} | "
                 f"{ratio(r['throughput_2'], r['py_throughput_2'], 'delivered_per_second', bold=True)} |")
    lines.append("| throughput, 8 clients (1 → 7), deliveries/s | "
                 f"{cell(r['throughput_8'], 'delivered_per_second', 0, ' k', k, True)} | "
                 f"{cell(r['py_throughput_8'], 'delivered_per_second', 0, ' k', k)} | "
                 f"{ratio(r['throughput_8'], r['py_throughput_8'], 'delivered_per_second', bold=True)} |")
    lines.append("| throughput, 8 clients all sending (8 → 7 each), deliveries/s | "
                 f"{cell(r['throughput_8_all'], 'delivered_per_second', 0, ' k', k, True)} | – | – |")
    lines.append(f"| round trip (ping-pong; {num(samples(r['latency']))} and {num(samples(r['py_latency']))} samples), "
                 f"p50 | {cell(r['latency'], 'rtt_us_p50', 0, ' µs', bold=True)} | "
                 f"{cell(r['py_latency'], 'rtt_us_p50', 0, ' µs')} | "
                 f"{ratio(r['latency'], r['py_latency'], 'rtt_us_p50', higher_is_better=False)} |")
    for key, label in [("rtt_us_p90", "p90"), ("rtt_us_p99", "p99")]:
        lines.append(f"| round trip {label} | {cell(r['latency'], key, 0, ' µs')} | {cell(r['py_latency'], key, 0, ' µs')} "
                     f"| {ratio(r['latency'], r['py_latency'], key, higher_is_better=False)} |")
    lines.append(f"| round trips/s | {cell(r['latency'], 'round_trips_per_second', 0, '', 1, True)} | "
                 f"{cell(r['py_latency'], 'round_trips_per_second')} | "
                 f"{ratio(r['latency'], r['py_latency'], 'round_trips_per_second')} |")
    two = spread(r["throughput_2"], "delivered_per_second")
    if two:
        lines += ["", f"The hub's median delivery rate on two clients is **{num(two[0] / SATURATED_DLC8)}× the frame "
                  f"rate of a saturated 1 Mbit/s bus** ({num(SATURATED_DLC8)} DLC-8 frames/s)."]
    lines += ["", "### How many saturated 1 Mbit/s buses one hub carries", "",
              f"One run per bus count; each bus has one sender paced at {num(BUS_RATE)} DLC-8 frames/s and one "
              "receiver. \"Lag\" is how late a frame arrived compared with its send time.", "",
              "| buses | frames delivered / sent | delivered per bus, frames/s | mean lag | max lag | "
              "frames > 10 ms late | hub CPU (one core = 100 %) | load generator CPU-s / hub CPU-s |",
              "|---|---|---|---|---|---|---|---|"]
    for b in r["buses"]:
        late = b["frames_later_than_10ms"]
        share = f" ({100 * late / b['frames_received']:.1f} %)" if b["frames_received"] and late else ""
        cpu = f"{b['hub_cpu_percent_of_one_core']:.0f} %" if "hub_cpu_percent_of_one_core" in b else "–"
        secs = (f"{b['loadgen_cpu_seconds']:.1f} / {b['hub_cpu_seconds']:.1f}"
                if "loadgen_cpu_seconds" in b and "hub_cpu_seconds" in b else "–")
        lines.append(f"| {b['buses']} | {num(b['frames_received'])} / {num(b['frames_sent'])} | "
                     f"{num(b['delivered_per_second_per_bus'])} | {b['mean_lag_ms']:.2f} ms | {b['max_lag_ms']:.1f} ms | "
                     f"{num(late)}{share} | {cpu} | {secs} |")
    lines += ["", "### python-can and python canopen through each hub", "",
              "| measurement | canopener hub | Python baseline hub | ratio |", "|---|---|---|---|"]
    ours, theirs = "canopener", "python"

    def lost(kind):
        entry = r[f"{kind}_pycan_exchange"]
        return (f"{sum(run['lost'] for run in entry['runs'])} / {sum(run['out_of_order'] for run in entry['runs'])} "
                f"(sum over {len(entry['runs'])} run(s))")

    exchange = spread(r[f"{ours}_pycan_exchange"], "frames_each_way")
    lines.append(f"| 2 python-can processes exchange {num(exchange[0] if exchange else 0)} frames each way: lost / out "
                 f"of order | {lost(ours)} | {lost(theirs)} | – |")
    lines.append(f"| … aggregate frames/s | {cell(r[f'{ours}_pycan_exchange'], 'frames_per_s', bold=True)} | "
                 f"{cell(r[f'{theirs}_pycan_exchange'], 'frames_per_s')} | "
                 f"{ratio(r[f'{ours}_pycan_exchange'], r[f'{theirs}_pycan_exchange'], 'frames_per_s', bold=True)} |")
    ping = (r[f"{ours}_pycan_ping"], r[f"{theirs}_pycan_ping"])
    lines.append(f"| python-can ping-pong ({num(samples(ping[0]))} samples), p50 | "
                 f"{cell(ping[0], 'median_us', 0, ' µs', bold=True)} | {cell(ping[1], 'median_us', 0, ' µs')} | "
                 f"{ratio(*ping, 'median_us', higher_is_better=False)} |")
    for key in ["p90_us", "p99_us"]:
        lines.append(f"| … {key[:3]} | {cell(ping[0], key, 0, ' µs')} | {cell(ping[1], key, 0, ' µs')} | "
                     f"{ratio(*ping, key, higher_is_better=False)} |")
    rec = (r[f"{ours}_reconnect"][0], r[f"{theirs}_reconnect"][0])
    lines.append(f"| {rec[0]['attempts']} python-can reconnects while the bus is flooded: handshake failures (1 run) | "
                 f"**{rec[0]['failures']}** | {rec[1]['failures']} | – |")
    co = (r[f"{ours}_canopen"], r[f"{theirs}_canopen"])
    rows = [("python canopen SDO expedited upload, median", "expedited_upload_median_ms", 3, " ms", False),
            ("… p99", "expedited_upload_p99_ms", 3, " ms", False),
            ("… transfers/s", "expedited_transfers_per_s", 0, "", True),
            ("python canopen segmented download, 889 bytes", "segmented_889_download_ms", 1, " ms", False),
            ("python canopen segmented upload, 889 bytes", "segmented_889_upload_ms", 1, " ms", False)]
    for label, key, digits, unit, higher in rows:
        lines.append(f"| {label} | {cell(co[0], key, digits, unit)} | {cell(co[1], key, digits, unit)} | "
                     f"{ratio(*co, key, higher_is_better=higher)} |")
    failed = sorted({name for entry in co for run in entry["runs"] for name in run.get("failed_checks", [])})
    lines += ["", "python canopen SDO and NMT checks (the CI interop test's): " +
              ("all passed in every run." if not failed else "FAILED: " + ", ".join(failed) + ".")]
    return "\n".join(lines) + "\n"


def pycan_exchange(hub, count):
    a = peer("pycan_exchange.py", "127.0.0.1", hub.port, "can0", "0x100", "0x200", count)
    b = peer("pycan_exchange.py", "127.0.0.1", hub.port, "can0", "0x200", "0x100", count)
    go(a, b)
    ra, rb = json_line(a), json_line(b)
    lost = ra["missing"] + rb["missing"]
    disorder = ra["out_of_order"] + rb["out_of_order"] + ra["duplicates"] + rb["duplicates"]
    elapsed = max(ra["elapsed_s"], rb["elapsed_s"])
    return {"frames_each_way": count, "lost": lost, "out_of_order": disorder,
            "frames_per_s": round(2 * count / elapsed), "elapsed_s": elapsed}


def pycan_ping(hub, samples):
    echo = peer("pycan_ping.py", "echo", "127.0.0.1", hub.port, "can0", samples)
    ping = peer("pycan_ping.py", "ping", "127.0.0.1", hub.port, "can0", samples)
    go(echo, ping)
    result = json_line(ping)
    json_line(echo)
    return result


def pycan_reconnect(hub, count):
    flood = subprocess.Popen([BIN, "bus", "gen", "--bus", f"socketcand://127.0.0.1:{hub.port}/can0",
                              "--duration", "600s", "--id", "181"], stderr=subprocess.DEVNULL)
    time.sleep(0.3)
    proc = peer("pycan_reconnect.py", "127.0.0.1", hub.port, "can0", count)
    result = json_line(proc)
    flood.terminate()
    flood.wait(10)
    return result


def canopen(hub, rounds):
    slave = peer("co_slave.py", "127.0.0.1", hub.port, "can0", "0x22", EDS)
    master = peer("co_master.py", "127.0.0.1", hub.port, "can0", "0x22", EDS, rounds)
    go(slave, master)
    result = json_line(master)
    slave.stdin.close()
    slave.wait(20)
    failed = [name for name, check in result["checks"].items() if not check["ok"]]
    return dict(result["timing"], failed_checks=failed)


def with_hub(kind, fn):
    hub = Hub(kind)
    try:
        return fn(hub)
    finally:
        hub.close()


def main():
    results = {"machine": machine(), "runs": RUNS}
    n_big = 30000 if QUICK else 100000
    log("rust clients, in-process canopener hub")
    results["throughput_2"] = median_of(lambda: hub_load("throughput", "--clients", 2, "--frames", 3 * n_big))
    results["throughput_8"] = median_of(lambda: hub_load("throughput", "--clients", 8, "--frames", n_big))
    results["throughput_8_all"] = median_of(lambda: hub_load("throughput", "--clients", 8, "--frames", n_big // 4, "--all-send"))
    results["latency"] = median_of(lambda: hub_load("latency", "--samples", 20000))
    log("rust clients, python baseline hub")
    results["py_throughput_2"] = median_of(lambda: with_hub("python", lambda h: hub_load("throughput", "--clients", 2, "--frames", n_big, hub=h)))
    results["py_throughput_8"] = median_of(lambda: with_hub("python", lambda h: hub_load("throughput", "--clients", 8, "--frames", n_big // 4, hub=h)))
    results["py_latency"] = median_of(lambda: with_hub("python", lambda h: hub_load("latency", "--samples", 5000, hub=h)))
    log(f"saturated 1 Mbit/s buses ({BUS_RATE} DLC-8 frames/s each)")
    results["buses"] = []
    for count in ([16, 64] if QUICK else [16, 32, 64, 96, 128]):
        results["buses"].append(hub_load("buses", "--buses", count, "--rate", BUS_RATE, "--seconds", 5 if QUICK else 10))
    for kind in ["canopener", "python"]:
        log(f"python-can and python canopen through the {kind} hub")
        results[f"{kind}_pycan_exchange"] = median_of(lambda: with_hub(kind, lambda h: pycan_exchange(h, n_big)))
        results[f"{kind}_pycan_ping"] = median_of(lambda: with_hub(kind, lambda h: pycan_ping(h, 5000)))
        results[f"{kind}_reconnect"] = [with_hub(kind, lambda h: pycan_reconnect(h, 200))]
        results[f"{kind}_canopen"] = median_of(lambda: with_hub(kind, lambda h: canopen(h, 1000)))
    out = ROOT / "bench-results/results.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(results, indent=1))
    text = markdown(results)
    (ROOT / "bench-results/hub.md").write_text(text)
    log(f"wrote {out} and {ROOT / 'bench-results/hub.md'}")
    print(text)


if __name__ == "__main__":
    main()
