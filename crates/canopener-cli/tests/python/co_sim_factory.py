"""A python `canopen` master runs the CiA 401 factory test round trip against `canopener sim` through a hub.

Usage: co_sim_factory.py HOST PORT CHANNEL NODE_ID

The device is simulated from a CiA 401 EDS (1000h bits 15..0 = 0191h, 6000h, TPDO1 mapping 6000h on event)
with no `--app`: a device described as a CiA 401 module must act as one. The master starts it, switches the
factory test on (2000h = 1), sets the test input pattern (2001h = F0h) and expects the digital inputs 6000h:01
to read F0h over SDO and TPDO1 to carry the change (CiA 401: 6000h mapped in TPDO1, sent on a change of input).
The master holds no dictionary of the device: python canopen cannot import this EDS (its empty
VendorNumber= fails int()), and the transfers name every object by index and sub-index, as a bench script does.

Prints {"ready": true} once connected; on the stdin line "go" it runs the checks and prints one JSON object:
{"checks": {name: {"ok": bool, "detail": str}}}. Every wait is bounded.
"""

import argparse
import json
import logging
import sys
import threading
import time

import canopen

logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)
logging.getLogger("canopen").setLevel(logging.CRITICAL)


class Frames:
    """Every frame of one CAN-ID, so a TPDO between two waits is not lost."""

    def __init__(self) -> None:
        self.frames = []
        self.cond = threading.Condition()

    def on_frame(self, can_id, data, timestamp) -> None:
        with self.cond:
            self.frames.append(bytes(data))
            self.cond.notify_all()

    def mark(self) -> int:
        with self.cond:
            return len(self.frames)

    def wait_for(self, predicate, mark: int, timeout: float):
        deadline = time.monotonic() + timeout
        with self.cond:
            while True:
                for data in self.frames[mark:]:
                    if predicate(data):
                        return data
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return None
                self.cond.wait(remaining)

    def since(self, mark: int):
        with self.cond:
            return list(self.frames[mark:])


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("host")
    parser.add_argument("port", type=int)
    parser.add_argument("channel")
    parser.add_argument("node_id", type=lambda text: int(text, 0))
    args = parser.parse_args()

    network = canopen.Network()
    network.connect(interface="socketcand", host=args.host, port=args.port, channel=args.channel)
    node = canopen.RemoteNode(args.node_id, canopen.ObjectDictionary())
    network.add_node(node)
    node.sdo.RESPONSE_TIMEOUT = 2.0
    tpdo1 = Frames()
    network.subscribe(0x180 + args.node_id, tpdo1.on_frame)
    print(json.dumps({"ready": True}), flush=True)
    if sys.stdin.readline().strip() != "go":
        return 2

    checks = {}

    def check(name, fn):
        try:
            ok, detail = fn()
        except Exception as exc:  # a failed check is reported, never hidden
            ok, detail = False, repr(exc)
        checks[name] = {"ok": bool(ok), "detail": str(detail)}

    def device_type():
        value = int.from_bytes(node.sdo.upload(0x1000, 0), "little")
        return value & 0xFFFF == 0x0191, f"1000h = {value:08X}h"

    check("1000h says CiA 401", device_type)

    node.nmt.send_command(0x01)
    # NMT has no answer; give the device time to enter Operational before the inputs change.
    time.sleep(0.5)

    def factory_round_trip():
        mark = tpdo1.mark()
        node.sdo.download(0x2000, 0, bytes([1]))
        node.sdo.download(0x2001, 0, bytes([0xF0]))
        inputs = node.sdo.upload(0x6000, 1)
        sent = tpdo1.wait_for(lambda data: len(data) >= 1 and data[0] == 0xF0, mark, 3.0)
        seen = [data.hex() for data in tpdo1.since(mark)]
        ok = inputs == bytes([0xF0]) and sent is not None
        return ok, f"6000h:01 = {inputs.hex()}, TPDO1 frames after the writes: {seen}"

    check("factory test 2000h = 1, 2001h = F0h -> 6000h:01 = F0h and TPDO1", factory_round_trip)

    def back_to_terminals():
        mark = tpdo1.mark()
        node.sdo.download(0x2001, 0, bytes([0x0F]))
        sent = tpdo1.wait_for(lambda data: len(data) >= 1 and data[0] == 0x0F, mark, 3.0)
        inputs = node.sdo.upload(0x6000, 1)
        return inputs == bytes([0x0F]) and sent is not None, f"6000h:01 = {inputs.hex()}"

    check("a second pattern 2001h = 0Fh follows", back_to_terminals)

    print(json.dumps({"checks": checks}), flush=True)
    network.disconnect()
    return 0


if __name__ == "__main__":
    sys.exit(main())
