"""A python-can udp_multicast peer: answers each frame with id REQ_ID by the same data on id REQ_ID+1.

Usage: udp_echo.py GROUP PORT REQ_ID COUNT

Prints {"ready": true} once the bus is open, then {"echoed": N, "own_frames_seen": M} after COUNT requests or 20 s
of silence. python-can receives its own frames on udp_multicast, so they are counted, not answered.
"""

import json
import sys
import time

import can


def main() -> int:
    group, port, req_id, count = sys.argv[1], int(sys.argv[2]), int(sys.argv[3], 0), int(sys.argv[4])
    bus = can.Bus(interface="udp_multicast", channel=group, port=port)
    print(json.dumps({"ready": True}), flush=True)
    echoed = own = 0
    last = time.monotonic()
    while echoed < count and time.monotonic() - last < 20:
        msg = bus.recv(timeout=0.5)
        if msg is None:
            continue
        last = time.monotonic()
        if msg.arbitration_id == req_id + 1:
            own += 1
        elif msg.arbitration_id == req_id and not msg.is_extended_id:
            bus.send(can.Message(arbitration_id=req_id + 1, is_extended_id=False, data=msg.data))
            echoed += 1
            # Pace replies: an unpaced burst overruns the receiver's socket buffer (reference §1).
            time.sleep(0.0005)
    time.sleep(0.2)
    bus.shutdown()
    print(json.dumps({"echoed": echoed, "own_frames_seen": own}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
