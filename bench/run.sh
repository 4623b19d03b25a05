#!/usr/bin/env bash
# Benchmark suite (cargo xtask bench): release builds, then bench/run.py measures everything in one run and
# writes bench-results/results.json plus the markdown tables for BENCHMARKS.md; bench/eds_load.py then times
# EDS loading against python canopen (bench-results/eds_load.md and .json), and bench/eds_check.py times
# checking the corpus against python canopen importing it (bench-results/eds_check.md and .json);
# bench/sdo_server.py, bench/sdo_client.py and bench/master_cli.py time the device's SDO server, the SDO client
# and the master commands (node scan, LSS fastscan) against the wire and python canopen (bench-results/*.md).
set -euo pipefail
cd "$(dirname "$0")/.."
python="${CANOPENER_PYTHON:-.venv/bin/python}"
cargo build --release --locked -p canopener-cli --bin canopener
cargo build --release --locked -p canopener-hub --example hub_load
cargo build --release --locked -p canopener-eds --example load_timing
cargo build --release --locked -p canopener-check --example check_timing
mkdir -p bench-results
"$python" bench/run.py "$@"
"$python" bench/eds_load.py "$@"
"$python" bench/eds_check.py "$@"
"$python" bench/check_scaling.py "$@"
"$python" bench/sdo_server.py "$@"
"$python" bench/sdo_client.py "$@"
"$python" bench/master_cli.py "$@"
