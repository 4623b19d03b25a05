"""python-can round-trip latency through a socketcand hub: one process pings, the other echoes.

Usage: pycan_ping.py echo|ping HOST PORT CHANNEL SAMPLES

Both print {"ready": true} after connecting and wait for "go" on stdin. `ping` sends id 0x301 with a sequence
number and waits for the echo on 0x302, SAMPLES times, then prints {"samples", "median_us", "p90_us", "p99_us",
"max_us", "round_trips_per_s"}. `echo` answers 0x301 with 0x302 until it has echoed SAMPLES frames.
"""

import json
import logging
import struct
import sys
import time

import can

logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)


def main() -> int:
    mode, host, port, channel, samples = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], int(sys.argv[5])
    bus = can.Bus(interface="socketcand", host=host, port=port, channel=channel)
    print(json.dumps({"ready": True}), flush=True)
    if sys.stdin.readline().strip() != "go":
        return 2
    if mode == "echo":
        echoed = 0
        while echoed < samples:
            msg = bus.recv(timeout=10)
            if msg is None:
                break
            if msg.arbitration_id == 0x301:
                bus.send(can.Message(arbitration_id=0x302, is_extended_id=False, data=msg.data))
                echoed += 1
        bus.shutdown()
        print(json.dumps({"echoed": echoed}), flush=True)
        return 0
    rtts = []
    started = time.perf_counter()
    for seq in range(samples):
        sent_at = time.perf_counter()
        bus.send(can.Message(arbitration_id=0x301, is_extended_id=False, data=struct.pack("<Q", seq)))
        while True:
            msg = bus.recv(timeout=5)
            if msg is None:
                print(json.dumps({"error": f"no echo for sample {seq}"}), flush=True)
                return 1
            if msg.arbitration_id == 0x302 and struct.unpack("<Q", bytes(msg.data))[0] == seq:
                break
        rtts.append(time.perf_counter() - sent_at)
    total = time.perf_counter() - started
    bus.shutdown()
    rtts.sort()

    def pct(p):
        return round(rtts[min(len(rtts) - 1, int(p * len(rtts)))] * 1e6, 1)

    print(json.dumps({
        "samples": samples,
        "median_us": pct(0.5),
        "p90_us": pct(0.9),
        "p99_us": pct(0.99),
        "max_us": round(rtts[-1] * 1e6, 1),
        "round_trips_per_s": round(samples / total, 1),
    }), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
