#!/bin/sh
# Regenerates the DCFs the network fixtures name: heartbeat-device.eds (producer heartbeat
# 1017h = 100 ms) commissioned for node-IDs 1 to 24 at 250 kbit/s. Run from the workspace root with
# the canopener binary on PATH (or CANOPENER=path/to/canopener).
set -eu
canopener=${CANOPENER:-canopener}
src=crates/canopener-network/test_data/dcf/heartbeat-device.eds
out=crates/canopener-network/test_data/dcf
for id in $(seq 1 24); do
    "$canopener" eds convert "$src" --to dcf --node-id "$id" --bitrate 250 -o "$out/node$id.dcf.tmp"
    mv "$out/node$id.dcf.tmp" "$out/node$id.dcf"
done
