"""Runs every benchmark of BENCHMARKS.md in one go and prints its tables.

Usage (via `cargo xtask bench`): bench/run.py [--quick]
Each figure is the median of RUNS runs unless the table says otherwise. Results: bench-results/results.json.
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
    results = [fn() for _ in range(runs)]
    return results


def med(results, key):
    values = [r[key] for r in results if key in r]
    return statistics.median(values) if values else None


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
    log("saturated 1 Mbit/s buses (8849 DLC-8 frames/s each)")
    results["buses"] = []
    for count in ([16, 64] if QUICK else [16, 32, 64, 96, 128]):
        results["buses"].append(hub_load("buses", "--buses", count, "--rate", 8849, "--seconds", 5 if QUICK else 10))
    for kind in ["canopener", "python"]:
        log(f"python-can and python canopen through the {kind} hub")
        results[f"{kind}_pycan_exchange"] = median_of(lambda: with_hub(kind, lambda h: pycan_exchange(h, n_big)))
        results[f"{kind}_pycan_ping"] = median_of(lambda: with_hub(kind, lambda h: pycan_ping(h, 5000)))
        results[f"{kind}_reconnect"] = [with_hub(kind, lambda h: pycan_reconnect(h, 200))]
        results[f"{kind}_canopen"] = median_of(lambda: with_hub(kind, lambda h: canopen(h, 1000)))
    out = ROOT / "bench-results/results.json"
    out.write_text(json.dumps(results, indent=1))
    log(f"wrote {out}")
    print(json.dumps(results))


if __name__ == "__main__":
    main()
