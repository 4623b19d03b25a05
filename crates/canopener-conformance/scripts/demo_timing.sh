#!/usr/bin/env bash
# Prints how long `canopener demo` (the product tour: EDS check, every suite against the bundled CiA 401
# device clean and with a fault, four reports written) takes on the wall clock, five runs, with the load
# average of the host, and the bus time and verdicts of each run of the tour.
# Usage: demo_timing.sh [CANOPENER_BINARY]   (default: target/release/canopener; `cargo build --release` first)
set -euo pipefail
root="$(cd "$(dirname "$0")/../../.." && pwd)"
bin="${1:-${CARGO_TARGET_DIR:-$root/target}/release/canopener}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
echo "host load average: $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) cores"
for run in 1 2 3 4 5; do
    start=$(date +%s.%N)
    "$bin" demo --dir "$work/tour" --format json > "$work/summary.json"
    end=$(date +%s.%N)
    python3 - "$work/summary.json" "$run" "$start" "$end" <<'PY'
import json, sys
summary = json.load(open(sys.argv[1]))
wall = float(sys.argv[4]) - float(sys.argv[3])
runs = "; ".join(
    f"{r['fault'] or 'clean'}: {r['summary']['pass']} pass {r['summary']['fail']} fail "
    f"{r['summary']['inconclusive']} inconclusive {r['summary']['not_applicable']} n/a, {r['bus_time_s']:.1f} s bus time"
    for r in summary["runs"]
)
print(f"run {sys.argv[2]}: {wall:.2f} s wall ({runs})")
PY
done
