"""What the benchmark scripts share: the machine facts every result records, and the corpus EDS files."""

import locale
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def machine():
    """CPU, cores, load, kernel and tool versions: the context a figure needs to mean anything."""
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo") as info:
            cpu = next((line.split(":", 1)[1].strip() for line in info if line.startswith("model name")), cpu)
    except OSError:
        pass
    import can
    import canopen
    rustc = subprocess.run(["rustc", "--version"], capture_output=True, text=True).stdout.strip()
    return {"cpu": cpu, "cores": os.cpu_count(), "load_average_1min": round(os.getloadavg()[0], 2),
            "kernel": platform.release(), "python": platform.python_version(), "python_can": can.__version__,
            "canopen": canopen.__version__, "python_file_encoding": locale.getpreferredencoding(False),
            "rustc": rustc, "date": time.strftime("%Y-%m-%d %H:%M")}


def corpus_eds(name, script):
    """A file of the shared EDS corpus (beside the checkout, or under CANOPENER_CORPUS); exits naming `script`."""
    root = os.environ.get("CANOPENER_CORPUS")
    path = (Path(root) if root else ROOT.parent / "shared/corpus") / "eds" / name
    if not path.is_file():
        sys.exit(f"{script}: {path} not found; set CANOPENER_CORPUS to the corpus root (the directory holding eds/)")
    return path


def transfer_stats(raw, expedited, large_bytes):
    """Median, p99 and fastest time of one kind of SDO transfer, plus transfers/s (expedited) or kB/s (the
    `large_bytes` of a segmented or block transfer over its median time). `raw` holds ok, failed, error and
    the verified transfers' `times_s`."""
    times = sorted(raw["times_s"])
    entry = {"ok": raw["ok"], "failed": raw["failed"], "error": raw["error"]}
    if times:
        median = statistics.median(times)
        entry["median_ms"] = median * 1e3
        entry["p99_ms"] = times[int(0.99 * (len(times) - 1))] * 1e3
        entry["min_ms"] = times[0] * 1e3
        if expedited:
            entry["transfers_per_s"] = len(times) / sum(times)
        else:
            entry["kB_per_s"] = large_bytes / median / 1e3
    return entry
