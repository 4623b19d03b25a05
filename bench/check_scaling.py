"""How `canopener eds check` scales with the size of a file: generated EDS files of 1k..64k objects with every
kind of finding the checks make about objects and lists, timed end to end, with the log-log slope.

Usage: bench/check_scaling.py [--quick] [--repeat N] [--sizes 1000,2000,...]
       (CANOPENER_BIN=path/to/canopener to time another build; default target/release/canopener)

An "object" here is one object-dictionary entry: a VAR, or one sub-index of an ARRAY (every fourth index is an
ARRAY with sub 0 and two elements). Half the indices lie below 6000h and half in the profile area (6000h..),
where the misplaced-list case of issue 13 lives. Every index carries one defect in rotation:

  listed in the wrong list (C403, both ways), not listed (P043), listed twice (P044), a default above its high
  limit, limits the wrong way round, an unknown data type, a bad access type, a missing ParameterName,
  a duplicated key, a default that is not a number, an ARRAY whose SubNumber disagrees with its subs,
  a PDO-mappable flag on a DOMAIN; plus listed indices without a section (P042) and numbering gaps (C402).

The slope is the least-squares fit of log(time) on log(objects) over the sizes: 1 is linear, 2 quadratic. A
per-run fixed cost (process start, 25 ms or so) flattens the small sizes, so the slope of the largest half
of the sizes is printed too. Each time is the median of N runs, wall clock and CPU (user + system, which the
other users of a shared machine affect less); the range is the fastest and slowest run.
Results: bench-results/check_scaling.md and .json.
"""

import json
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402

ROOT = common.ROOT
CANOPENER = Path(os.environ.get("CANOPENER_BIN", ROOT / "target/release/canopener"))
OUT_DIR = ROOT / "bench-results"
SIZES = [1000, 2000, 4000, 8000, 16000, 32000, 64000]
DEFECTS = 14
SERIES = ["mixed", "misplaced"]


def var(lines, name, index, sub, defect, data_type="0x0007", mappable=False):
    lines.append(f"[{name}]")
    if defect != 9:
        lines.append(f"ParameterName=Object {index:04X}h sub {sub}")
    lines.append("ObjectType=0x7")
    lines.append("DataType=" + ("0x00FF" if defect == 7 else ("0x000F" if defect == 13 else data_type)))
    lines.append("AccessType=" + ("rwx" if defect == 8 else "rw"))
    if defect == 5:
        lines += ["LowLimit=0", "HighLimit=100", "DefaultValue=200"]
    elif defect == 6:
        lines += ["LowLimit=100", "HighLimit=10", "DefaultValue=50"]
    elif defect == 11:
        lines.append("DefaultValue=not-a-number")
    elif defect != 13:
        lines.append(f"DefaultValue={sub}")
    if defect == 10:
        lines.append("AccessType=ro")
    lines.append("PDOMapping=" + ("1" if mappable or defect == 13 else "0"))
    lines.append("")


def generate(objects, series):
    """The EDS text of a file with `objects` entries, and how many indices it has. `series` "mixed" rotates
    every defect; "misplaced" is issue 13's case: every index in the profile area (6000h..), each an ARRAY
    (two objects), all listed under [ManufacturerObjects], so nearly every entry of that list is a C403."""
    lists = {"Mandatory": [0x1000, 0x1001, 0x1018], "Optional": [], "Manufacturer": []}
    body = []
    # The mandatory objects, clean, so the file is otherwise a device description.
    var(body, "1000", 0x1000, 0, -1)
    var(body, "1001", 0x1001, 0, -1, data_type="0x0005")
    body += ["[1018]", "ParameterName=Identity", "ObjectType=0x9", "SubNumber=2", "",
             "[1018sub0]", "ParameterName=Highest sub-index", "ObjectType=0x7", "DataType=0x0005",
             "AccessType=const", "DefaultValue=1", "PDOMapping=0", "",
             "[1018sub1]", "ParameterName=Vendor-ID", "ObjectType=0x7", "DataType=0x0007",
             "AccessType=ro", "DefaultValue=0x1234", "PDOMapping=0", ""]
    # Half the indices below 6000h, half above, so every size has both areas (and both C403 directions).
    first = max(0x2000, 0x6000 - (objects * 4 // 5) // 2) if series == "mixed" else 0x6000
    made, index, n = 3, first, 0
    while made < objects and index <= 0xFFFF:
        defect = n % DEFECTS if series == "mixed" else 1
        right = "Manufacturer" if index < 0x6000 else "Optional"
        wrong = "Optional" if right == "Manufacturer" else "Manufacturer"
        if defect in (1, 2):
            lists[wrong].append(index)  # C403 both ways: 2000h.. in Optional, 6000h.. in Manufacturer
        elif defect == 3:
            pass  # P043: described, listed nowhere
        elif defect == 4:
            lists[right] += [index, index]  # P044
        else:
            lists[right].append(index)
        if n % 4 == 3 or series == "misplaced":
            subs = 2 if defect != 12 else 3  # SubNumber=3 with two subs written
            body += [f"[{index:04X}]", f"ParameterName=Array {index:04X}h", "ObjectType=0x8", f"SubNumber={subs}", ""]
            body += [f"[{index:04X}sub0]", "ParameterName=Highest sub-index", "ObjectType=0x7", "DataType=0x0005",
                     "AccessType=ro", "DefaultValue=1", "PDOMapping=0", ""]
            var(body, f"{index:04X}sub1", index, 1, defect)
            made += 2
        else:
            var(body, f"{index:04X}", index, 0, defect)
            made += 1
        index += 1
        n += 1
    # P042: listed, no section (after the last described index).
    for missing in (range(0) if series == "misplaced" else range(index, min(index + max(1, objects // 1000), 0x10000))):
        lists["Manufacturer" if missing < 0x6000 else "Optional"].append(missing)
    head = ["[FileInfo]", "FileName=scaling.eds", "FileVersion=1", "FileRevision=0", "EDSVersion=4.0",
            "Description=generated by bench/check_scaling.py", "CreationTime=12:00PM", "CreationDate=01-01-2026",
            "CreatedBy=bench", "", "[DeviceInfo]", "VendorName=bench", "VendorNumber=0x1234", "ProductName=scaling",
            "ProductNumber=1", "RevisionNumber=1", "OrderCode=1", "BaudRate_10=0", "BaudRate_20=0", "BaudRate_50=0",
            "BaudRate_125=1", "BaudRate_250=1", "BaudRate_500=1", "BaudRate_800=0", "BaudRate_1000=1",
            "SimpleBootUpMaster=0", "SimpleBootUpSlave=1", "Granularity=8", "DynamicChannelsSupported=0",
            "GroupMessaging=0", "NrOfRXPDO=0", "NrOfTXPDO=0", "LSS_Supported=0", ""]
    for kind, indices in lists.items():
        head.append(f"[{kind}Objects]")
        head.append(f"SupportedObjects={len(indices)}")
        for number, listed in enumerate(indices, start=1):
            # C402: one gap per list (entry 2 numbered past the count) when the list is long enough.
            key = len(indices) + 1 if number == 2 and len(indices) > 2 else number
            head.append(f"{key}=0x{listed:04X}")
        head.append("")
    return "\n".join(head + body) + "\n", index - first + 3


def child_cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def time_check(path, repeat):
    """Wall-clock and CPU seconds (user + system) of each of `repeat` runs, and the last run's report. CPU time
    is what the other users of a shared machine leave least mark on."""
    times, cpu, findings = [], [], None
    for _ in range(repeat):
        cpu_before = child_cpu_seconds()
        start = time.perf_counter()
        done = subprocess.run([CANOPENER, "eds", "check", path, "--format", "json"], capture_output=True, text=True)
        times.append(time.perf_counter() - start)
        cpu.append(child_cpu_seconds() - cpu_before)
        if done.returncode not in (0, 1):
            sys.exit(f"check_scaling.py: canopener eds check failed with exit {done.returncode}: {done.stderr[:500]}")
        findings = done.stdout
    return times, cpu, findings


def codes_of(report_text):
    """Finding counts by code from the JSON report (one object, or one per line)."""
    counts = {}

    def walk(value):
        if isinstance(value, dict):
            code = value.get("code")
            if isinstance(code, str) and ("message" in value or "severity" in value):
                counts[code] = counts.get(code, 0) + 1
            for child in value.values():
                walk(child)
        elif isinstance(value, list):
            for child in value:
                walk(child)

    for line in report_text.splitlines() or [report_text]:
        line = line.strip()
        if line:
            try:
                walk(json.loads(line))
            except json.JSONDecodeError:
                walk(json.loads(report_text))
                break
    return counts


def slope(points):
    xs = [math.log(n) for n, _ in points]
    ys = [math.log(t) for _, t in points]
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def main():
    args = sys.argv[1:]
    repeat = 3 if "--quick" in args else 7
    sizes = SIZES
    if "--repeat" in args:
        repeat = int(args[args.index("--repeat") + 1])
    if "--sizes" in args:
        sizes = [int(s) for s in args[args.index("--sizes") + 1].split(",")]
    if not CANOPENER.is_file():
        sys.exit(f"check_scaling.py: {CANOPENER} is missing; build it with "
                 "`cargo build --release -p canopener-cli --bin canopener` (bench/run.sh does) or set CANOPENER_BIN")
    load_before = os.getloadavg()[0]
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for series, objects in [(series, objects) for series in SERIES for objects in sizes]:
            text, indices = generate(objects, series)
            path = Path(scratch) / f"scaling_{series}_{objects}.eds"
            path.write_text(text)
            times, cpu, report = time_check(str(path), repeat)
            codes = codes_of(report)
            rows.append({"series": series, "objects": objects, "indices": indices, "bytes": len(text.encode()),
                         "median_s": statistics.median(times), "min_s": min(times), "max_s": max(times),
                         "cpu_median_s": statistics.median(cpu), "cpu_min_s": min(cpu), "cpu_max_s": max(cpu),
                         "findings": sum(codes.values()), "codes": codes})
            print(f"check_scaling: {series}, {objects} objects: median {rows[-1]['median_s'] * 1e3:.1f} ms, "
                  f"{rows[-1]['findings']} findings", file=sys.stderr)
    slopes = {}
    for series in SERIES:
        for measure, key in [("wall", "median_s"), ("cpu", "cpu_median_s")]:
            points = [(r["objects"], r[key]) for r in rows if r["series"] == series]
            upper = points[len(points) // 2:]
            slopes[f"{series}, {measure}"] = {"all": slope(points),
                                              "upper_half": slope(upper) if len(upper) >= 2 else None}
    results = {"machine": dict(common.machine(), load_average_1min_before=load_before), "repeat": repeat,
               "binary": str(CANOPENER), "rows": rows, "slopes": slopes}
    OUT_DIR.mkdir(exist_ok=True)
    (OUT_DIR / "check_scaling.json").write_text(json.dumps(results, indent=1))
    text = markdown(results)
    (OUT_DIR / "check_scaling.md").write_text(text)
    print(text)


def markdown(r):
    m = r["machine"]
    all_codes = sorted({code for row in r["rows"] if row["series"] == "mixed" for code in row["codes"]})
    lines = [
        f"One run of `bench/check_scaling.py` on {m['date']}: {m['cpu']}, {m['cores']} cores, load average "
        f"{m['load_average_1min_before']:.1f} before the run; {m['rustc']}; `canopener eds check FILE --format json`, "
        f"{r['repeat']} runs per size (median, fastest..slowest).",
        "",
        "| file | objects | indices | size | wall time (median) | range | CPU time (median) | range | findings |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for row in r["rows"]:
        lines.append(f"| {row['series']} | {row['objects']:,} | {row['indices']:,} | {row['bytes'] / 1e6:.1f} MB "
                     f"| {row['median_s'] * 1e3:,.1f} ms | {row['min_s'] * 1e3:,.1f}..{row['max_s'] * 1e3:,.1f} ms "
                     f"| {row['cpu_median_s'] * 1e3:,.1f} ms "
                     f"| {row['cpu_min_s'] * 1e3:,.1f}..{row['cpu_max_s'] * 1e3:,.1f} ms | {row['findings']:,} |")
    lines.append("")
    for series, fit in r["slopes"].items():
        upper = f", {fit['upper_half']:.2f} over the larger half" if fit["upper_half"] is not None else ""
        lines.append(f"- {series} time: log-log slope on objects {fit['all']:.2f} over all sizes{upper} "
                     "(1 = linear, 2 = quadratic).")
    lines += ["", "Finding codes in the mixed files: " + ", ".join(all_codes) + "."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
