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


CORPUS_EXTENSIONS = {"eds": (".eds", ".dcf"), "xdd": (".xdd", ".xdc", ".xpd", ".nxdd")}


def corpus_files(kind="eds"):
    """Every corpus file of `kind` ("eds" or "xdd"), sorted by name: the vendored files of corpus/ in the
    repository, plus those only the extended corpus has (CANOPENER_CORPUS, else ../shared/corpus beside the
    checkout when it exists). The same rules as canopener_testkit::corpus, which Python cannot call."""
    roots = [ROOT / "corpus"]
    extended = os.environ.get("CANOPENER_CORPUS")
    if extended:
        if not Path(extended).is_dir():
            # A typo must not silently shrink a benchmark to the vendored files.
            sys.exit(f"CANOPENER_CORPUS={extended} is not a directory; point it at a corpus root holding eds/ and "
                     "xdd/, or unset it")
        roots.append(Path(extended))
    elif (ROOT.parent / "shared/corpus").is_dir():
        roots.append(ROOT.parent / "shared/corpus")
    by_name = {}
    for root in roots:
        directory = root / kind
        if directory.is_dir():
            for path in directory.iterdir():
                if path.is_file() and path.suffix.lower() in CORPUS_EXTENSIONS[kind]:
                    by_name.setdefault(path.name, path)  # the vendored copy first
    return [by_name[name] for name in sorted(by_name)]


def corpus_eds(name, script):
    """One EDS of the corpus by name (see corpus_files); exits naming `script` when no corpus has it."""
    path = next((path for path in corpus_files("eds") if path.name == name), None)
    if path is None:
        sys.exit(f"{script}: {name} is in neither corpus/eds nor the extended corpus (CANOPENER_CORPUS)")
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
