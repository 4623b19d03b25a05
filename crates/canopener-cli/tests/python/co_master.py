"""A python `canopen` RemoteNode (master side) exercising NMT and SDO against a device through a socketcand hub.

Usage: co_master.py HOST PORT CHANNEL NODE_ID EDS_PATH [EXPEDITED_ROUNDS]

Prints {"ready": true} once connected and listening; on the stdin line "go" it runs the checks and prints one JSON
object: {"checks": {name: {"ok": bool, "detail": str}}, "timing": {...}}.
"""

import json
import logging
import statistics
import sys
import threading
import time

import canopen
from canopen.sdo.exceptions import SdoAbortedError

logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)

STATE_NAMES = {0x00: "BOOT-UP", 0x04: "STOPPED", 0x05: "OPERATIONAL", 0x7F: "PRE-OPERATIONAL"}


class HeartbeatWatch:
    """Records every NMT error-control frame of one node, so boot-up is never missed."""

    def __init__(self) -> None:
        self.states = []
        self.cond = threading.Condition()

    def on_frame(self, can_id, data, timestamp) -> None:
        with self.cond:
            self.states.append(data[0] if len(data) else None)
            self.cond.notify_all()

    def wait_for(self, state: int, timeout: float) -> bool:
        """Waits for a heartbeat with `state` that arrives after this call."""
        deadline = time.monotonic() + timeout
        with self.cond:
            start = len(self.states)
            while True:
                if state in self.states[start:]:
                    return True
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return False
                self.cond.wait(remaining)


def main() -> int:
    host, port, channel = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    node_id, eds = int(sys.argv[4], 0), sys.argv[5]
    rounds = int(sys.argv[6]) if len(sys.argv) > 6 else 200
    network = canopen.Network()
    network.connect(interface="socketcand", host=host, port=port, channel=channel)
    node = canopen.RemoteNode(node_id, eds)
    network.add_node(node)
    node.sdo.RESPONSE_TIMEOUT = 2.0
    watch = HeartbeatWatch()
    network.subscribe(0x700 + node_id, watch.on_frame)
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

    def bootup():
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and 0x00 not in watch.states:
            time.sleep(0.01)
        return 0x00 in watch.states, f"states seen: {[STATE_NAMES.get(s, s) for s in watch.states[:5]]}"

    check("boot-up received", bootup)
    check("heartbeat PRE-OPERATIONAL", lambda: (watch.wait_for(0x7F, 3), "after boot"))

    def nmt(command, state):
        node.nmt.state = command
        return watch.wait_for(state, 3), f"NMT {command} -> heartbeat {STATE_NAMES[state]}"

    check("NMT start", lambda: nmt("OPERATIONAL", 0x05))
    check("NMT stop", lambda: nmt("STOPPED", 0x04))
    check("NMT enter pre-operational", lambda: nmt("PRE-OPERATIONAL", 0x7F))

    check("SDO expedited upload 1017h", lambda: (node.sdo[0x1017].raw == 100, node.sdo[0x1017].raw))

    def expedited_download():
        node.sdo[0x2004].raw = -123456
        value = node.sdo[0x2004].raw
        return value == -123456, value

    check("SDO expedited download+upload 2004h", expedited_download)
    check("SDO segmented upload 1008h",
          lambda: (node.sdo[0x1008].raw == "TEST DEVICE", node.sdo[0x1008].raw))

    text = "".join(chr(0x41 + (i % 26)) for i in range(889))

    def segmented_download():
        node.sdo[0x2000].raw = text
        back = node.sdo[0x2000].raw
        return back == text, f"{len(back)} bytes read back"

    check("SDO segmented download+upload 2000h (889 bytes)", segmented_download)

    def abort():
        try:
            node.sdo.upload(0x5FFF, 0)
        except SdoAbortedError as exc:
            return exc.code == 0x06020000, f"abort code {exc.code:#010x}"
        return False, "no abort"

    check("SDO abort for a missing object", abort)

    timings = []
    for _ in range(rounds):
        start = time.perf_counter()
        node.sdo.upload(0x1017, 0)
        timings.append(time.perf_counter() - start)
    timings.sort()
    start = time.perf_counter()
    node.sdo[0x2000].raw = text
    seg_download = time.perf_counter() - start
    start = time.perf_counter()
    _ = node.sdo[0x2000].raw
    seg_upload = time.perf_counter() - start

    network.disconnect()
    print(json.dumps({
        "checks": checks,
        "timing": {
            "expedited_upload_rounds": rounds,
            "expedited_upload_median_ms": round(statistics.median(timings) * 1e3, 3),
            "expedited_upload_p99_ms": round(timings[int(0.99 * (len(timings) - 1))] * 1e3, 3),
            "expedited_transfers_per_s": round(len(timings) / sum(timings), 1),
            "segmented_889_download_ms": round(seg_download * 1e3, 2),
            "segmented_889_upload_ms": round(seg_upload * 1e3, 2),
        },
    }), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
