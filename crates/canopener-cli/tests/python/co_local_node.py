"""A python `canopen` LocalNode (a device built from an EDS) on a socketcand hub, as the device that canopener's
master commands talk to. It reports on stdout, as JSON lines, what it observed, so a test can check the effect of
a command on the device and not only the command's own output.

Usage: co_local_node.py HOST PORT CHANNEL NODE_ID EDS_PATH [--bare]

With --bare the peer adds nothing below: LocalNode exactly as python canopen ships it (no boot-up, its own
reaction to the NMT resets), so a test can show what LocalNode lacks by itself.

What python canopen 2.4.1's LocalNode does by itself: an SDO server (expedited and segmented; it answers a block
upload with a normal upload whatever the client's protocol switch threshold, and aborts a block download with
05040001h), values from its data store, the EDS's ParameterValue or DefaultValue (an entry with neither is
aborted with 060A0023h), and an NMT slave that follows start, stop and enter pre-operational, puts the new state
into its heartbeat and starts or stops the heartbeat when 1017h is written over SDO.
What it lacks and this peer adds, as a device application would:
- boot-up at start: INITIALISING (boot-up message 700h+ID, 00h) then PRE-OPERATIONAL, heartbeat from 1017h;
- NMT reset node / reset communication (CiA 301 §7.2.8.3.1): LocalNode only sets its state to INITIALISING and
  keeps sending heartbeats of 00h. The peer resets the objects (reset node: every value written; reset
  communication: those of 1000h..1FFFh), sends one boot-up message and enters PRE-OPERATIONAL, with the
  heartbeat 1017h now holds (the EDS default after the reset);
- the error register 1001h = 00h (mandatory in CiA 301; the EDS may give it no default).

Events on stdout (one JSON object per line):
  {"ready": true, "node_id": N}                                    connected and booted
  {"event": "write", "index": I, "sub": S, "hex": "..", "value": V}   an SDO download, before it is confirmed
  {"event": "nmt", "command": CS, "target": T, "state": "..", "reset": "node"|"communication"|null}
  {"event": "client_abort", "index": I, "sub": S, "code": C}       an abort the client sent
  {"event": "dcf", ...}                                            answer to the stdin line "dcf PATH"
  {"done": true, "sdo_requests": N, "block_requests": N}           when stdin closes
Stdin: "dcf PATH" loads PATH with python canopen's own EDS/DCF reader and compares every ParameterValue in it
with the value this device holds; end of input stops the peer.
"""

import json
import logging
import struct
import sys
import threading

import canopen
from canopen import objectdictionary as od
from canopen.sdo.exceptions import SdoAbortedError

logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)
# LocalNode logs the block download it refuses as an error; the test provokes it on purpose.
logging.getLogger("canopen").setLevel(logging.CRITICAL)

NMT_RESET_NODE = 0x81
NMT_RESET_COMMUNICATION = 0x82
# The device application's values, set again after every reset.
APPLICATION_VALUES = {(0x1001, 0): b"\x00"}

print_lock = threading.Lock()


def emit(obj) -> None:
    with print_lock:
        print(json.dumps(obj), flush=True)


def jsonable(value):
    if isinstance(value, (bytes, bytearray)):
        return bytes(value).hex()
    return value


class Peer:
    def __init__(self, node: canopen.LocalNode) -> None:
        self.node = node
        self.sdo_requests = 0
        self.block_requests = 0

    def apply_application_values(self) -> None:
        for (index, sub), data in APPLICATION_VALUES.items():
            self.node.data_store.setdefault(index, {})[sub] = data

    def boot(self) -> None:
        """INITIALISING sends the boot-up message; INITIALISING -> PRE-OPERATIONAL starts the heartbeat (1017h)."""
        self.node.nmt.state = "INITIALISING"
        self.node.nmt.state = "PRE-OPERATIONAL"

    def on_write(self, index, subindex, data, **kwargs) -> None:
        """LocalNode calls this with the entry as `od` before it stores a write (and before it answers)."""
        try:
            value = kwargs["od"].decode_raw(data)
        except Exception:  # a value of the wrong length still gets reported
            value = None
        emit({"event": "write", "index": index, "sub": subindex, "hex": bytes(data).hex(), "value": jsonable(value)})

    def on_sdo_request(self, can_id, data, timestamp) -> None:
        self.sdo_requests += 1
        if not data:
            return
        ccs = data[0] >> 5
        if ccs in (5, 6):
            self.block_requests += 1
        if ccs == 4 and len(data) >= 8:
            index, sub, code = struct.unpack_from("<HBL", data, 1)
            emit({"event": "client_abort", "index": index, "sub": sub, "code": code})

    def on_nmt(self, can_id, data, timestamp) -> None:
        """Replaces LocalNode's own NMT handler, which it calls for everything but the resets."""
        if len(data) < 2:
            return
        command, target = data[0], data[1]
        if target not in (0, self.node.id):
            return
        reset = None
        if command in (NMT_RESET_NODE, NMT_RESET_COMMUNICATION):
            self.node.nmt.stop_heartbeat()
            if command == NMT_RESET_NODE:
                reset = "node"
                self.node.data_store.clear()
            else:
                reset = "communication"
                for index in [index for index in self.node.data_store if 0x1000 <= index <= 0x1FFF]:
                    del self.node.data_store[index]
            self.apply_application_values()
            self.boot()
        else:
            self.node.nmt.on_command(can_id, data, timestamp)
        emit({"event": "nmt", "command": command, "target": target, "state": self.node.nmt.state, "reset": reset})

    def compare_dcf(self, path: str) -> dict:
        """Every entry of the DCF (read by python canopen) against the value this device holds."""
        try:
            dcf = od.import_od(path, self.node.id)
        except Exception as exc:
            return {"event": "dcf", "loaded": False, "error": f"{type(exc).__name__}: {exc}"}
        compared, equal = 0, 0
        mismatches, dcf_without_value, device_without_value = [], [], []
        for obj in dcf.values():
            variables = [obj] if isinstance(obj, od.ODVariable) else list(obj.values())
            for var in variables:
                if not var.readable:
                    continue
                name = f"{var.index:04X}:{var.subindex:02X}"
                try:
                    held = self.node.get_data(var.index, var.subindex)
                except SdoAbortedError as exc:
                    held, abort = None, exc.code
                except Exception as exc:  # an entry the device does not have at all
                    held, abort = None, str(exc)
                if var.value is None:
                    if held is not None:
                        dcf_without_value.append(name)
                    continue
                if held is None:
                    device_without_value.append({"entry": name, "dcf": jsonable(var.value), "abort": abort})
                    continue
                compared += 1
                mine = self.node.object_dictionary[var.index]
                if not isinstance(mine, od.ODVariable):
                    mine = mine[var.subindex]
                device_value = mine.decode_raw(held)
                if device_value == var.value:
                    equal += 1
                else:
                    mismatches.append({"entry": name, "dcf": jsonable(var.value), "device": jsonable(device_value)})
        return {
            "event": "dcf",
            "loaded": True,
            "compared": compared,
            "equal": equal,
            "mismatches": mismatches,
            "dcf_without_value": dcf_without_value,
            "device_without_value": device_without_value,
        }


def main() -> int:
    host, port, channel = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    node_id, eds = int(sys.argv[4], 0), sys.argv[5]
    network = canopen.Network()
    network.connect(interface="socketcand", host=host, port=port, channel=channel, tcp_tune=True)
    node = canopen.LocalNode(node_id, eds)
    network.add_node(node)
    peer = Peer(node)
    bare = sys.argv[6:] == ["--bare"]
    if not bare:
        network.unsubscribe(0, node.nmt.on_command)
        network.subscribe(0, peer.on_nmt)
    network.subscribe(0x600 + node_id, peer.on_sdo_request)
    node.add_write_callback(peer.on_write)
    if not bare:
        peer.apply_application_values()
        peer.boot()
    emit({"ready": True, "node_id": node_id})
    for line in sys.stdin:
        words = line.split(maxsplit=1)
        if words and words[0] == "dcf" and len(words) == 2:
            emit(peer.compare_dcf(words[1].strip()))
        elif words:
            emit({"event": "error", "error": f"unknown command {line.strip()!r}"})
    node.nmt.stop_heartbeat()
    network.disconnect()
    emit({"done": True, "sdo_requests": peer.sdo_requests, "block_requests": peer.block_requests})
    return 0


if __name__ == "__main__":
    sys.exit(main())
