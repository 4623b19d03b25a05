#!/usr/bin/env python3
"""Prints the tables of docs/conformance.md that map canopener's CiA 301 tests to CCT cases.

Usage: canopener test --list --format json | cct_coverage.py CCT_CASES_TXT

CCT_CASES_TXT is the CCT 3.0.3.10 case list (../shared/reference/cct-3.0.3.10-test-cases.txt). Prints the
id -> CCT table, then how many CCT cases are covered, then the table of cases not covered yet.
"""

import json
import re
import sys


def main() -> None:
    tests = json.load(sys.stdin)
    cases = []
    with open(sys.argv[1], encoding="utf-8") as f:
        for line in f:
            m = re.match(r"\s*[\d.]+\s+-\s+Test name : ([^|]+)\|\s*(.*)", line)
            if m:
                cases.append((m.group(1).strip(), m.group(2).strip()))
    covered = set()
    print("| Id | Test | CCT case | CiA clauses |")
    print("|---|---|---|---|")
    for t in tests:
        cct = [r[4:] for r in t["references"] if r.startswith("CCT ")]
        cia = [r for r in t["references"] if not r.startswith("CCT ")]
        covered.update(cct)
        print(f"| `{t['id']}` | {t['title']} | {', '.join(cct) or '— (beyond the CCT)'} | {'; '.join(cia)} |")
    unknown = sorted(covered - {name for name, _ in cases})
    if unknown:
        sys.exit(f"references to CCT cases that do not exist: {unknown}")
    missing = [(name, what) for name, what in cases if name not in covered]
    print()
    print(f"{len(cases) - len(missing)} of {len(cases)} CCT cases covered, {len(missing)} not covered yet.")
    print()
    print("| CCT case | What it checks |")
    print("|---|---|")
    for name, what in missing:
        print(f"| {name} | {what[:110]} |")


if __name__ == "__main__":
    main()
