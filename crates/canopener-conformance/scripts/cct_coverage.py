#!/usr/bin/env python3
"""Prints the tables of docs/conformance.md that map canopener's CiA 301 tests to CCT cases.

Usage: canopener test --list --format json | cct_coverage.py CCT_CASES_TXT

CCT_CASES_TXT is the CCT 3.0.3.10 case list (../shared/reference/cct-3.0.3.10-test-cases.txt). The
coverage comes from the table each test carries in the list (`cct`: case, coverage, reading), which
is crates/canopener-conformance/src/cct.rs, not from counting references: a case is covered when a
test does what its name says, partial when a test checks a named part of it, different when
canopener deliberately reads it another way. Prints the id -> CCT table, the counts, and every case
that is partial or different, or whose name leaves the procedure open, with canopener's reading. Exits with an error when a case of the list
has no test, a test names a case the list does not have, the table and a test's references
disagree, or two tests give one case different coverages.
"""

import json
import re
import sys

MARK = {"covered": "", "partial": " (partial)", "different": " (different)"}


def main() -> None:
    tests = json.load(sys.stdin)
    cases = []
    with open(sys.argv[1], encoding="utf-8") as f:
        for line in f:
            m = re.match(r"\s*[\d.]+\s+-\s+Test name : ([^|]+)\|\s*(.*)", line)
            if m:
                cases.append((m.group(1).strip(), m.group(2).strip()))
    names = {name for name, _ in cases}
    coverage = {}
    readings = {}
    testers = {}
    problems = []
    print("| Id | Test | CCT case | CiA clauses |")
    print("|---|---|---|---|")
    for t in tests:
        referenced = {r[4:] for r in t["references"] if r.startswith("CCT ")}
        table = {c["case"]: c for c in t.get("cct", [])}
        if referenced != set(table):
            problems.append(f"{t['id']}: references {sorted(referenced)}, table {sorted(table)}")
        for name, c in table.items():
            if name not in names:
                problems.append(f"{t['id']}: no CCT case {name}")
            if coverage.setdefault(name, c["coverage"]) != c["coverage"]:
                problems.append(f"{name}: {coverage[name]} and {c['coverage']}")
            if c["reading"]:
                readings[name] = c["reading"]
            testers.setdefault(name, []).append(t["id"])
        cct = ", ".join(f"{name}{MARK[c['coverage']]}" for name, c in table.items())
        cia = "; ".join(r for r in t["references"] if not r.startswith("CCT "))
        print(f"| `{t['id']}` | {t['title']} | {cct or '— (beyond the CCT)'} | {cia} |")
    missing = [(name, what) for name, what in cases if name not in coverage]
    if problems:
        sys.exit("the coverage table disagrees:\n" + "\n".join(problems))
    counts = {kind: sum(1 for name, _ in cases if coverage.get(name) == kind) for kind in MARK}
    print()
    print(
        f"{len(cases)} CCT cases: {counts['covered']} covered, {counts['partial']} partial, "
        f"{counts['different']} different, {len(missing)} not covered."
    )
    print()
    print("| CCT case | Coverage | Tests | canopener's reading |")
    print("|---|---|---|---|")
    for name, _ in cases:
        kind = coverage.get(name)
        if kind in ("partial", "different") or readings.get(name):
            tested = ", ".join(f"`{i.removeprefix('cia301.')}`" for i in testers[name])
            print(f"| {name} | {kind} | {tested} | {readings.get(name, '')} |")
    if missing:
        print()
        print("| CCT case not covered | What it checks |")
        print("|---|---|")
        for name, what in missing:
            print(f"| {name} | {what[:110]} |")


if __name__ == "__main__":
    main()
