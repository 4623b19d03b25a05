"""EDS load time, side by side in one run: canopener (examples/load_timing) and python canopen's import_od.

Usage (via bench/run.sh, i.e. cargo xtask bench): bench/eds_load.py [--quick] [--repeat N]

Both tools load the same files the same way: every file of the EDS corpus, then synthetic files of 1k, 5k,
10k and 20k objects written to a temporary directory by `load_timing --generate` (the one generator, so both
read the identical bytes). Each file is loaded N times (7, or 3 with --quick) and the median is kept; one
timed load is reading the file plus parsing it, which is what `canopen.import_od(path)` does.
Files python canopen cannot import are reported with the exception class: they are a finding, not noise.
Throughput counts dictionary entries (objects plus sub-objects) as canopener's model holds them, the same
number for both tools, so objects/s compares the speed of reading one and the same file.

The corpus is the vendored corpus/eds plus the extended corpus when present (CANOPENER_CORPUS, else
../shared/corpus next to the repository; see bench/common.py). Results: bench-results/eds_load.md and
bench-results/eds_load.json.
"""

import gc
import json
import logging
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import corpus_files, machine  # noqa: E402  (shared with the other bench scripts)

import canopen
from canopen.objectdictionary import ODArray, ODRecord

ROOT = Path(__file__).resolve().parent.parent
TIMING = ROOT / "target/release/examples/load_timing"
OUT_DIR = ROOT / "bench-results"
SYNTHETIC_OBJECTS = [1_000, 5_000, 10_000, 20_000]
# Corpus files are grouped by size; the synthetic files form one class each.
SIZE_CLASSES = [("corpus small (< 10 kB)", 0, 10_000), ("corpus medium (10-100 kB)", 10_000, 100_000),
                ("corpus large (>= 100 kB)", 100_000, math.inf)]
GOAL_SPEEDUP = 50
# A log-log slope of load time against entries within this band counts as linear scaling; up to
# NEAR_LINEAR_SLOPE (overall and between the two largest files, so no quadratic term is taking over) it is
# near-linear, the per-entry cost growing slowly as the working set outgrows the caches.
LINEAR_SLOPE = (0.9, 1.1)
NEAR_LINEAR_SLOPE = 1.3


def log(text):
    print(text, file=sys.stderr, flush=True)


def parse_args(argv):
    quick = "--quick" in argv
    repeat = 3 if quick else 7
    if "--repeat" in argv:
        position = argv.index("--repeat")
        try:
            repeat = int(argv[position + 1])
        except (IndexError, ValueError):
            sys.exit("eds_load.py: --repeat needs a positive whole number")
        if repeat < 1:
            sys.exit("eds_load.py: --repeat needs a positive whole number")
    return repeat


def timing_program():
    if not TIMING.is_file():
        sys.exit(f"eds_load.py: {TIMING} is missing; build it with "
                 "`cargo build --release -p canopener-eds --example load_timing` (bench/run.sh does)")
    return TIMING


def generate(directory, objects):
    path = directory / f"synthetic_{objects}.eds"
    done = subprocess.run([timing_program(), "--generate", str(objects), path], check=True, capture_output=True,
                          text=True)
    return path, json.loads(done.stdout)


def time_canopener(paths, repeat):
    """Runs load_timing once over every file; returns its result per path."""
    done = subprocess.run([timing_program(), "--repeat", str(repeat), "--list", "-"],
                          input="\n".join(str(p) for p in paths), check=True, capture_output=True, text=True)
    return {entry["path"]: entry for entry in json.loads(done.stdout)["files"]}


def python_entries(od):
    """Objects plus sub-objects of a python canopen object dictionary."""
    return sum(1 + (len(obj) if isinstance(obj, (ODRecord, ODArray)) else 0) for obj in od.values())


def time_python(path, repeat):
    times = []
    entries = None
    for _ in range(repeat):
        start = time.perf_counter()
        try:
            od = canopen.import_od(str(path))
        except Exception as error:  # every failure class is the finding, whatever it is
            message = str(error).splitlines()[0] if str(error) else ""
            return {"error_class": type(error).__name__, "error": message[:200]}
        times.append(time.perf_counter() - start)
        if entries is None:
            entries = python_entries(od)
        # Freed outside the timed region, as load_timing drops its model after timing. python canopen's
        # objects point at their parents, so only the cycle collector frees them: without this, the garbage
        # of earlier loads makes later ones pay for ever longer collections.
        del od
        gc.collect()
    return {"median_us": statistics.median(times) * 1e6, "min_us": min(times) * 1e6, "entries": entries}


def quiet_python_canopen():
    """Keeps the messages python canopen logs for odd files off the terminal; they are still produced."""
    logger = logging.getLogger("canopen")
    logger.addHandler(logging.NullHandler())
    logger.propagate = False


def per_second(count, micros):
    return count / (micros / 1e6) if micros else None


def class_summary(name, rows):
    both = [r for r in rows if "median_us" in r["python"] and "median_us" in r["canopener"]]
    ours = [r for r in rows if "median_us" in r["canopener"]]
    c_total = sum(r["canopener"]["median_us"] for r in ours)
    c_both = sum(r["canopener"]["median_us"] for r in both)
    p_both = sum(r["python"]["median_us"] for r in both)
    entries_ours = sum(r["canopener"]["entries"] for r in ours)
    entries_both = sum(r["canopener"]["entries"] for r in both)
    bytes_ours = sum(r["canopener"]["bytes"] for r in ours)
    bytes_both = sum(r["canopener"]["bytes"] for r in both)
    return {
        "class": name,
        "files": len(rows),
        "canopener_failures": len(rows) - len(ours),
        "python_failures": len(rows) - len(both),
        "canopener_median_us": statistics.median(r["canopener"]["median_us"] for r in ours) if ours else None,
        "python_median_us": statistics.median(r["python"]["median_us"] for r in both) if both else None,
        "canopener_entries_per_s": per_second(entries_ours, c_total),
        "python_entries_per_s": per_second(entries_both, p_both),
        "canopener_mb_per_s": per_second(bytes_ours, c_total) / 1e6 if c_total else None,
        "python_mb_per_s": per_second(bytes_both, p_both) / 1e6 if p_both else None,
        # Over the files both tools loaded: total python time over total canopener time.
        "speedup": p_both / c_both if c_both else None,
        "median_file_speedup": statistics.median(r["python"]["median_us"] / r["canopener"]["median_us"]
                                                 for r in both) if both else None,
    }


def slope(points):
    """Least-squares slope of log(time) against log(entries): 1 is linear, 2 quadratic."""
    xs = [math.log(x) for x, _ in points]
    ys = [math.log(y) for _, y in points]
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def verdict(overall, last):
    low, high = LINEAR_SLOPE
    slopes = f"log-log slope {overall:.2f} overall, {last:.2f} between the two largest files"
    if overall < low:
        return f"sub-linear ({slopes}: fixed costs weigh on the small files)"
    if overall <= high:
        return f"linear ({slopes})"
    if overall <= NEAR_LINEAR_SLOPE and last <= NEAR_LINEAR_SLOPE:
        return f"near-linear ({slopes}; 1 is linear, 2 quadratic)"
    return f"super-linear ({slopes}; 1 is linear, 2 quadratic)"


def linearity(rows):
    table = []
    for row in rows:
        c, p = row["canopener"], row["python"]
        table.append({
            "objects": row["objects"], "entries": c.get("entries"), "bytes": c.get("bytes"),
            "canopener_us": c.get("median_us"), "python_us": p.get("median_us"),
            "canopener_ns_per_entry": c["median_us"] * 1e3 / c["entries"] if "median_us" in c else None,
            "python_ns_per_entry": p["median_us"] * 1e3 / c["entries"] if "median_us" in p and "entries" in c
            else None,
        })
    result = {"rows": table}
    for tool in ("canopener", "python"):
        points = [(r["entries"], r[f"{tool}_us"]) for r in table if r[f"{tool}_us"] and r["entries"]]
        if len(points) >= 2:
            overall, last = slope(points), slope(points[-2:])
            per_entry = [r[f"{tool}_ns_per_entry"] for r in table if r[f"{tool}_ns_per_entry"]]
            result[tool] = {"slope": overall, "slope_largest_two": last, "verdict": verdict(overall, last),
                            "ns_per_entry_spread": max(per_entry) / min(per_entry)}
    return result


def fmt_time(micros):
    if micros is None:
        return "-"
    if micros >= 10_000:
        return f"{micros / 1000:,.1f} ms"
    return f"{micros:,.0f} µs" if micros >= 100 else f"{micros:,.1f} µs"


def fmt_rate(value, unit=""):
    if value is None:
        return "-"
    for limit, suffix in ((1e6, "M"), (1e3, "k")):
        if value >= limit:
            return f"{value / limit:,.2f} {suffix}{unit}".strip()
    return f"{value:,.0f} {unit}".strip()


def fmt_mb(value):
    return "-" if value is None else f"{value:,.2f}"


def fmt_ratio(value):
    return "-" if value is None else f"{value:,.1f}×"


def markdown(results):
    m = results["machine"]
    corpus = next(c for c in results["classes"] if c["class"] == "corpus (all files)")
    met = corpus["speedup"] is not None and corpus["speedup"] >= GOAL_SPEEDUP
    lines = [
        "# EDS load time: canopener against python canopen",
        "",
        f"{m['date']}, {m['cpu']} ({m['cores']} cores), Linux {m['kernel']}, {m['rustc']}, "
        f"Python {m['python']} with canopen {m['canopen']} (files opened as {m['python_file_encoding']}). "
        f"1-minute load average {m['load_average_1min_before']:.2f} before the run, {m['load_average_1min']:.2f} "
        "after (this script uses one core). "
        f"Median of {results['repeat']} loads per file, each reading the file and parsing it "
        "(`canopener_eds::load`, `canopen.import_od(path)`). Entries are objects plus sub-objects as canopener's "
        "model holds them; both tools are credited with the same count.",
        "",
        f"**Whole corpus: canopener is {fmt_ratio(corpus['speedup'])} faster than python canopen "
        f"(goal ≥ {GOAL_SPEEDUP}×: {'met' if met else 'not met'}); python canopen failed on "
        f"{corpus['python_failures']} of {corpus['files']} files.**",
        "",
        "| class | files | python failures | canopener median/file | python median/file | canopener entries/s "
        "| python entries/s | canopener MB/s | python MB/s | speed-up (python ÷ canopener) | median speed-up per file |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for c in results["classes"]:
        lines.append(
            f"| {c['class']} | {c['files']} | {c['python_failures']} | {fmt_time(c['canopener_median_us'])} "
            f"| {fmt_time(c['python_median_us'])} | {fmt_rate(c['canopener_entries_per_s'])} "
            f"| {fmt_rate(c['python_entries_per_s'])} "
            f"| {fmt_mb(c['canopener_mb_per_s'])} | {fmt_mb(c['python_mb_per_s'])} "
            f"| {fmt_ratio(c['speedup'])} | {fmt_ratio(c['median_file_speedup'])} |")
    lin = results["linearity"]
    lines += ["", "## Scaling on synthetic files", "",
              "| objects | entries | bytes | canopener | ns/entry | python | ns/entry | speed-up |",
              "|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in lin["rows"]:
        speedup = r["python_us"] / r["canopener_us"] if r["python_us"] and r["canopener_us"] else None
        lines.append(f"| {r['objects']:,} | {r['entries'] or 0:,} | {r['bytes'] or 0:,} | {fmt_time(r['canopener_us'])} "
                     f"| {r['canopener_ns_per_entry'] or 0:,.0f} | {fmt_time(r['python_us'])} "
                     f"| {r['python_ns_per_entry'] or 0:,.0f} | {fmt_ratio(speedup)} |")
    lines.append("")
    for tool in ("canopener", "python"):
        if tool in lin:
            lines.append(f"- {tool}: {lin[tool]['verdict']}; time per entry varies "
                         f"{lin[tool]['ns_per_entry_spread']:.2f}× between the sizes.")
    failures = results["python_failures"]
    lines += ["", f"## Files python canopen {canopen.__version__} cannot import ({len(failures)})", ""]
    if failures:
        lines += ["| file | exception | message |", "|---|---|---|"]
        lines += [f"| {f['file']} | `{f['error_class']}` | {f['error'].replace('|', '/')} |" for f in failures]
    else:
        lines.append("None.")
    differ = [r for r in results["files"] if r["python"].get("entries") not in (None, r["canopener"].get("entries"))]
    lines += ["", f"Python canopen's dictionary has a different number of entries than canopener's model for "
              f"{len(differ)} of the files it imported (see `python.entries` in eds_load.json).", ""]
    lines += ["## Per file", "", "| file | bytes | entries | canopener | python | speed-up |",
              "|---|---:|---:|---:|---:|---:|"]
    for r in results["files"]:
        c, p = r["canopener"], r["python"]
        py = fmt_time(p["median_us"]) if "median_us" in p else f"`{p['error_class']}`"
        speedup = p["median_us"] / c["median_us"] if "median_us" in p and "median_us" in c else None
        lines.append(f"| {r['file']} | {c.get('bytes', 0):,} | {c.get('entries', 0):,} | {fmt_time(c.get('median_us'))} "
                     f"| {py} | {fmt_ratio(speedup)} |")
    return "\n".join(lines) + "\n"


def main():
    repeat = parse_args(sys.argv[1:])
    quiet_python_canopen()
    load_before = os.getloadavg()[0]
    corpus = corpus_files("eds")
    log(f"eds_load: {len(corpus)} corpus files, synthetic {SYNTHETIC_OBJECTS} objects, {repeat} loads each")
    with tempfile.TemporaryDirectory(prefix="canopener-eds-load-") as tmp:
        synthetic = [(objects, *generate(Path(tmp), objects)) for objects in SYNTHETIC_OBJECTS]
        paths = corpus + [path for _, path, _ in synthetic]
        log("eds_load: canopener")
        ours = time_canopener(paths, repeat)
        log("eds_load: python canopen")
        theirs = {}
        for number, path in enumerate(paths, 1):
            if number % 25 == 0:
                log(f"eds_load: python canopen {number}/{len(paths)}")
            theirs[str(path)] = time_python(path, repeat)
    rows = [{"file": p.name, "canopener": ours[str(p)], "python": theirs[str(p)]} for p in paths]
    corpus_rows = rows[:len(corpus)]
    synthetic_rows = [dict(row, objects=objects) for row, (objects, _, _) in zip(rows[len(corpus):], synthetic)]
    classes = [class_summary(name, [r for r in corpus_rows if low <= r["canopener"].get("bytes", 0) < high])
               for name, low, high in SIZE_CLASSES]
    classes.append(class_summary("corpus (all files)", corpus_rows))
    classes += [class_summary(f"synthetic {row['objects']:,} objects", [row]) for row in synthetic_rows]
    results = {
        "machine": dict(machine(), load_average_1min_before=load_before),
        "repeat": repeat,
        "goal_speedup": GOAL_SPEEDUP,
        "classes": classes,
        "linearity": linearity(synthetic_rows),
        "python_failures": [{"file": r["file"], **r["python"]} for r in corpus_rows if "error_class" in r["python"]],
        "canopener_failures": [{"file": r["file"], "error": r["canopener"]["error"]} for r in rows
                               if "error" in r["canopener"]],
        "files": rows,
    }
    OUT_DIR.mkdir(exist_ok=True)
    (OUT_DIR / "eds_load.json").write_text(json.dumps(results, indent=1))
    text = markdown(results)
    (OUT_DIR / "eds_load.md").write_text(text)
    log(f"eds_load: wrote {OUT_DIR / 'eds_load.md'} and {OUT_DIR / 'eds_load.json'}")
    print(text)


if __name__ == "__main__":
    main()
