"""Times the master commands users wait for: `node scan` of 127 node-IDs and `lss scan` (fastscan plus node-ID
assignment) of 1 and 8 unconfigured devices, with python canopen's LSS fastscan of 1 device beside it.

Usage (via `cargo xtask bench`, after the release build): bench/master_cli.py [--quick]
Writes bench-results/master_cli.json and bench-results/master_cli.md.

Everything runs through one `canopener bus serve` hub per measurement, with `canopener sim` devices as the targets
(the checker's base.eds fixture). Each figure is the median of RUNS runs (min-max). The commands are timed from
process start to exit, so process start-up and the client's wait for the hub's 50 ms raw-mode grace are included:
that is what a user waits for.
"""

import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import machine  # noqa: E402  (shared bench plumbing)
from run import BIN, ROOT, Hub  # noqa: E402

EDS = ROOT / "crates/canopener-check/test_data/checks/base.eds"
QUICK = "--quick" in sys.argv
RUNS = 1 if QUICK else 3
PY = sys.executable
PY_FASTSCAN = r"""
import sys, time, canopen
host, port = sys.argv[1], int(sys.argv[2])
net = canopen.Network()
net.connect(interface="socketcand", host=host, port=port, channel="can0", tcp_tune=True)
time.sleep(0.06)  # the hub's raw-mode grace, as our client waits it out
start = time.perf_counter()
ok, address = net.lss.fast_scan()
elapsed = time.perf_counter() - start
net.disconnect()
print(f"{ok} {elapsed} {address}")
"""


def log(text):
    print(text, file=sys.stderr, flush=True)


class Sims:
    """`canopener sim` devices on the hub: configured ones with node-IDs, or LSS-unconfigured ones."""

    def __init__(self, hub, count, node_id=None, serial=100):
        args = [str(BIN), "sim"] + [str(EDS)] * count + ["--bus", f"socketcand://127.0.0.1:{hub.port}/can0"]
        args += ["--node-id", str(node_id)] if node_id else ["--serial", str(serial)]
        # The log goes to a file: a pipe nobody reads would fill up and stall the simulator.
        self.log = tempfile.NamedTemporaryFile("w+", prefix="canopener-sim-", suffix=".jsonl")
        self.proc = subprocess.Popen(args + ["--format", "json"], stdout=self.log, text=True)
        deadline = time.time() + 30
        while time.time() < deadline:
            with open(self.log.name) as text:
                started = sum('"event":"started"' in line.replace(" ", "") for line in text)
            if started >= count:
                break
            time.sleep(0.05)
        else:
            raise RuntimeError(f"only {started} of {count} simulated devices started")
        time.sleep(0.2)  # the simulator's own hub grace

    def close(self):
        self.proc.terminate()
        self.proc.wait(10)
        self.log.close()


def timed(args):
    start = time.perf_counter()
    done = subprocess.run(args, capture_output=True, text=True, timeout=600)
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} exited {done.returncode}: {done.stderr}")
    return elapsed, json.loads(done.stdout)


def node_scan(timeout):
    hub = Hub("canopener")
    sims = Sims(hub, 1, node_id=5)
    try:
        elapsed, report = timed([str(BIN), "node", "scan", "--bus", f"socketcand://127.0.0.1:{hub.port}/can0",
                                 "--timeout", timeout, "--format", "json"])
        found = [node["node"] for node in report["nodes"]]
        if found != [5]:
            raise RuntimeError(f"node scan found {found}, expected [5]")
        return {"wall_s": elapsed, "elapsed_ms": report["elapsed_ms"]}
    finally:
        sims.close()
        hub.close()


def lss_scan(count):
    hub = Hub("canopener")
    sims = Sims(hub, count)
    try:
        elapsed, report = timed([str(BIN), "lss", "scan", "--assign", "10-40", "--bus",
                                 f"socketcand://127.0.0.1:{hub.port}/can0", "--format", "json"])
        serials = sorted(device["serial_number"] for device in report["devices"])
        if serials != list(range(100, 100 + count)) or not report["complete"]:
            raise RuntimeError(f"lss scan found serials {serials}, expected 100..{99 + count}: {report}")
        return {
            "wall_s": elapsed,
            "elapsed_ms": report["elapsed_ms"],
            "frames": report["frames_sent"] + report["frames_received"],
            "timeouts": report["timeouts"],
            "timeout_ms": report["timeout_ms"],
        }
    finally:
        sims.close()
        hub.close()


def python_fastscan():
    hub = Hub("canopener")
    sims = Sims(hub, 1)
    try:
        done = subprocess.run([PY, "-c", PY_FASTSCAN, "127.0.0.1", str(hub.port)], capture_output=True, text=True,
                              timeout=600)
        ok, elapsed, address = done.stdout.split(" ", 2)
        if ok != "True":
            raise RuntimeError(f"python fastscan failed: {done.stdout} {done.stderr}")
        return {"elapsed_s": float(elapsed), "address": address.strip()}
    finally:
        sims.close()
        hub.close()


def ms(values):
    return f"{statistics.median(values):.0f} ms ({min(values):.0f}–{max(values):.0f})"


def main():
    results = {"machine": machine(), "runs": RUNS}
    for timeout in ["100ms", "1s"]:
        log(f"node scan, --timeout {timeout}")
        results[f"node_scan_{timeout}"] = [node_scan(timeout) for _ in range(RUNS)]
    for count in [1, 8]:
        log(f"lss scan --assign, {count} device(s)")
        results[f"lss_scan_{count}"] = [lss_scan(count) for _ in range(RUNS)]
    log("python canopen fast_scan, 1 device")
    results["python_fastscan_1"] = [python_fastscan() for _ in range(RUNS)]

    lines = [
        f"One run of `bench/master_cli.py` on {time.strftime('%Y-%m-%d %H:%M')}: {results['machine']['cpu']}, "
        f"median of {RUNS} run(s) (min–max); command wall time from process start to exit (start-up and the 60 ms "
        "wait for the hub's raw-mode grace included). Targets: `canopener sim` devices from the checker's "
        "`base.eds` through one `canopener bus serve` hub.",
        "",
        "| what | canopener | python canopen | note |",
        "|---|---|---|---|",
    ]
    for timeout in ["100ms", "1s"]:
        runs = results[f"node_scan_{timeout}"]
        lines.append(
            f"| `node scan` of node-IDs 1–127, one device present, `--timeout {timeout}` | "
            f"**{ms([r['wall_s'] * 1000 for r in runs])}** (scan itself {ms([r['elapsed_ms'] for r in runs])}) | "
            "– | all 127 SDO requests in flight at once: one timeout for the silent IDs |"
        )
    for count in [1, 8]:
        runs = results[f"lss_scan_{count}"]
        python = ""
        if count == 1:
            py = results["python_fastscan_1"]
            python = f"{ms([r['elapsed_s'] * 1000 for r in py])} (`fast_scan()` only, no assignment)"
        lines.append(
            f"| `lss scan --assign 10-40`, {count} unconfigured device(s) | "
            f"**{ms([r['wall_s'] * 1000 for r in runs])}** (scan itself {ms([r['elapsed_ms'] for r in runs])}; "
            f"{runs[0]['frames']} frames, {runs[0]['timeouts']} timeouts of {runs[0]['timeout_ms']:.0f} ms) | "
            f"{python or '–'} | fastscan, configure node-ID, switch to waiting, per device; one final probe |"
        )
    lines += [
        "",
        "Fastscan is bound by its timeouts, not by the bus: every bit that no device answers costs one LSS timeout "
        "(100 ms by default here, 0.5 s in python canopen). Our default keeps a margin of about 20× over the worst "
        "round trip measured through socketcand; `--timeout` trades that margin for speed.",
    ]
    out = ROOT / "bench-results"
    out.mkdir(exist_ok=True)
    (out / "master_cli.json").write_text(json.dumps(results, indent=2))
    (out / "master_cli.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
