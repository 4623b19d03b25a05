"""`eds check` on CiA 311 XML against reading it: what checking an XDD/XDC costs beyond loading it.

Usage (via bench/run.sh, i.e. cargo xtask bench): bench/xdd_check.py [--quick] [--repeat N]

Runs target/release/examples/xdd_check_timing on every XDD/XDC/XPD/NXDD of the corpus (vendored plus the
extended corpus when present): per file, on one thread, the median of N runs of the XDD reader alone
(canopener_xdd::read: model, diagnostics, locations) and of the whole check (Checker::check: reading, every
model check on the reader's model, placing findings in the XML). Files the checker refuses
(POWERLINK) are listed and left out of the sums. Results: bench-results/xdd_check.md and .json.
"""

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402

ROOT = common.ROOT
# CARGO_TARGET_DIR is honoured as cargo honours it when building the program.
TIMING = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "release/examples/xdd_check_timing"
OUT_DIR = ROOT / "bench-results"


def parse_args(argv):
    repeat = 7
    rest = list(argv)
    while rest:
        arg = rest.pop(0)
        if arg == "--quick":
            repeat = 3
        elif arg == "--repeat" and rest:
            repeat = int(rest.pop(0))
        else:
            sys.exit(f"xdd_check.py: unknown argument {arg!r}; usage: bench/xdd_check.py [--quick] [--repeat N]")
    return repeat


def main():
    repeat = parse_args(sys.argv[1:])
    if not TIMING.is_file():
        sys.exit(f"xdd_check.py: {TIMING} is missing; cargo build --release -p canopener-description "
                 "--example xdd_check_timing (bench/run.sh does)")
    files = common.corpus_files("xdd")
    facts = common.machine()
    done = subprocess.run([str(TIMING), "--repeat", str(repeat), *map(str, files)],
                          capture_output=True, text=True, check=True)
    results = json.loads(done.stdout)["files"]
    checked = [r for r in results if not r.get("refused") and "error" not in r]
    refused = [Path(r["path"]).name for r in results if r.get("refused") or "error" in r]
    def row(label, key):
        read = sum(r[f"read_{key}_us"] for r in checked)
        check = sum(r[f"check_{key}_us"] for r in checked)
        return f"| {label} | {read / 1e3:,.1f} ms | {check / 1e3:,.1f} ms | {check / read:.2f}× |"

    ratios = [r["check_median_us"] / r["read_median_us"] for r in checked if r["read_median_us"] > 0]
    biggest = max(checked, key=lambda r: r["bytes"])
    lines = [
        "## Checking XDD/XDC files against reading them (`bench/xdd_check.py`, issue 18)",
        "",
        f"One run of `bench/xdd_check.py` on {facts['date']}: {facts['cpu']}, {facts['cores']} cores, load average "
        f"{facts['load_average_1min']} before the run; {facts['rustc']}. {len(checked)} corpus XML files checked "
        f"({', '.join(refused) or 'none'} refused), {repeat} runs each, one thread.",
        "",
        "| | read (XDD reader) | check (read + every check, placed in the XML) | check / read |",
        "|---|---:|---:|---:|",
        row("whole corpus, sum of per-file medians", "median"),
        row("whole corpus, sum of per-file fastest runs", "min"),
        f"| median file (median of per-file ratios) | {statistics.median(r['read_median_us'] for r in checked):,.0f} µs | "
        f"{statistics.median(r['check_median_us'] for r in checked):,.0f} µs | {statistics.median(ratios):.2f}× |",
        f"| largest file ({Path(biggest['path']).name}, {biggest['bytes']:,} bytes), median | "
        f"{biggest['read_median_us']:,.0f} µs | {biggest['check_median_us']:,.0f} µs | "
        f"{biggest['check_median_us'] / biggest['read_median_us']:.2f}× |",
        "",
    ]
    OUT_DIR.mkdir(exist_ok=True)
    (OUT_DIR / "xdd_check.md").write_text("\n".join(lines))
    (OUT_DIR / "xdd_check.json").write_text(json.dumps({"machine": facts, "repeat": repeat, "files": results},
                                                       indent=1))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
