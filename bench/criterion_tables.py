"""Runs the criterion micro-benchmarks of the runtime object dictionary, the frame-length model, the bus
engine and the EDS loader, plus the wall-clock saturation test of the virtual bus, and prints the BENCHMARKS.md sections about them
(bench-results/criterion.md). Every figure below those headings comes from here.

    python bench/criterion_tables.py [--quick]

Criterion's own estimates (target/criterion/**/new/estimates.json, the median's point estimate) are read back,
so the tables are exactly what criterion measured. --quick shortens warm-up and measurement (noisier)."""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import ROOT  # noqa: E402

QUICK = "--quick" in sys.argv
TARGET = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
BENCHES = [("canopener-eds", "load"), ("canopener-od", "od"), ("canopener-can", "bits"), ("canopener-bus-engine", "bus")]


def log(text):
    print(text, file=sys.stderr, flush=True)


def run_benches():
    timing = ["--warm-up-time", "1", "--measurement-time", "2" if QUICK else "5"]
    for package, bench in BENCHES:
        log(f"cargo bench -p {package} --bench {bench}")
        subprocess.run(["cargo", "bench", "--locked", "-q", "-p", package, "--bench", bench, "--", "--noplot", *timing],
                       cwd=ROOT, check=True, stdout=subprocess.DEVNULL)


def estimates():
    """{group: [(function, parameter, median_ns, elements)]} from criterion's JSON files."""
    groups = {}
    for path in sorted((TARGET / "criterion").glob("**/new/benchmark.json")):
        bench = json.loads(path.read_text())
        median = json.loads((path.parent / "estimates.json").read_text())["median"]["point_estimate"]
        throughput = bench.get("throughput") or {}
        elements = throughput.get("Elements") or throughput.get("BytesDecimal")
        groups.setdefault(bench["group_id"], []).append(
            (bench.get("function_id") or bench["group_id"], bench.get("value_str"), median, elements))
    return groups


def num(value, digits=1):
    text = f"{value:,.{digits}f}".replace(",", " ")
    return text


def table(rows, title, cell):
    """One markdown table: a row per function, a column per parameter (or one column without parameters)."""
    params = sorted({p for _, p, _, _ in rows if p is not None}, key=lambda p: (len(p), p))
    functions = list(dict.fromkeys(f for f, _, _, _ in rows))
    by_key = {(f, p): (m, e) for f, p, m, e in rows}
    out = [f"| {title} | " + (" | ".join(params) if params else "median") + " |",
           "|---|" + "---:|" * max(1, len(params))]
    for function in functions:
        cells = [cell(*by_key[(function, p)]) if (function, p) in by_key else "" for p in (params or [None])]
        out.append(f"| `{function}` | " + " | ".join(cells) + " |")
    return out


def saturation_line():
    """The wall-clock saturation test of the bit-accurate virtual bus prints one line of measured rates."""
    result = subprocess.run(["cargo", "test", "--locked", "--release", "-q", "-p", "canopener-transport", "--test",
                             "virtual_saturation", "--", "--nocapture"], cwd=ROOT, capture_output=True, text=True)
    line = next((l for l in result.stdout.splitlines() if "theoretical" in l), None)
    if result.returncode != 0 or line is None:
        return f"The wall-clock saturation test failed on this run (exit {result.returncode})."
    return line.strip()


def main():
    from common import machine
    facts = machine()
    run_benches()
    groups = estimates()
    per_element = lambda median, elements: num(median / elements) if elements else num(median)
    lines = [f"{facts['date']}, {facts['cpu']} ({facts['cores']} cores), {facts['rustc']}; 1-minute load average "
             f"{facts['load_average_1min']} before the run, {round(os.getloadavg()[0], 2)} after (2 cores: above 1, other "
             f"work shared them, so read ratios rather than absolute times). Criterion medians"
             f"{' (--quick)' if QUICK else ''}.", ""]
    entries = {p: (m, e) for _, p, m, e in groups.get("eds_load/entries", [])}
    sizes = {p: (m, e) for _, p, m, e in groups.get("eds_load/bytes", [])}
    if entries:
        lines += ["### The EDS loader (`cargo bench -p canopener-eds --bench load`)", "",
                  "`canopener_eds::load` on corpus files and synthetic ones; entries are objects plus sub-objects.", "",
                  "| input | bytes | entries | median time per load | entries/s | MB/s |", "|---|---:|---:|---:|---:|---:|"]
        for name, (median, count) in entries.items():
            size = sizes.get(name, (median, 0))
            lines.append(f"| `{name}` | {num(size[1], 0)} | {num(count, 0)} | {num(median / 1e3)} µs | "
                         f"{num(count / median * 1e3, 2)} M | {num(size[1] / median * 1e3)} |")
        lines.append("")
    lines += ["### The runtime object dictionary (`cargo bench -p canopener-od`)", "",
              "`DynamicOd` (sorted array, binary search over packed `u32` keys) against the standard maps, "
              "by dictionary size.", ""]
    for group in ("od_lookup_hit", "od_lookup_miss"):
        if group in groups:
            lines += table(groups[group], f"{group}, ns per lookup", per_element) + [""]
    if "od_insert" in groups:
        lines += table(groups["od_insert"], "od_insert, ns per insert", lambda m, e: num(m, 0)) + [""]
    if "od_build" in groups:
        lines += table(groups["od_build"], "od_build, µs for the whole dictionary", lambda m, e: num(m / 1e3)) + [""]
    if "od_value_storage" in groups:
        lines += table(groups["od_value_storage"], "od_value_storage, ns per entry", per_element) + [""]
    lines += ["### Frame lengths and the bus engine (`cargo bench -p canopener-can -p canopener-bus-engine`)", ""]
    if "frame_bits" in groups:
        lines += table(groups["frame_bits"], "frame_bits, ns per frame", lambda m, e: num(m)) + [""]
    for group, rows in groups.items():
        if group.startswith("saturated_1M"):
            lines += table(rows, f"{group}: frames per second of wall time (× real time at 1 Mbit/s, 9 009 frames/s)",
                           lambda m, e: f"{num(e / m * 1e3, 2)} M ({num(e / m * 1e9 / 9009, 0)}×)") + [""]
    lines += ["The bit-accurate virtual bus driven by the wall clock "
              "(`cargo test --release -p canopener-transport --test virtual_saturation`):", "", "> " + saturation_line()]
    text = "\n".join(lines) + "\n"
    (ROOT / "bench-results").mkdir(exist_ok=True)
    (ROOT / "bench-results/criterion.md").write_text(text)
    print(text, end="")


if __name__ == "__main__":
    main()
