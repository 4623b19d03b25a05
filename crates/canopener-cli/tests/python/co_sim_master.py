"""A python `canopen` RemoteNode as the master of `canopener sim` (a CiA 401 I/O device) through a socketcand hub.

Usage: co_sim_master.py HOST PORT CHANNEL NODE_ID EDS_PATH [--rounds N] [--block-bytes N]
                        [--lss NEW_NODE_ID SERIAL]

The device runs with `--app cia401`, so besides the EDS's objects it has the CiA 401 process objects and the
factory test registers 2000h-2002h the simulator adds (CiA 401 §8 of the reference); this master adds the same
objects to its own copy of the dictionary, as a master that knows the device profile would.

With --lss, a second simulated device from the same EDS is on the bus LSS-unconfigured (node-ID FFh) with serial
number SERIAL; the master finds it with fastscan and gives it NEW_NODE_ID (CiA 305).

Prints {"ready": true} once connected and listening; on the stdin line "go" it runs the checks and prints one
JSON object: {"checks": {name: {"ok": bool, "detail": str}}, "timing": {...}}. Every wait is bounded, and once
the overall time budget is spent the remaining checks are reported as failed without talking to the bus, so a
dead device makes this script finish, not hang.
"""

import argparse
import json
import logging
import random
import statistics
import sys
import threading
import time

import can
import canopen
from canopen import objectdictionary as od
from canopen.lss import LssError
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)
# python canopen logs expected SDO timeouts (the stopped-node check) as errors; the checks report them.
logging.getLogger("canopen").setLevel(logging.CRITICAL)

STATE_NAMES = {0x00: "BOOT-UP", 0x04: "STOPPED", 0x05: "OPERATIONAL", 0x7F: "PRE-OPERATIONAL"}
# A node nobody simulates, whose heartbeat the device is told to consume (EMCY 8130h check).
GHOST_NODE = 0x7D
# Seconds after "go" when the remaining checks are given up (the Rust side waits longer than this).
BUDGET_S = 100.0


class FrameLog:
    """Every frame of a set of CAN-IDs with its hub timestamp, so no reception between two waits is lost."""

    def __init__(self) -> None:
        self.frames = []  # (can_id, data, timestamp)
        self.cond = threading.Condition()

    def on_frame(self, can_id, data, timestamp) -> None:
        with self.cond:
            self.frames.append((can_id, bytes(data), timestamp))
            self.cond.notify_all()

    def mark(self) -> int:
        with self.cond:
            return len(self.frames)

    def since(self, mark: int):
        with self.cond:
            return list(self.frames[mark:])

    def wait_for(self, predicate, mark: int, timeout: float):
        """The first frame after `mark` for which predicate(can_id, data) holds, or None after `timeout`."""
        deadline = time.monotonic() + timeout
        with self.cond:
            while True:
                for frame in self.frames[mark:]:
                    if predicate(frame[0], frame[1]):
                        return frame
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return None
                self.cond.wait(remaining)


class EverythingLog(can.Listener):
    """Every CAN-ID received by this process (the hub does not echo our own frames)."""

    def __init__(self) -> None:
        self.ids = set()
        self.lock = threading.Lock()

    def on_message_received(self, msg) -> None:
        with self.lock:
            self.ids.add(msg.arbitration_id)


def add_cia401_objects(dictionary) -> None:
    """The objects `canopener sim --app cia401` adds to a dictionary without CiA 401 I/O (reference §8.2)."""

    def var(name, index, sub, data_type, access, mappable):
        v = od.ODVariable(name, index, sub)
        v.data_type = data_type
        v.access_type = access
        v.pdo_mappable = mappable
        v.default = 0
        return v

    def array(name, index, data_type, access, mappable, count):
        a = od.ODArray(name, index)
        count_var = var("Highest sub-index supported", index, 0, od.UNSIGNED8, "const", False)
        count_var.default = count
        a.add_member(count_var)
        for sub in range(1, count + 1):
            a.add_member(var(f"{name} {sub}", index, sub, data_type, access, mappable))
        return a

    objects = [
        var("Factory test config", 0x2000, 0, od.BOOLEAN, "rw", False),
        var("Factory digital inputs", 0x2001, 0, od.UNSIGNED8, "rw", False),
        array("Factory analogue inputs", 0x2002, od.INTEGER16, "rw", False, 4),
        array("Read input 8-bit", 0x6000, od.UNSIGNED8, "ro", True, 1),
        array("Write output 8-bit", 0x6200, od.UNSIGNED8, "rww", True, 1),
        array("Read analogue input 16-bit", 0x6401, od.INTEGER16, "ro", True, 4),
    ]
    for obj in objects:
        if obj.index not in dictionary:
            dictionary.add_object(obj)


def u32(data: bytes) -> int:
    return int.from_bytes(data, "little")


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("host")
    parser.add_argument("port", type=int)
    parser.add_argument("channel")
    parser.add_argument("node_id", type=lambda text: int(text, 0))
    parser.add_argument("eds")
    parser.add_argument("--rounds", type=int, default=200)
    parser.add_argument("--block-bytes", type=int, default=32768)
    parser.add_argument("--lss", nargs=2, type=lambda text: int(text, 0), metavar=("NEW_NODE_ID", "SERIAL"))
    args = parser.parse_args()
    node_id = args.node_id

    network = canopen.Network()
    network.connect(interface="socketcand", host=args.host, port=args.port, channel=args.channel)
    everything = EverythingLog()
    network.notifier.add_listener(everything)
    node = canopen.RemoteNode(node_id, args.eds)
    add_cia401_objects(node.object_dictionary)
    network.add_node(node)
    node.sdo.RESPONSE_TIMEOUT = 2.0
    # Generous for a loaded machine; fastscan waits this long for each 1 bit of the LSS address.
    network.lss.RESPONSE_TIMEOUT = 1.0
    heartbeats = FrameLog()
    network.subscribe(0x700 + node_id, heartbeats.on_frame)
    tpdos = FrameLog()
    for base in (0x180, 0x280, 0x380):
        network.subscribe(base + node_id, tpdos.on_frame)
    lss_heartbeats = FrameLog()
    if args.lss:
        network.subscribe(0x700 + args.lss[0], lss_heartbeats.on_frame)

    print(json.dumps({"ready": True}), flush=True)
    if sys.stdin.readline().strip() != "go":
        return 2
    started = time.monotonic()

    checks = {}
    timing = {}
    # Checks in a row that failed because the device did not answer: after a few, the device is taken for
    # dead and the rest of its checks are reported without waiting out every SDO timeout.
    no_answer = {"streak": 0}

    def check(name, fn):
        if time.monotonic() - started > BUDGET_S:
            checks[name] = {"ok": False, "detail": f"not run: the {BUDGET_S:.0f} s budget was spent"}
            return
        if no_answer["streak"] >= 3:
            checks[name] = {"ok": False, "detail": "not run: the device stopped answering SDO"}
            return
        try:
            ok, detail = fn()
            no_answer["streak"] = 0
        except SdoCommunicationError as exc:
            ok, detail = False, repr(exc)
            no_answer["streak"] += 1
        except Exception as exc:  # a failed check is reported, never hidden
            ok, detail = False, repr(exc)
        checks[name] = {"ok": bool(ok), "detail": str(detail)}

    def upload_u(index, sub=0):
        return u32(node.sdo.upload(index, sub))

    def download_u(index, sub, value, size):
        node.sdo.download(index, sub, value.to_bytes(size, "little"))

    def is_state(state):
        return lambda can_id, data: len(data) == 1 and data[0] == state

    def wait_state(state, mark, timeout=5.0):
        return heartbeats.wait_for(is_state(state), mark, timeout) is not None

    def compressed_states(mark):
        out = []
        for _, data, _ in heartbeats.since(mark):
            state = data[0] if len(data) == 1 else None
            if not out or out[-1] != state:
                out.append(state)
        return out

    # ---- boot-up and heartbeat (CiA 301 NMT error control) ------------------------------------------------
    check("boot-up received",
          lambda: (wait_state(0x00, 0, 10.0), f"frames on {0x700 + node_id:03X}h: {heartbeats.since(0)[:3]}"))

    hb_mark = heartbeats.mark()

    def heartbeat_on():
        download_u(0x1017, 0, 100, 2)
        back = upload_u(0x1017)
        return back == 100 and wait_state(0x7F, hb_mark), f"1017h read back {back}"

    check("SDO expedited download 1017h = 100 ms starts heartbeat PRE-OPERATIONAL (7Fh)", heartbeat_on)

    def heartbeat_period():
        mark = heartbeats.mark()
        deadline = time.monotonic() + 3.0
        while len(heartbeats.since(mark)) < 8 and time.monotonic() < deadline:
            time.sleep(0.05)
        stamps = [ts for _, _, ts in heartbeats.since(mark)]
        gaps = [b - a for a, b in zip(stamps, stamps[1:])]
        if len(gaps) < 5:
            return False, f"only {len(stamps)} heartbeats in 3 s"
        median = statistics.median(gaps) * 1e3
        timing["heartbeat_period_median_ms"] = round(median, 1)
        return 70 <= median <= 200, f"median interval {median:.1f} ms over {len(gaps)} gaps (1017h = 100 ms)"

    check("heartbeat period follows 1017h", heartbeat_period)

    # ---- NMT (CiA 301 §2) ---------------------------------------------------------------------------------
    def nmt(command, state):
        mark = heartbeats.mark()
        node.nmt.state = command
        seen = wait_state(state, mark)
        return seen, f"NMT {command}: heartbeat {STATE_NAMES[state]} {'seen' if seen else 'not seen in 5 s'}"

    check("NMT start -> heartbeat OPERATIONAL (05h)", lambda: nmt("OPERATIONAL", 0x05))
    check("NMT stop -> heartbeat STOPPED (04h)", lambda: nmt("STOPPED", 0x04))

    def stopped_is_silent():
        mark = heartbeats.mark()
        node.sdo.RESPONSE_TIMEOUT = 0.5
        try:
            node.sdo.upload(0x1000, 0)
        except SdoCommunicationError as exc:
            # Silence alone would also pass for a dead device: it must still be heartbeating STOPPED.
            alive = heartbeats.wait_for(is_state(0x04), mark, 1.0) is not None
            return alive, f"no answer ({exc}); heartbeat STOPPED meanwhile: {alive}"
        except SdoAbortedError as exc:
            return False, f"the stopped node aborted with {exc.code:#010x} instead of staying silent"
        finally:
            node.sdo.RESPONSE_TIMEOUT = 2.0
        return False, "the stopped node answered an SDO upload"

    check("stopped node does not answer SDO", stopped_is_silent)
    check("NMT enter pre-operational -> heartbeat PRE-OPERATIONAL (7Fh)", lambda: nmt("PRE-OPERATIONAL", 0x7F))
    check("SDO answered again in PRE-OPERATIONAL",
          lambda: (upload_u(0x1017) == 100, f"1017h = {upload_u(0x1017)}"))

    def states_in_order():
        seen = compressed_states(hb_mark)
        wanted = [0x7F, 0x05, 0x04, 0x7F]
        return seen == wanted, f"heartbeat states since 1017h was set: {[hex(s) for s in seen if s is not None]}"

    check("heartbeat states 7Fh, 05h, 04h, 7Fh in order", states_in_order)

    def reset_communication():
        download_u(0x2200, 0, 0x12345678, 4)
        mark = heartbeats.mark()
        node.nmt.state = "RESET COMMUNICATION"
        booted = wait_state(0x00, mark)
        producer = upload_u(0x1017)
        application = upload_u(0x2200)
        ok = booted and producer == 0 and application == 0x12345678
        return ok, (f"boot-up {'seen' if booted else 'missing'}; 1017h = {producer} (EDS default 0); "
                    f"2200h = {application:#x} (kept: reset communication leaves 2000h-9FFFh alone)")

    check("NMT reset communication -> boot-up, communication objects back to defaults", reset_communication)

    def reset_node():
        mark = heartbeats.mark()
        node.nmt.state = "RESET"
        booted = wait_state(0x00, mark)
        application = upload_u(0x2200)
        ok = booted and application == 0
        return ok, f"boot-up {'seen' if booted else 'missing'}; 2200h = {application:#x} (EDS default 0)"

    check("NMT reset node -> boot-up, application objects back to defaults", reset_node)

    # ---- SDO (CiA 301 §1) ---------------------------------------------------------------------------------
    check("SDO expedited upload 1000h = 00070191h (CiA 401 I/O)",
          lambda: (upload_u(0x1000) == 0x00070191, f"{upload_u(0x1000):#010x}"))

    def identity():
        values = [upload_u(0x1018, sub) for sub in range(1, 5)]
        return values == [0, 1, 0x00010000, 1], f"1018h:01..04 = {[hex(v) for v in values]}"

    check("SDO expedited upload 1018h:01..04 (identity from the EDS)", identity)

    def expedited_download():
        node.sdo[0x2200].raw = 0xCAFEF00D
        value = node.sdo[0x2200].raw
        return value == 0xCAFEF00D, f"{value:#x}"

    check("SDO expedited download+upload 2200h", expedited_download)
    check("SDO segmented upload 1008h",
          lambda: (node.sdo[0x1008].raw == "rtt demo", repr(node.sdo[0x1008].raw)))

    rng = random.Random(0x5EED)
    seg_data = rng.randbytes(889)

    def segmented():
        node.sdo.download(0x2304, 0, seg_data)
        back = node.sdo.upload(0x2304, 0)
        return back == seg_data, f"{len(back)} bytes read back"

    check("SDO segmented download+upload 2304h DOMAIN (889 bytes)", segmented)

    def block_write(index, data):
        with node.sdo.open(index, 0, "wb", size=len(data), block_transfer=True) as stream:
            stream.write(data)

    def block_read(index):
        with node.sdo.open(index, 0, "rb", block_transfer=True) as stream:
            return stream.read()

    cross = rng.randbytes(2000)

    def block_download_checked_by_segmented_upload():
        block_write(0x2304, cross)
        back = node.sdo.upload(0x2304, 0)
        return back == cross, f"{len(back)} bytes read back segmented"

    check("SDO block download 2304h (2000 bytes), read back segmented", block_download_checked_by_segmented_upload)

    cross2 = rng.randbytes(2001)

    def segmented_download_checked_by_block_upload():
        node.sdo.download(0x2304, 0, cross2)
        back = block_read(0x2304)
        return back == cross2, f"{len(back)} bytes read back by block upload"

    check("SDO segmented download 2304h (2001 bytes), read back by block upload",
          segmented_download_checked_by_block_upload)

    def block_short():
        block_write(0x2304, b"\x01\x02\x03")
        back = block_read(0x2304)
        return back == b"\x01\x02\x03", f"read back {back.hex()}"

    check("SDO block download+upload 2304h (3 bytes, one segment)", block_short)
    check("SDO block upload 1008h (8 bytes)",
          lambda: (block_read(0x1008) == b"rtt demo", repr(block_read(0x1008))))

    big = rng.randbytes(args.block_bytes)

    def block_big():
        start = time.perf_counter()
        block_write(0x2304, big)
        down = time.perf_counter() - start
        start = time.perf_counter()
        back = block_read(0x2304)
        up = time.perf_counter() - start
        timing["block_bytes"] = len(big)
        timing["block_download_kB_per_s"] = round(len(big) / 1024 / down, 1)
        timing["block_upload_kB_per_s"] = round(len(big) / 1024 / up, 1)
        same = back == big
        first_difference = next((i for i, (a, b) in enumerate(zip(back, big)) if a != b), None)
        return same, f"{len(back)} of {len(big)} bytes back, first difference at {first_difference}"

    check("SDO block download+upload 2304h (--block-bytes, 32 KiB by default), byte for byte", block_big)

    def block_tuned():
        # python-can's socketcand client leaves Nagle's algorithm on unless tcp_tune is set: the last frames
        # of each 127-frame block then wait for the hub's delayed ACK, which caps block downloads. The same
        # transfer from a tuned connection shows what the device itself sustains.
        tuned = canopen.Network()
        tuned.connect(interface="socketcand", host=args.host, port=args.port, channel=args.channel,
                      tcp_tune=True)
        try:
            twin = canopen.RemoteNode(node_id, node.object_dictionary)
            tuned.add_node(twin)
            twin.sdo.RESPONSE_TIMEOUT = 2.0
            data = bytes(reversed(big))
            start = time.perf_counter()
            with twin.sdo.open(0x2304, 0, "wb", size=len(data), block_transfer=True) as stream:
                stream.write(data)
            elapsed = time.perf_counter() - start
        finally:
            tuned.disconnect()
        timing["block_download_tcp_tune_kB_per_s"] = round(len(data) / 1024 / elapsed, 1)
        back = block_read(0x2304)
        return back == data, f"{len(back)} of {len(data)} bytes read back by block upload"

    check("SDO block download 2304h from a python-can connection with tcp_tune, byte for byte", block_tuned)

    def abort(index, sub, code, write=None):
        try:
            if write is None:
                node.sdo.upload(index, sub)
            else:
                node.sdo.download(index, sub, write)
        except SdoAbortedError as exc:
            return exc.code == code, f"abort code {exc.code:#010x}"
        return False, "no abort"

    check("SDO abort 06020000h for a missing object", lambda: abort(0x5FFF, 0, 0x06020000))
    check("SDO abort 06010002h for writing read-only 1000h",
          lambda: abort(0x1000, 0, 0x06010002, write=b"\x00\x00\x00\x00"))

    def sdo_timing():
        times = []
        for _ in range(args.rounds):
            start = time.perf_counter()
            node.sdo.upload(0x1017, 0)
            times.append(time.perf_counter() - start)
        times.sort()
        timing["expedited_upload_rounds"] = len(times)
        timing["expedited_upload_median_ms"] = round(statistics.median(times) * 1e3, 3)
        timing["expedited_upload_p99_ms"] = round(times[int(0.99 * (len(times) - 1))] * 1e3, 3)
        start = time.perf_counter()
        node.sdo.download(0x2304, 0, seg_data)
        timing["segmented_889_download_ms"] = round((time.perf_counter() - start) * 1e3, 2)
        start = time.perf_counter()
        node.sdo.upload(0x2304, 0)
        timing["segmented_889_upload_ms"] = round((time.perf_counter() - start) * 1e3, 2)
        return True, f"{len(times)} expedited uploads"

    check("SDO timing rounds complete", sdo_timing)

    # ---- PDO (CiA 301 §3) ---------------------------------------------------------------------------------
    tpdo_ids = {n: base + node_id for n, base in ((1, 0x180), (2, 0x280), (3, 0x380))}
    rpdo_id = 0x200 + node_id

    def decode(number, data):
        """The values of TPDO `number`'s mapped objects in a received frame, decoded by python canopen's
        dictionary types (byte-aligned mappings only, which is all this test maps)."""
        values = []
        for variable in node.tpdo[number].map:
            start = variable.offset // 8
            values.append(variable.od.decode_raw(data[start:start + variable.length // 8]))
        return values

    def configure():
        node.tpdo.read()
        node.rpdo.read()
        before = {n: hex(node.tpdo[n].cob_id) for n in (1, 2, 3)}
        tpdo1 = node.tpdo[1]
        tpdo1.clear()
        tpdo1.add_variable(0x6000, 1)
        tpdo1.trans_type = 254
        tpdo1.event_timer = 0
        tpdo1.enabled = True
        tpdo2 = node.tpdo[2]
        tpdo2.clear()
        tpdo2.add_variable(0x6401, 1)
        tpdo2.add_variable(0x6401, 2)
        tpdo2.trans_type = 254
        tpdo2.event_timer = 100
        tpdo2.enabled = True
        tpdo3 = node.tpdo[3]
        tpdo3.clear()
        tpdo3.add_variable(0x6000, 1)
        tpdo3.add_variable(0x6401, 1)
        tpdo3.trans_type = 2
        tpdo3.enabled = True
        rpdo1 = node.rpdo[1]
        rpdo1.clear()
        rpdo1.add_variable(0x2200)
        rpdo1.add_variable(0x6200, 1)
        rpdo1.trans_type = 254
        rpdo1.enabled = True
        for pdo in (tpdo1, tpdo2, tpdo3, rpdo1):
            pdo.save()
        # Read the configuration back over SDO rather than trusting python's copy.
        wanted = {
            (0x1A00, 0): 1, (0x1A00, 1): 0x60000108,
            (0x1A01, 0): 2, (0x1A01, 1): 0x64010110, (0x1A01, 2): 0x64010210,
            (0x1A02, 0): 2, (0x1A02, 1): 0x60000108, (0x1A02, 2): 0x64010110,
            (0x1600, 0): 2, (0x1600, 1): 0x22000020, (0x1600, 2): 0x62000108,
            (0x1800, 1): 0x40000000 | tpdo_ids[1], (0x1800, 2): 254,
            (0x1801, 1): 0x40000000 | tpdo_ids[2], (0x1801, 2): 254, (0x1801, 5): 100,
            (0x1802, 1): 0x40000000 | tpdo_ids[3], (0x1802, 2): 2,
            (0x1400, 1): rpdo_id, (0x1400, 2): 254,
        }
        wrong = {f"{i:04X}h:{s:02X}": hex(upload_u(i, s)) for (i, s), v in wanted.items() if upload_u(i, s) != v}
        return not wrong, f"COB-IDs read {before}; entries differing from what was saved: {wrong}"

    check("PDO reconfiguration over SDO (python read/clear/add_variable/save), read back", configure)

    def start_operational():
        mark = heartbeats.mark()
        download_u(0x1017, 0, 100, 2)
        node.nmt.state = "OPERATIONAL"
        ok = wait_state(0x05, mark)
        # Factory test on: the digital and analogue inputs now come from 2001h and 2002h.
        node.sdo[0x2000].raw = True
        return ok and node.sdo[0x2000].raw, "operational, factory test register 2000h = TRUE"

    check("NMT start with the new PDOs, factory test 2000h on", start_operational)

    def barrier():
        """An SDO round trip: the device answers frames in order, so PDOs it sent before the answer are in."""
        node.sdo.upload(0x1000, 0)

    def on_event():
        barrier()
        mark = tpdos.mark()
        node.sdo[0x2001].raw = 0x5A
        first = tpdos.wait_for(lambda cid, _: cid == tpdo_ids[1], mark, 3.0)
        if first is None:
            return False, "no TPDO1 after 2001h = 5Ah"
        values = decode(1, first[1])
        return values == [0x5A], f"TPDO1 {first[1].hex()} decoded {values}"

    check("TPDO1 on event: 2001h = 5Ah -> 6000h:01 = 5Ah sent", on_event)

    def only_on_change():
        barrier()
        mark = tpdos.mark()
        node.sdo[0x2001].raw = 0x5A
        barrier()
        unchanged = [f.hex() for cid, f, _ in tpdos.since(mark) if cid == tpdo_ids[1]]
        mark = tpdos.mark()
        node.sdo[0x2001].raw = 0xA5
        frame = tpdos.wait_for(lambda cid, _: cid == tpdo_ids[1], mark, 3.0)
        values = decode(1, frame[1]) if frame else None
        ok = not unchanged and values == [0xA5]
        return ok, f"TPDO1 after writing the same value: {unchanged}; after 2001h = A5h: {values}"

    check("TPDO1 only on a change (same value again sends nothing)", only_on_change)

    def event_timer():
        node.sdo[0x2002][1].raw = -1234
        node.sdo[0x2002][2].raw = 4321
        barrier()
        mark = tpdos.mark()
        time.sleep(1.05)
        frames = [(data, ts) for cid, data, ts in tpdos.since(mark) if cid == tpdo_ids[2]]
        gaps = [b[1] - a[1] for a, b in zip(frames, frames[1:])]
        values = [decode(2, data) for data, _ in frames]
        if len(gaps) < 4:
            return False, f"only {len(frames)} TPDO2 in 1 s"
        median = statistics.median(gaps) * 1e3
        timing["tpdo_event_timer_median_ms"] = round(median, 1)
        ok = 70 <= median <= 200 and all(v == [-1234, 4321] for v in values)
        return ok, f"{len(frames)} TPDO2 in 1 s, median interval {median:.1f} ms (1801h:05 = 100), values {values[:3]}"

    check("TPDO2 on event timer 100 ms carries 6401h:01..02 from 2002h (-1234, 4321)", event_timer)

    def on_sync():
        latencies = []
        pattern = []
        values = []
        for _ in range(6):
            mark = tpdos.mark()
            sent = time.time()
            network.sync.transmit()
            barrier()
            got = [(data, ts) for cid, data, ts in tpdos.since(mark) if cid == tpdo_ids[3]]
            pattern.append(len(got))
            for data, ts in got:
                values.append(decode(3, data))
                latencies.append(ts - sent)
        if latencies:
            timing["sync_to_tpdo_median_ms"] = round(statistics.median(latencies) * 1e3, 2)
        alternating = pattern in ([0, 1, 0, 1, 0, 1], [1, 0, 1, 0, 1, 0])
        ok = alternating and values and all(v == [0xA5, -1234] for v in values)
        return ok, f"TPDO3 per SYNC: {pattern} (type 2: every 2nd SYNC); values {values}"

    check("TPDO3 on SYNC, transmission type 2 (every 2nd SYNC)", on_sync)

    def rpdo():
        rpdo1 = node.rpdo[1]
        rpdo1.map[0].raw = 0xDEADBEEF
        rpdo1.map[1].raw = 0x3C
        rpdo1.transmit()
        written = upload_u(0x2200)
        output = upload_u(0x6200, 1)
        return written == 0xDEADBEEF and output == 0x3C, f"2200h = {written:#x}, 6200h:01 = {output:#x}"

    check("RPDO1 write visible over SDO (2200h, 6200h:01)", rpdo)

    # ---- EMCY (CiA 301 §4.3) ------------------------------------------------------------------------------
    def wait_emcy(code, mark, timeout=3.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for entry in node.emcy.log[mark:]:
                if entry.code == code:
                    return entry
            time.sleep(0.01)
        return None

    def describe(entries):
        return [f"{e.code:04X}h reg {e.register:02X}h data {e.data.hex()}" for e in entries]

    def emcy_rpdo_length():
        mark = len(node.emcy.log)
        network.send_message(rpdo_id, b"\x01\x02")
        entry = wait_emcy(0x8210, mark)
        ok = entry is not None and entry.register & 0x10
        return ok, f"EMCY after a 2-byte RPDO1 (5 mapped): {describe(node.emcy.log[mark:])}"

    check("EMCY 8210h for a too-short RPDO, error register bit 4", emcy_rpdo_length)

    def emcy_reset():
        mark = len(node.emcy.log)
        node.rpdo[1].transmit()
        entry = wait_emcy(0x0000, mark)
        return entry is not None and not node.emcy.active, f"after a correct RPDO1: {describe(node.emcy.log[mark:])}"

    check("EMCY error reset 0000h after a correct RPDO", emcy_reset)

    def emcy_heartbeat():
        download_u(0x1016, 1, (GHOST_NODE << 16) | 250, 4)
        mark = len(node.emcy.log)
        for _ in range(3):
            network.send_message(0x700 + GHOST_NODE, b"\x05")
            time.sleep(0.05)
        entry = wait_emcy(0x8130, mark)
        ok = entry is not None and entry.register & 0x10
        return ok, f"EMCY after node {GHOST_NODE:02X}h's heartbeat stopped (1016h:01 = 250 ms): " \
                   f"{describe(node.emcy.log[mark:])}"

    check("EMCY 8130h when a consumed heartbeat stops (1016h)", emcy_heartbeat)

    # ---- LSS (CiA 305 §7) ---------------------------------------------------------------------------------
    if args.lss:
        # Another device: whether node 20h went silent says nothing about this one.
        no_answer["streak"] = 0
        new_id, serial = args.lss
        # Node 20h's frames, LSS answers, and the SDO requests of the tcp_tune connection (the hub forwards
        # them to this one).
        main_ids = {0x80 + node_id, 0x580 + node_id, 0x600 + node_id, 0x700 + node_id, *tpdo_ids.values(), 0x7E4}

        def nothing_before_lss():
            with everything.lock:
                foreign = sorted(everything.ids - main_ids)
            return not foreign, f"CAN-IDs not from node {node_id:02X}h: {[hex(i) for i in foreign]}"

        check("unconfigured device sends nothing before LSS", nothing_before_lss)
        found = {}

        def fastscan():
            network.lss.send_switch_state_global(network.lss.WAITING_STATE)
            start = time.perf_counter()
            ok, ids = network.lss.fast_scan()
            timing["lss_fastscan_s"] = round(time.perf_counter() - start, 2)
            found["ids"] = ids
            wanted = [0, 1, 0x00010000, serial]
            return ok and ids == wanted, f"fastscan: {ok}, {[hex(i) for i in ids or []]} (wanted " \
                                         f"{[hex(i) for i in wanted]})"

        check("LSS fastscan finds the unconfigured device", fastscan)
        check("LSS inquire node-ID = FFh (unconfigured)",
              lambda: (network.lss.inquire_node_id() == 0xFF, f"{network.lss.inquire_node_id():#04x}"))
        check("LSS configure node-ID",
              lambda: (network.lss.configure_node_id(new_id) is None, f"node-ID {new_id:#04x} accepted"))

        def store():
            try:
                network.lss.store_configuration()
            except LssError as exc:
                return False, f"refused or unanswered: {exc}"
            return True, "stored (error code 0)"

        check("LSS store configuration", store)

        def boots():
            mark = lss_heartbeats.mark()
            network.lss.send_switch_state_global(network.lss.WAITING_STATE)
            frame = lss_heartbeats.wait_for(is_state(0x00), mark, 5.0)
            return frame is not None, f"boot-up on {0x700 + new_id:03X}h: {frame}"

        check("LSS switch to waiting -> boot-up at 700h + new node-ID", boots)

        def answers():
            lss_node = canopen.RemoteNode(new_id, args.eds)
            network.add_node(lss_node)
            lss_node.sdo.RESPONSE_TIMEOUT = 2.0
            got_serial = u32(lss_node.sdo.upload(0x1018, 4))
            server_rx = u32(lss_node.sdo.upload(0x1200, 1))
            ok = got_serial == serial and server_rx == 0x600 + new_id
            return ok, f"1018h:04 = {got_serial:#x}; 1200h:01 = {server_rx:#x} ($NODEID follows LSS)"

        check("LSS-configured device answers SDO at the new node-ID", answers)

    timing["total_s"] = round(time.monotonic() - started, 2)
    network.disconnect()
    print(json.dumps({"checks": checks, "timing": timing}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
