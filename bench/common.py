"""What the benchmark scripts share: the machine facts every result records, and the corpus EDS files."""

import locale
import os
import platform
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
