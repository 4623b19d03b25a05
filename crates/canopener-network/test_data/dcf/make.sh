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
# The paper's example (paper/Nodelist.graphml) names its DCFs as the iCC 2012 paper does.
cp "$out/node2.dcf" "$out/../paper/EDS/demo_plc.dcf"
cp "$out/node3.dcf" "$out/../paper/EDS/demodeva.dcf"
cp "$out/node4.dcf" "$out/../paper/EDS/demodevb.dcf"
cp "$out/node6.dcf" "$out/../paper/EDS/demodevb2.dcf"
cp "$out/node5.dcf" "$out/../paper/EDS/demodevd.dcf"
