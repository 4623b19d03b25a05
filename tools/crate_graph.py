#!/usr/bin/env python3
"""The workspace's crate graph as `cargo metadata` gives it, with each crate's non-test line count.

    tools/crate_graph.py [WORKSPACE_DIR]

One line per workspace crate: its name, the lines of its `src/` that are not tests, and the workspace
crates it depends on (normal and build dependencies; dev-dependencies are tests). A file's test lines
are everything from its first `#[cfg(test)]` on (the house style puts tests last) and files under a
`tests` directory of `src/`. Run it on two checkouts to compare a refactoring's before and after.
"""

import json
import subprocess
import sys
from pathlib import Path


def non_test_lines(src: Path) -> int:
    total = 0
    for path in src.rglob("*.rs"):
        if "tests" in path.relative_to(src).parts:
            continue
        for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
            if line.strip().startswith("#[cfg(test)]"):
                break
            total += 1
    return total


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    meta = json.loads(subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--no-deps"],
        cwd=root, capture_output=True, text=True, check=True).stdout)
    members = {p["name"]: p for p in meta["packages"] if p["id"] in meta["workspace_members"]}
    total = 0
    for name in sorted(members):
        package = members[name]
        deps = sorted({d["name"] for d in package["dependencies"]
                       if d["name"] in members and d.get("kind") in (None, "build")})
        lines = non_test_lines(Path(package["manifest_path"]).parent / "src")
        total += lines
        print(f"{name:24} {lines:6}  -> {', '.join(d.removeprefix('canopener-') for d in deps) or '-'}")
    print(f"{len(members)} crates, {total} non-test lines")


if __name__ == "__main__":
    main()
