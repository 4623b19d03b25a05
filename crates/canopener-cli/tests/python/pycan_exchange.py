"""A python-can peer that exchanges numbered frames with another peer through a socketcand hub.

Usage: pycan_exchange.py HOST PORT CHANNEL SEND_ID RECV_ID COUNT

Protocol with the test driver (stdin/stdout, one JSON object per line):
  1. connect (python-can's own socketcand client and handshake), print {"ready": true}
  2. wait for a line "go" on stdin, so that both peers are connected before either sends
  3. a thread sends COUNT frames with id SEND_ID whose first 4 bytes are the sequence number (little endian)
     and last 4 bytes a pattern derived from it; the main thread receives until COUNT frames with id RECV_ID
     arrived or nothing arrived for 20 s
  4. print a result object: received, in_order, duplicates, corrupt, missing, elapsed_s
"""

import json
import logging
import struct
import sys
import threading
import time

import can

# python-can logs a warning every time a TCP read splits an element; that is expected under load.
logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)


def payload(seq: int) -> bytes:
    return struct.pack("<II", seq, (seq * 2654435761) & 0xFFFFFFFF)


def main() -> int:
    host, port, channel = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    send_id, recv_id, count = int(sys.argv[4], 0), int(sys.argv[5], 0), int(sys.argv[6])
    bus = can.Bus(interface="socketcand", host=host, port=port, channel=channel)
    print(json.dumps({"ready": True}), flush=True)
    if sys.stdin.readline().strip() != "go":
        print(json.dumps({"error": "driver did not say go"}), flush=True)
        return 2

    send_error = []

    def sender() -> None:
        try:
            for seq in range(count):
                bus.send(can.Message(arbitration_id=send_id, is_extended_id=False, data=payload(seq)))
        except Exception as exc:  # reported in the result, not swallowed
            send_error.append(repr(exc))

    started = time.monotonic()
    thread = threading.Thread(target=sender)
    thread.start()

    expected = 0
    received = duplicates = corrupt = out_of_order = 0
    last_rx = time.monotonic()
    while received < count and time.monotonic() - last_rx < 20.0:
        msg = bus.recv(timeout=1.0)
        if msg is None or msg.arbitration_id != recv_id or msg.is_error_frame:
            continue
        last_rx = time.monotonic()
        if len(msg.data) != 8:
            corrupt += 1
            continue
        seq = struct.unpack("<I", bytes(msg.data[:4]))[0]
        if bytes(msg.data) != payload(seq):
            corrupt += 1
        elif seq < expected:
            duplicates += 1
        else:
            if seq != expected:
                out_of_order += 1
            expected = seq + 1
            received += 1
    elapsed = time.monotonic() - started
    thread.join()
    bus.shutdown()
    print(json.dumps({
        "received": received,
        "missing": count - received,
        "out_of_order": out_of_order,
        "duplicates": duplicates,
        "corrupt": corrupt,
        "send_error": send_error,
        "elapsed_s": round(elapsed, 3),
    }), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
