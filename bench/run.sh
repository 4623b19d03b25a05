#!/usr/bin/env bash
# Benchmark suite (cargo xtask bench): release builds, then one script per part of BENCHMARKS.md, each writing its
# raw results (bench-results/*.json) and its tables (bench-results/*.md) that the section of BENCHMARKS.md it
# names is pasted from: the can_limits example the physical CAN limits (can_limits.md), bench/run.py the hub sections (hub.md), bench/eds_load.py EDS loading against python
# canopen, bench/eds_check.py checking the corpus against python canopen importing it, bench/check_scaling.py how
# `eds check` scales with file size, bench/xdd_check.py `eds check` on XDD against reading it, bench/sdo_server.py,
# bench/sdo_client.py and bench/master_cli.py the device's SDO server, the SDO client and the master commands
# (node scan, LSS fastscan), bench/criterion_tables.py the criterion micro-benchmarks (criterion.md).
set -euo pipefail
cd "$(dirname "$0")/.."
python="${CANOPENER_PYTHON:-.venv/bin/python}"
cargo build --release --locked -p canopener-cli --bin canopener
cargo build --release --locked -p canopener-hub --example hub_load
cargo build --release --locked -p canopener-eds --example load_timing
cargo build --release --locked -p canopener-check --example check_timing
cargo build --release --locked -p canopener-description --example xdd_check_timing
mkdir -p bench-results
cargo run --release --locked -q -p canopener-can --example can_limits > bench-results/can_limits.md
"$python" bench/run.py "$@"
"$python" bench/eds_load.py "$@"
"$python" bench/eds_check.py "$@"
"$python" bench/check_scaling.py "$@"
"$python" bench/xdd_check.py "$@"
"$python" bench/sdo_server.py "$@"
"$python" bench/sdo_client.py "$@"
"$python" bench/master_cli.py "$@"
"$python" bench/criterion_tables.py "$@"
