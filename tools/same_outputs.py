#!/usr/bin/env python3
"""Do two canopener binaries print the same thing? The check a refactoring must pass (issue 25).

    tools/same_outputs.py BEFORE_BIN AFTER_BIN [--corpus DIR ...] [--work DIR]

For each binary, in its own scratch directory, this runs:

* `eds check --format json FILE` on every EDS, DCF, XDD and XDC file of the corpus directories
  (default: the repository's `corpus/` and, when it exists, `../shared/corpus/`), keeping stdout and
  the exit code;
* `demo --dir DIR`: the product tour (its narrative's wall time blanked), every conformance suite on the simulated demo device, clean and
  with a fault, on virtual time; its JSON reports are compared (`started`/`finished` wall-clock stamps
  and wall durations are the only fields blanked, since they differ from run to run by design);
* `mbt run MODELS --sim demo.eds --node N --seed S --steps 2000 --format json` for each shipped
  CANopen model alone and the compositions the docs quote, seeds 1-3 (virtual time, deterministic;
  the `wall_s` field is blanked).

It prints one line per output that differs and a summary with the number of outputs compared, and
exits 1 when any differs. Nothing of the repository is written: the scratch directory is a temporary
one unless --work names one (it is then kept, for a look at the differences).
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SUFFIXES = {".eds", ".dcf", ".xdd", ".xdc"}
# Wall-clock fields: the only ones allowed to differ between two runs of the same binary.
VOLATILE = {"started", "finished", "wall_s", "wall_ms", "elapsed_s", "elapsed_ms", "duration_s", "generated"}
MBT_RUNS = [
    ["nmt"], ["heartbeat"], ["sdo"], ["sync"], ["emcy"], ["guarding"], ["lss"],
    ["nmt", "heartbeat"], ["nmt", "sdo"], ["nmt", "heartbeat", "sdo"],
    ["nmt", "sync", "lss", "emcy", "guarding", "heartbeat", "sdo"],
]
SEEDS = [1, 2, 3]


def blank(value):
    """`value` with its wall-clock fields replaced by a marker, recursively."""
    if isinstance(value, dict):
        return {k: ("<wall clock>" if k in VOLATILE else blank(v)) for k, v in value.items()}
    if isinstance(value, list):
        return [blank(v) for v in value]
    return value


def normalised(text):
    """JSON text with wall-clock fields blanked (one document, or one per line); other text as is."""
    try:
        return json.dumps(blank(json.loads(text)), indent=1, sort_keys=True)
    except ValueError:
        pass
    lines = []
    for line in text.splitlines():
        try:
            lines.append(json.dumps(blank(json.loads(line)), sort_keys=True))
        except ValueError:
            lines.append(line)
    return "\n".join(lines)


# The demo's narrative states its wall time ("Wrote 5 files to DIR in 3.2 s").
WALL_TIME = re.compile(r"\bin \d+(\.\d+)? s\b")


def run(binary, args, cwd):
    done = subprocess.run([binary, *args], cwd=cwd, capture_output=True, text=True, timeout=600)
    return f"exit {done.returncode}\n{WALL_TIME.sub('in <wall clock> s', normalised(done.stdout))}"


def corpus_files(dirs):
    files = []
    for directory in dirs:
        for path in sorted(Path(directory).rglob("*")):
            if path.is_file() and path.suffix.lower() in SUFFIXES:
                files.append(path.resolve())
    return files


def outputs(binary, files, work):
    """Every output of `binary`, by a name that says which command made it."""
    work.mkdir(parents=True, exist_ok=True)
    out = {}
    for path in files:
        out[f"eds check {path}"] = run(binary, ["eds", "check", "--format", "json", str(path)], work)
    demo = work / "demo"
    out["demo (exit and stdout)"] = run(binary, ["demo", "--dir", str(demo)], work).replace(str(work), "<work>")
    eds = None
    for report in sorted(demo.glob("*.json")):
        out[f"demo report {report.name}"] = normalised(report.read_text())
    for candidate in sorted(demo.glob("*.eds")):
        eds = candidate
    if eds is None:
        sys.exit(f"{binary}: the demo wrote no EDS into {demo}")
    for models in MBT_RUNS:
        for seed in SEEDS:
            args = ["mbt", "run", *models, "--sim", str(eds), "--node", "5", "--seed", str(seed),
                    "--steps", "2000", "--format", "json"]
            out[f"mbt run {' '.join(models)} seed {seed}"] = run(binary, args, work).replace(str(work), "<work>")
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--corpus", action="append", help="corpus directory (repeatable)")
    parser.add_argument("--work", help="keep the scratch output here")
    args = parser.parse_args()
    dirs = args.corpus or [d for d in (ROOT / "corpus", ROOT.parent / "shared" / "corpus") if d.is_dir()]
    files = corpus_files(dirs)
    with tempfile.TemporaryDirectory() as scratch:
        work = Path(args.work) if args.work else Path(scratch)
        before = outputs(os.path.abspath(args.before), files, work / "before")
        after = outputs(os.path.abspath(args.after), files, work / "after")
    differ = [name for name in before if before[name] != after.get(name)]
    differ += [name for name in after if name not in before]
    for name in differ:
        print(f"differs: {name}")
    kinds = {
        "eds check": sum(1 for n in before if n.startswith("eds check")),
        "demo": sum(1 for n in before if n.startswith("demo")),
        "mbt run": sum(1 for n in before if n.startswith("mbt run")),
    }
    print(f"{len(before)} outputs compared ({', '.join(f'{k}: {v}' for k, v in kinds.items())}); "
          f"{len(differ)} differ")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
