#!/usr/bin/env python3
"""Writes demo.log: a believable CANopen session on can0 in candump -l format.

Run from this directory: `python3 generate_demo_log.py > demo.log`. Standard library only.

Nodes: 1 = NMT master, SDO client, SYNC and TIME producer; 5 = CiA 401 I/O module; 6 = digital I/O
module; 10 = CiA 402 servo drive guarded by node guarding instead of heartbeat. The bus runs at
500 kbit/s: frames are serialised one after another, ties go to the lower CAN-ID (arbitration), and a
frame's timestamp is when it ends on the bus, as SocketCAN reports it.
"""

import binascii
import calendar
import random
import struct

BITRATE = 500_000
START = calendar.timegm((2025, 1, 15, 8, 30, 0)) * 1_000_000  # microseconds since the Unix epoch
MASTER, IO, DIO, DRIVE = 1, 5, 6, 10

IDENTITY = {
    IO: dict(device_type=0x000F0191, vendor=0x00000CA7, product=0x00004010, revision=0x00010003, serial=0x2025A105),
    DIO: dict(device_type=0x00030191, vendor=0x00000CA7, product=0x00004008, revision=0x00010001, serial=0x2025A217),
    DRIVE: dict(device_type=0x00020192, vendor=0x00000CA7, product=0x00007102, revision=0x00020000, serial=0x2025B033),
}
DEVICE_NAME_IO = b"canopener demo I/O"
LABEL_DIO = b"Line 2 / Station A"
STORED_EDS_DRIVE = (
    b"[FileInfo]\r\nFileName=demo-servo.eds\r\nFileVersion=3\r\n"
    b"[DeviceInfo]\r\nVendorName=canopener demo\r\nProductNumber=0x7102\r\n"
)

frames = []  # (scheduled time in us, sequence, can_id, data or ("R", dlc))
jitter = random.Random(2025)  # fixed seed: the log is the same on every run


def jittered(t_us, spread_us):
    """A periodic producer's timer is never exact; `spread_us` is its worst deviation."""
    return t_us + jitter.randint(-spread_us, spread_us)


def send(t_us, can_id, data):
    frames.append((t_us, len(frames), can_id, data))


def frame_us(data):
    """Approximate duration of a standard frame: 47 + 8n bits plus about 10 % stuff bits."""
    n = 0 if isinstance(data, tuple) else len(data)  # a remote frame has no data field
    bits = (47 + 8 * n) * 1.1
    return int(bits * 1_000_000 / BITRATE) + 1


def u32(value):
    return list(struct.pack("<I", value))


class Sdo:
    """An SDO client on node 1 talking to the default server of `node`; returns when it is done."""

    def __init__(self, node):
        self.node = node

    def req(self, t, data):
        send(t, 0x600 + self.node, data)

    def rsp(self, t, data):
        send(t, 0x580 + self.node, data)

    def mux(self, index, sub):
        return [index & 0xFF, index >> 8, sub]

    def read_expedited(self, t, index, sub, value, size=4):
        self.req(t, [0x40] + self.mux(index, sub) + [0, 0, 0, 0])
        data = list(value.to_bytes(size, "little")) + [0] * (4 - size)
        self.rsp(t + 700, [0x43 | ((4 - size) << 2)] + self.mux(index, sub) + data)
        return t + 1500

    def write_expedited(self, t, index, sub, value, size):
        data = list(value.to_bytes(size, "little")) + [0] * (4 - size)
        self.req(t, [0x23 | ((4 - size) << 2)] + self.mux(index, sub) + data)
        self.rsp(t + 800, [0x60] + self.mux(index, sub) + [0, 0, 0, 0])
        return t + 1600

    def read_segmented(self, t, index, sub, value):
        self.req(t, [0x40] + self.mux(index, sub) + [0, 0, 0, 0])
        self.rsp(t + 700, [0x41] + self.mux(index, sub) + u32(len(value)))
        t += 1400
        toggle = 0
        for offset in range(0, len(value), 7):
            chunk = list(value[offset:offset + 7])
            last = offset + 7 >= len(value)
            self.req(t, [0x60 | (toggle << 4)] + [0] * 7)
            command = (toggle << 4) | ((7 - len(chunk)) << 1) | int(last)
            self.rsp(t + 600, [command] + chunk + [0] * (7 - len(chunk)))
            t += 1300
            toggle ^= 1
        return t

    def write_segmented(self, t, index, sub, value):
        self.req(t, [0x21] + self.mux(index, sub) + u32(len(value)))
        self.rsp(t + 800, [0x60] + self.mux(index, sub) + [0, 0, 0, 0])
        t += 1500
        toggle = 0
        for offset in range(0, len(value), 7):
            chunk = list(value[offset:offset + 7])
            last = offset + 7 >= len(value)
            command = (toggle << 4) | ((7 - len(chunk)) << 1) | int(last)
            self.req(t, [command] + chunk + [0] * (7 - len(chunk)))
            self.rsp(t + 900, [0x20 | (toggle << 4), 0, 0, 0, 0, 0, 0, 0])
            t += 1600
            toggle ^= 1
        return t

    def read_block(self, t, index, sub, value, blksize):
        """Block upload with CRC on both sides (CiA 301 §7.2.4.3.13-16)."""
        self.req(t, [0xA4] + self.mux(index, sub) + [blksize, 0, 0, 0])
        self.rsp(t + 800, [0xC6] + self.mux(index, sub) + u32(len(value)))
        self.req(t + 1500, [0xA3, 0, 0, 0, 0, 0, 0, 0])
        t += 2000
        chunks = [list(value[i:i + 7]) for i in range(0, len(value), 7)]
        for start in range(0, len(chunks), blksize):
            sub_block = chunks[start:start + blksize]
            for seq, chunk in enumerate(sub_block, 1):
                last = start + seq == len(chunks)
                self.rsp(t, [(0x80 if last else 0) | seq] + chunk + [0] * (7 - len(chunk)))
                t += 300
            self.req(t + 400, [0xA2, len(sub_block), blksize, 0, 0, 0, 0, 0])
            t += 1000
        unused = 7 - len(chunks[-1])
        crc = binascii.crc_hqx(value, 0)
        self.rsp(t, [0xC1 | (unused << 2), crc & 0xFF, crc >> 8, 0, 0, 0, 0, 0])
        self.req(t + 700, [0xA1, 0, 0, 0, 0, 0, 0, 0])
        return t + 1500

    def read_missing(self, t, index, sub):
        self.req(t, [0x40] + self.mux(index, sub) + [0, 0, 0, 0])
        self.rsp(t + 700, [0x80] + self.mux(index, sub) + u32(0x06020000))
        return t + 1500


def nmt(t, command, target):
    send(t, 0x000, [command, target])


def heartbeat(t, node, state):
    send(t, 0x700 + node, [state])


def time_of_day(t_us):
    """TIME_OF_DAY for the wall-clock time of log timestamp `t_us` (CiA 301 §7.1.6.5)."""
    seconds = t_us // 1_000_000
    days = seconds // 86400 - 5113  # 5113 days from 1970-01-01 to 1984-01-01
    millis = (t_us // 1000) % 86_400_000
    return list(struct.pack("<IH", millis, days))


# --- Power-on: the master and the three slaves boot. ---
t = START + 12_000
heartbeat(t, MASTER, 0x00)
for node, delay in ((IO, 180_000), (DIO, 214_500), (DRIVE, 402_000)):
    heartbeat(START + delay, node, 0x00)

# --- The master resets the communication of all nodes; they boot again. ---
t = START + 1_000_000
nmt(t, 0x82, 0)
for node, delay in ((IO, 9_100), (DIO, 11_800), (DRIVE, 35_600)):
    heartbeat(t + delay, node, 0x00)

# --- Identify every node: 1000h and 1018h:01..04, expedited uploads. ---
t += 100_000
for node in (IO, DIO, DRIVE):
    sdo = Sdo(node)
    ident = IDENTITY[node]
    t = sdo.read_expedited(t, 0x1000, 0, ident["device_type"])
    for sub, key in ((1, "vendor"), (2, "product"), (3, "revision"), (4, "serial")):
        t = sdo.read_expedited(t, 0x1018, sub, ident[key])
    t += 2_000

# --- Device name of node 5 (segmented upload) and a label for node 6 (segmented download). ---
t = Sdo(IO).read_segmented(t + 3_000, 0x1008, 0, DEVICE_NAME_IO)
t = Sdo(DIO).write_segmented(t + 3_000, 0x2100, 0, LABEL_DIO)

# --- The stored EDS of the drive (1021h) by block upload with CRC, 8 segments per sub-block. ---
t = Sdo(DRIVE).read_block(t + 5_000, 0x1021, 0, STORED_EDS_DRIVE, 8)

# --- Error control: heartbeat 100 ms on nodes 5 and 6, node guarding 100 ms x 3 on node 10. ---
t = Sdo(IO).write_expedited(t + 4_000, 0x1017, 0, 100, 2)
hb_start_io = t
t = Sdo(DIO).write_expedited(t + 1_000, 0x1017, 0, 100, 2)
hb_start_dio = t
t = Sdo(DRIVE).write_expedited(t + 1_000, 0x100C, 0, 100, 2)
t = Sdo(DRIVE).write_expedited(t + 1_000, 0x100D, 0, 3, 1)
guard_start = t + 20_000

# --- Remap TPDO1 of node 5 (the CiA 301 PDO mapping procedure), synchronous every SYNC. ---
io = Sdo(IO)
t += 6_000
t = io.write_expedited(t, 0x1800, 1, 0x80000185, 4)  # make TPDO1 invalid
t = io.write_expedited(t + 500, 0x1A00, 0, 0, 1)  # disable the mapping
t = io.write_expedited(t + 500, 0x1A00, 1, 0x60000108, 4)  # 6000h:01 digital inputs 1-8
t = io.write_expedited(t + 500, 0x1A00, 2, 0x60000208, 4)  # 6000h:02 digital inputs 9-16
t = io.write_expedited(t + 500, 0x1A00, 3, 0x64010110, 4)  # 6401h:01 analogue input 1
t = io.write_expedited(t + 500, 0x1A00, 0, 3, 1)  # enable 3 entries
t = io.write_expedited(t + 500, 0x1800, 2, 1, 1)  # transmission type 1: every SYNC
t = io.write_expedited(t + 500, 0x1800, 1, 0x00000185, 4)  # make TPDO1 valid again

# --- LSS: address node 5 by its identity and inquire its identity and node-id (CiA 305). ---
t += 10_000
ident = IDENTITY[IO]
for cs, key in ((0x40, "vendor"), (0x41, "product"), (0x42, "revision"), (0x43, "serial")):
    send(t, 0x7E5, [cs] + u32(ident[key]) + [0, 0, 0])
    t += 600
send(t + 400, 0x7E4, [0x44, 0, 0, 0, 0, 0, 0, 0])
t += 2_000
for cs, key in ((0x5A, "vendor"), (0x5B, "product"), (0x5C, "revision"), (0x5D, "serial")):
    send(t, 0x7E5, [cs, 0, 0, 0, 0, 0, 0, 0])
    send(t + 500, 0x7E4, [cs] + u32(ident[key]) + [0, 0, 0])
    t += 1_500
send(t, 0x7E5, [0x5E, 0, 0, 0, 0, 0, 0, 0])
send(t + 500, 0x7E4, [0x5E, IO, 0, 0, 0, 0, 0, 0])
send(t + 1_500, 0x7E5, [0x04, 0x00, 0, 0, 0, 0, 0, 0])  # everybody back to LSS waiting
t += 20_000

# --- Start all nodes, then TIME. ---
start_at = t + 50_000
nmt(start_at, 0x01, 0)
send(start_at + 5_000, 0x100, time_of_day(start_at + 5_000))

# --- Cyclic phase: SYNC every 10 ms with counter, TPDOs answer, RPDOs from the master. ---
cyclic_end = start_at + 620_000
sync_t = start_at + 10_000
counter = 1
analog = 0x1F40
while sync_t < cyclic_end:
    send(jittered(sync_t, 15), 0x080, [counter])
    di_low = 0x0C if sync_t < start_at + 300_000 else 0x0D
    analog += 7
    send(sync_t + 200, 0x185, [di_low, 0x00] + list(struct.pack("<h", analog)))
    velocity = min(1500, (sync_t - start_at) // 200)
    send(sync_t + 300, 0x18A, [0x37, 0x02] + list(struct.pack("<i", velocity * 10 - 12)))
    if counter % 5 == 0:
        send(sync_t + 1_200, 0x205, [0x21 if counter % 10 else 0x25])
        send(sync_t + 1_400, 0x20A, [0x0F, 0x00] + list(struct.pack("<i", 1500 * 10)))
    counter = counter % 240 + 1
    sync_t += 10_000

# TPDO2 of node 5 (analogue inputs 1-4, event timer 100 ms) and events of node 6 (TPDO1, type 255).
for k in range(6):
    base = start_at + 15_500 + k * 100_000
    send(base, 0x285, list(struct.pack("<hhhh", 0x1F40 + 70 * k, 0x0A10, -0x0040, 0x7FF0)))
send(start_at + 2_300, 0x186, [0x00])
send(start_at + 233_700, 0x186, [0x04])
send(start_at + 455_100, 0x186, [0x06])

# EMCY from node 6: output 3 overloaded (2310h, register generic + current), cleared 180 ms later.
emcy_at = start_at + 256_400
send(emcy_at, 0x086, [0x10, 0x23, 0x03, 0x03, 0x00, 0x00, 0x00, 0x00])
send(emcy_at + 180_000, 0x086, [0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00])

# An SDO read of an object node 6 does not have: abort 0602 0000h.
Sdo(DIO).read_missing(start_at + 333_600, 0x6100, 1)

# --- Heartbeats (100 ms) and node guarding of node 10 (100 ms), through the whole session. ---
end = cyclic_end + 250_000
state = {MASTER: 0x7F, IO: 0x7F, DIO: 0x7F, DRIVE: 0x7F}


def nmt_state(node, at):
    if at >= end - 200_000:
        return 0x7F
    return 0x05 if at >= start_at + 2_000 else 0x7F


hb_master = START + 112_000
while hb_master < end:
    heartbeat(jittered(hb_master, 400), MASTER, 0x05)
    hb_master += 100_000
for node, first in ((IO, hb_start_io + 3_000), (DIO, hb_start_dio + 4_100)):
    at = first
    while at < end:
        heartbeat(jittered(at, 900), node, nmt_state(node, at))
        at += 100_000
toggle = 0
at = guard_start
while at < end:
    request_at = jittered(at, 300)
    send(request_at, 0x700 + DRIVE, ("R", 1))
    heartbeat(request_at + jitter.randint(380, 520), DRIVE, nmt_state(DRIVE, at) | (toggle << 7))
    toggle ^= 1
    at += 100_000

# --- Back to pre-operational at the end. ---
nmt(end - 200_000, 0x80, 0)

# --- Serialise on the bus and print. ---
frames.sort(key=lambda f: (f[0], f[2], f[1]))
bus_free = 0
for scheduled, _, can_id, data in frames:
    begin = max(scheduled, bus_free)
    done = begin + frame_us(data)
    bus_free = done + 3  # interframe space
    if isinstance(data, tuple):
        text = f"{can_id:03X}#R{data[1] if data[1] else ''}"
    else:
        text = f"{can_id:03X}#" + "".join(f"{b:02X}" for b in data)
    print(f"({done // 1_000_000:010d}.{done % 1_000_000:06d}) can0 {text}")
