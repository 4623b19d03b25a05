#!/usr/bin/env bash
# Beyond the 2^7 matrix of docs/mbt.md: the thirteen CANopen models (the seven and the six added
# by issue 23) composed as every pair, every set of twelve (one left out) and all thirteen, on the
# composition matrix's six corpus devices, 5 seeds x 2000 steps each, on virtual time. Prints a
# Markdown table (pass counts per composition size) and every run that did not pass.
# Usage: tools/mbt_thirteen.sh [path/to/canopener]   (default: target/release/canopener)
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-target/release/canopener}"
models=(nmt sdo sync lss emcy guarding heartbeat sdo-block sdo-download pdo store lss-config life-guarding)
devices=(
  CANopenNode__CANopenNode__example__IO.eds
  CANopenNode__CANopenDemo__demo__demoDevice.eds
  YamamotoSoya__maxon_epos4compact50-5can_ros2__maxon_epos4_ros2__config__bus_config_cia402_epos4_pos__maxon_epos4_0x1018.eds
  iota2__CANopen-tools-suite__eds_files__sample_node_0x01.eds
  christiansandberg__canopen__test__sample.eds
  Daxbot__node-canopen__examples__eds__example.eds
)
comps=()
n=${#models[@]}
for ((i = 0; i < n; i++)); do
  for ((j = i + 1; j < n; j++)); do comps+=("pairs|${models[i]} ${models[j]}"); done
done
for ((i = 0; i < n; i++)); do
  rest=()
  for ((j = 0; j < n; j++)); do [[ $j -ne $i ]] && rest+=("${models[j]}"); done
  comps+=("twelve|${rest[*]}")
done
comps+=("thirteen|${models[*]}")
declare -A total pass
failures=""
start=$SECONDS
for entry in "${comps[@]}"; do
  kind="${entry%%|*}"
  set_="${entry#*|}"
  for d in "${devices[@]}"; do
    # shellcheck disable=SC2086
    out=$("$bin" mbt run $set_ --sim "corpus/eds/$d" --node 5 --steps 2000 --seeds 1..5 --format json || true)
    p=$(printf '%s' "$out" | python3 -c 'import json,sys; print(json.load(sys.stdin)["summary"]["pass"])')
    total[$kind]=$(( ${total[$kind]:-0} + 5 ))
    pass[$kind]=$(( ${pass[$kind]:-0} + p ))
    if [[ $p -ne 5 ]]; then
      failures+=$(printf '%s' "$out" | python3 -c '
import json,sys
r=json.load(sys.stdin)
for s in r["seeds"]:
    if s["verdict"]!="pass": print("* `%s` on %s, seed %s: %s: %s" % (sys.argv[1], sys.argv[2], s["seed"], s["verdict"], s.get("reason","")))
' "$set_" "$d")$'\n'
    fi
  done
done
echo "| compositions | how many | devices | seeds x steps | runs passing |"
echo "|---|---|---|---|---|"
echo "| every pair of the thirteen | 78 | 6 | 5 x 2000 | ${pass[pairs]}/${total[pairs]} |"
echo "| every twelve (one left out) | 13 | 6 | 5 x 2000 | ${pass[twelve]}/${total[twelve]} |"
echo "| all thirteen | 1 | 6 | 5 x 2000 | ${pass[thirteen]}/${total[thirteen]} |"
echo
if [[ -n "$failures" ]]; then echo "Runs that did not pass:"; echo; printf '%s' "$failures"; else echo "Every run passed."; fi
echo
echo "Wall time $(( SECONDS - start )) s ($(nproc) cores, shared with whatever else ran)."
