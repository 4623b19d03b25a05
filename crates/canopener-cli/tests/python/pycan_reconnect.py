"""Connects to a socketcand hub COUNT times with python-can's client and counts failed handshakes.

Usage: pycan_reconnect.py HOST PORT CHANNEL COUNT

python-can reads each handshake reply with one recv(256) and demands it be exactly "< hi >" / "< ok >", so a hub
that lets bus traffic follow the rawmode "< ok >" too early makes it raise CanError. Each connection also reads a
few frames of the (flooded) bus before it disconnects, proving traffic flows after the handshake.
Prints one JSON object: attempts, failures, errors (first few), frames_seen.
"""

import json
import logging
import sys

import can

logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)


def main() -> int:
    host, port, channel, count = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
    failures = 0
    errors = []
    frames_seen = 0
    connections_with_traffic = 0
    for _ in range(count):
        try:
            bus = can.Bus(interface="socketcand", host=host, port=port, channel=channel)
        except Exception as exc:
            failures += 1
            if len(errors) < 5:
                errors.append(repr(exc))
            continue
        seen_here = 0
        try:
            for _ in range(3):
                msg = bus.recv(timeout=2.0)
                if msg is not None and not msg.is_error_frame:
                    seen_here += 1
        finally:
            bus.shutdown()
        frames_seen += seen_here
        connections_with_traffic += seen_here > 0
    print(json.dumps({
        "attempts": count,
        "failures": failures,
        "errors": errors,
        "frames_seen": frames_seen,
        "connections_with_traffic": connections_with_traffic,
    }), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
