"""Checking the EDS corpus with canopener against importing it with python canopen, in one run.

Usage (via bench/run.sh, i.e. cargo xtask bench): bench/eds_check.py [--quick] [--repeat N]

Python canopen has no checker; importing a file is the least it must do to say anything about it, so its
import time is the floor of any python-based check. Three comparisons, all on the whole corpus
(148 files with the extended corpus):

1. per file, one thread each: canopener reads, loads and runs every built-in check (examples/check_timing)
   against python canopen's import_od of the same file; medians of N runs per file, summed over the corpus;
2. the command a user runs: `canopener eds check FILES --format json -o /dev/null` (parallel, all cores)
   against one python process that imports every file (interpreter start and `import canopen` included);
   median wall-clock time of N runs each;
3. the same command pinned to one core (RAYON_NUM_THREADS=1), so parallelism is not credited as speed.

Files python canopen cannot import are counted at the median time it took to fail (N attempts). Results:
bench-results/eds_check.md and bench-results/eds_check.json.
"""

import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import eds_load  # noqa: E402  (shares corpus discovery, python timing and machine facts)

ROOT = eds_load.ROOT
CHECK_TIMING = ROOT / "target/release/examples/check_timing"
CANOPENER = ROOT / "target/release/canopener"
OUT_DIR = ROOT / "bench-results"
GOAL_SPEEDUP = 50
IMPORT_ALL = """
import logging, sys, canopen
logging.getLogger("canopen").addHandler(logging.NullHandler())
logging.getLogger("canopen").propagate = False
failed = 0
for path in sys.argv[1:]:
    try:
        canopen.import_od(path)
    except Exception:
        failed += 1
print(failed)
"""


def need(path, how):
    if not path.is_file():
        sys.exit(f"eds_check.py: {path} is missing; {how} (bench/run.sh does)")


def time_command(argv, repeat, env=None):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        done = subprocess.run(argv, capture_output=True, text=True, env=env)
        times.append(time.perf_counter() - start)
        if done.returncode not in (0, 1):
            sys.exit(f"eds_check.py: {argv[0]} failed with exit {done.returncode}: {done.stderr[:500]}")
    return statistics.median(times), done.stdout


def python_time_failed(path, repeat):
    """The median time python canopen takes to fail on a file, over `repeat` attempts, like every other figure."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        try:
            eds_load.canopen.import_od(str(path))
        except Exception:
            pass
        times.append((time.perf_counter() - start) * 1e6)
    return statistics.median(times)


def main():
    repeat = eds_load.parse_args(sys.argv[1:])
    need(CHECK_TIMING, "build it with `cargo build --release -p canopener-check --example check_timing`")
    need(CANOPENER, "build it with `cargo build --release -p canopener-cli --bin canopener`")
    eds_load.quiet_python_canopen()
    paths = eds_load.corpus_files("eds")
    load_before = os.getloadavg()[0]
    eds_load.log(f"eds_check: canopener check_timing on {len(paths)} files, {repeat} runs each")
    done = subprocess.run([CHECK_TIMING, "--repeat", str(repeat), "--list", "-"],
                          input="\n".join(str(p) for p in paths), check=True, capture_output=True, text=True)
    ours = {e["path"]: e for e in json.loads(done.stdout)["files"]}
    eds_load.log("eds_check: python canopen import_od per file")
    rows = []
    for path in paths:
        theirs = eds_load.time_python(path, repeat)
        python_us = theirs.get("median_us") or python_time_failed(path, repeat)
        mine = ours[str(path)]
        rows.append({"file": path.name, "canopener_check_us": mine["median_us"],
                     "canopener_load_us": mine["load_median_us"], "findings": mine["findings"],
                     "errors": mine["errors"], "python_import_us": python_us,
                     "python_error": theirs.get("error_class")})
    ours_total = sum(r["canopener_check_us"] for r in rows)
    load_total = sum(r["canopener_load_us"] for r in rows)
    theirs_total = sum(r["python_import_us"] for r in rows)
    ratios = [r["python_import_us"] / r["canopener_check_us"] for r in rows if r["canopener_check_us"] > 0]
    eds_load.log("eds_check: whole commands")
    files = [str(p) for p in paths]
    # The files, not a directory: the corpus may span the vendored and the extended directory.
    cli = [CANOPENER, "eds", "check", *files, "--format", "json", "-o", os.devnull]
    cli_time, _ = time_command(cli, repeat)
    one_core = dict(os.environ, RAYON_NUM_THREADS="1")
    cli_one_time, _ = time_command(cli, repeat, env=one_core)
    py_time, py_out = time_command([sys.executable, "-c", IMPORT_ALL, *files], max(3, repeat // 2))
    results = {
        "machine": dict(eds_load.machine(), load_average_1min_before=load_before),
        "repeat": repeat,
        "goal_speedup": GOAL_SPEEDUP,
        "files": len(rows),
        "python_failures": sum(1 for r in rows if r["python_error"]),
        "per_file": {
            "canopener_check_total_us": ours_total,
            "canopener_load_total_us": load_total,
            "python_import_total_us": theirs_total,
            "speedup_total": theirs_total / ours_total if ours_total else None,
            "speedup_median_per_file": statistics.median(ratios) if ratios else None,
            "canopener_check_median_us": statistics.median(r["canopener_check_us"] for r in rows),
            "python_import_median_us": statistics.median(r["python_import_us"] for r in rows),
        },
        "commands": {
            "canopener_check_s": cli_time,
            "canopener_check_one_core_s": cli_one_time,
            "python_import_all_s": py_time,
            "python_import_all_failures": int(py_out.strip() or 0),
            "speedup": py_time / cli_time if cli_time else None,
            "speedup_one_core": py_time / cli_one_time if cli_one_time else None,
        },
        "rows": rows,
    }
    OUT_DIR.mkdir(exist_ok=True)
    (OUT_DIR / "eds_check.json").write_text(json.dumps(results, indent=1))
    text = markdown(results)
    (OUT_DIR / "eds_check.md").write_text(text)
    eds_load.log(f"eds_check: wrote {OUT_DIR / 'eds_check.md'} and {OUT_DIR / 'eds_check.json'}")
    print(text)


def markdown(r):
    m, p, c = r["machine"], r["per_file"], r["commands"]
    verdict = lambda x: "met" if x and x >= r["goal_speedup"] else "NOT met"  # noqa: E731
    lines = [
        f"One run of `bench/eds_check.py` on {m['date']}: {m['cpu']}, {m['cores']} cores, load average "
        f"{m['load_average_1min_before']:.1f} before the run; python {m['python']}, canopen {m['canopen']}; "
        f"{m['rustc']}. {r['files']} corpus files, {r['repeat']} runs each (medians); python canopen cannot "
        f"import {r['python_failures']} of them (the median time it takes to fail).",
        "",
        "| comparison | canopener (check: load + every built-in check) | python canopen (import only) | speed-up | goal 50× |",
        "|---|---:|---:|---:|---|",
        f"| whole corpus, sum of per-file medians, one thread each | {p['canopener_check_total_us'] / 1e3:,.1f} ms "
        f"| {p['python_import_total_us'] / 1e3:,.1f} ms | {p['speedup_total']:.1f}× | {verdict(p['speedup_total'])} |",
        f"| median file | {p['canopener_check_median_us']:,.0f} µs | {p['python_import_median_us']:,.0f} µs "
        f"| {p['speedup_median_per_file']:.1f}× (median of per-file ratios) | {verdict(p['speedup_median_per_file'])} |",
        f"| the command, all {m['cores']} cores (`eds check DIR` vs one python process importing all) "
        f"| {c['canopener_check_s'] * 1e3:,.0f} ms | {c['python_import_all_s'] * 1e3:,.0f} ms "
        f"| {c['speedup']:.1f}× | {verdict(c['speedup'])} |",
        f"| the command on one core (RAYON_NUM_THREADS=1) | {c['canopener_check_one_core_s'] * 1e3:,.0f} ms "
        f"| {c['python_import_all_s'] * 1e3:,.0f} ms | {c['speedup_one_core']:.1f}× | {verdict(c['speedup_one_core'])} |",
        "",
        f"canopener's load alone is {p['canopener_load_total_us'] / 1e3:,.1f} ms of the "
        f"{p['canopener_check_total_us'] / 1e3:,.1f} ms: the checks cost "
        f"{(p['canopener_check_total_us'] - p['canopener_load_total_us']) / 1e3:,.1f} ms for the whole corpus.",
    ]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
