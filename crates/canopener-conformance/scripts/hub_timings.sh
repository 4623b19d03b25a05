#!/usr/bin/env bash
# Prints how long the CiA 301 suite takes on the wall clock against simulated devices through the hub,
# for the five clean vendored EDS files of tests/simulated.rs.
# Usage: hub_timings.sh [CANOPENER_BINARY]   (default: target/debug/canopener; build it first)
set -euo pipefail
root="$(cd "$(dirname "$0")/../../.." && pwd)"
bin="${1:-${CARGO_TARGET_DIR:-$root/target}/debug/canopener}"
port=29677
work="$(mktemp -d)"
"$bin" bus serve --listen "127.0.0.1:$port" > "$work/hub.log" 2>&1 &
hub=$!
trap 'kill $hub 2>/dev/null; rm -rf "$work"' EXIT
sleep 1
for eds in \
    CANopenNode__CANopenDemo__demo__demoDevice.eds \
    YamamotoSoya__maxon_epos4compact50-5can_ros2__maxon_epos4_ros2__config__bus_config_cia402_epos4_pos__maxon_epos4_0x1018.eds \
    ros-industrial__ros_canopen__canopen_chain_node__test__eds__ISD860.eds \
    ros-industrial__ros_canopen__ipa_canopen_test__config__PRL120.eds \
    ros-industrial__ros_canopen__ipa_canopen_test__config__Schunk_0_63.eds; do
    bus="socketcand://127.0.0.1:$port/$RANDOM"
    "$bin" sim "$root/corpus/eds/$eds" --node-id 5 --bus "$bus" > "$work/sim.log" 2>&1 &
    sim=$!
    sleep 1
    start=$(date +%s.%N)
    code=0
    # The cia313 performance suite judges the host's timing, not the device's: docs/conformance.md
    # (CiA 313) gives its own figures.
    "$bin" test --bus "$bus" --node 5 --eds "$root/corpus/eds/$eds" --skip cia313 --format json -o "$work/report.json" || code=$?
    end=$(date +%s.%N)
    kill $sim
    wait $sim 2>/dev/null || true
    python3 - "$work/report.json" "$eds" "$code" "$start" "$end" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
s = report["summary"]
wall = float(sys.argv[5]) - float(sys.argv[4])
failed = [f"{t['id']}: {t['reason']}" for t in report["tests"] if t["verdict"] in ("fail", "inconclusive")]
print(f"{sys.argv[2][:60]:60} exit {sys.argv[3]} wall {wall:5.1f} s: {s['pass']} pass, {s['fail']} fail, "
      f"{s['inconclusive']} inconclusive, {s['not_applicable']} n/a {failed}")
PY
done
