"""The SDO client of bench/sdo_server.py: python canopen RemoteNodes running one fixed workload against SDO servers.

Usage: sdo_workload.py HOST PORT NODE_ID EDS_PATH EXPEDITED_ROUNDS LARGE_ROUNDS tune|default CHANNEL [CHANNEL ...]

One server per CHANNEL (a bus of the socketcand hub), all at node NODE_ID with the dictionary of EDS_PATH. This one
process is the client of all of them, and it interleaves them: each round does one transfer with every server,
the order alternating from round to round, so a machine that is busier at one moment than at another slows every
server alike and the comparison stays paired. It waits until every server answers, then times, one transfer at a
time:
  expedited_upload    upload of 1018h:01 (EXPEDITED_ROUNDS rounds), compared with the EDS default;
  expedited_download  download of a different 4-byte value to the UNSIGNED32 2007h (EXPEDITED_ROUNDS rounds), each
                      read back untimed and compared;
  segmented_download, segmented_upload
                      889 bytes to and from the DOMAIN 200Fh (LARGE_ROUNDS rounds, different bytes each round), each
                      upload compared with what was downloaded;
  block_download, block_upload
                      the same with SDO block transfer (blksize 127, CRC requested); each block download is read
                      back untimed with a segmented upload and compared.
With "tune" python-can's socketcand client sets TCP_NODELAY and TCP_QUICKACK (`tcp_tune=True`); "default" keeps
python-can's default socket, on which Nagle's algorithm holds back the segments of a block download (sent back to
back) until the hub's delayed ACK.
A failed or wrong transfer ends that kind for that server (its remaining rounds are skipped) and is reported with
the exception, so nothing wrong is ever timed as a success. Prints one JSON object:
{"requests_answered": bool, "results": {CHANNEL: {kind: {"ok": n, "failed": n, "error": str|null,
"times_s": [...]}}}}.
"""

import json
import logging
import struct
import sys
import time

import canopen
from canopen.sdo.exceptions import SdoAbortedError

logging.getLogger("canopen").setLevel(logging.CRITICAL)
logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)

IDENTITY = (0x1018, 1)
U32 = (0x2007, 0)
DOMAIN = (0x200F, 0)
LARGE = 889  # 127 segments of 7 bytes: one full block
READY_TIMEOUT_S = 15.0
KINDS = ["expedited_upload", "expedited_download", "segmented_download", "segmented_upload", "block_download",
         "block_upload"]


def payload(round_idx):
    """889 printable bytes that differ from round to round, so a stale value never passes the comparison."""
    return bytes(0x41 + (i + round_idx) % 26 for i in range(LARGE))


def describe(exc):
    if isinstance(exc, SdoAbortedError):
        return f"SdoAbortedError 0x{exc.code:08X}"
    return f"{type(exc).__name__}: {exc}"


def same(expected):
    return lambda got: None if bytes(got) == expected else f"wrong data: {len(got)} bytes, expected {len(expected)}"


class Kind:
    """The timings and outcome of one kind of transfer with one server."""

    def __init__(self):
        self.times = []
        self.failed = 0
        self.error = None

    def run(self, transfer, check):
        """Times `transfer()`, then `check(result)` untimed; returns False once this kind has failed."""
        if self.error is not None:
            return False
        try:
            start = time.perf_counter()
            result = transfer()
            elapsed = time.perf_counter() - start
            problem = check(result)
        except Exception as exc:  # every failure is a result to report, whatever its class
            problem = describe(exc)
        if problem:
            self.failed += 1
            self.error = problem
            return False
        self.times.append(elapsed)
        return True

    def as_json(self):
        return {"ok": len(self.times), "failed": self.failed, "error": self.error, "times_s": self.times}


class Target:
    """One server: its bus connection, its RemoteNode and its results."""

    def __init__(self, host, port, channel, node_id, eds, tune):
        self.network = canopen.Network()
        self.network.connect(interface="socketcand", host=host, port=port, channel=channel, tcp_tune=tune)
        node = canopen.RemoteNode(node_id, eds)
        self.network.add_node(node)
        self.sdo = node.sdo
        self.sdo.RESPONSE_TIMEOUT = 1.0
        identity = node.object_dictionary.get_variable(*IDENTITY)
        self.identity = identity.encode_raw(identity.value if identity.value is not None else identity.default)
        self.kinds = {kind: Kind() for kind in KINDS}
        self.block_data = None

    def wait_until_answering(self):
        deadline = time.monotonic() + READY_TIMEOUT_S
        while time.monotonic() < deadline:
            try:
                self.sdo.upload(*IDENTITY)
                return True
            except Exception:  # not connected or not booted yet
                time.sleep(0.05)
        return False

    def expedited_upload(self, _round_idx):
        self.kinds["expedited_upload"].run(lambda: self.sdo.upload(*IDENTITY), same(self.identity))

    def expedited_download(self, round_idx):
        value = struct.pack("<I", (0x9E3779B9 * (round_idx + 1)) & 0xFFFFFFFF)
        self.kinds["expedited_download"].run(lambda: self.sdo.download(*U32, value),
                                             lambda _: same(value)(self.sdo.upload(*U32)))

    def segmented(self, round_idx):
        data = payload(round_idx)
        if self.kinds["segmented_download"].run(lambda: self.sdo.download(*DOMAIN, data), lambda _: None):
            self.kinds["segmented_upload"].run(lambda: self.sdo.upload(*DOMAIN), same(data))

    def block(self, round_idx):
        if self.kinds["block_download"].error is not None and self.kinds["block_upload"].error is not None:
            return
        data = payload(round_idx + 13)  # not what the segmented rounds left behind
        if not self.kinds["block_download"].run(lambda: self.block_download(data),
                                                lambda _: same(data)(self.sdo.upload(*DOMAIN))):
            # Without a block download the block upload still gets known bytes to read.
            try:
                self.sdo.download(*DOMAIN, data)
            except Exception as exc:  # reported as the block upload's failure: its data could not be set
                self.kinds["block_upload"].error = f"could not write the bytes to read back: {describe(exc)}"
                return
        self.kinds["block_upload"].run(self.block_upload, same(data))

    def block_download(self, data):
        with self.sdo.open(*DOMAIN, mode="wb", size=len(data), block_transfer=True) as stream:
            stream.write(data)

    def block_upload(self):
        with self.sdo.open(*DOMAIN, mode="rb", block_transfer=True) as stream:
            return stream.read()


def interleaved(targets, rounds, step):
    for round_idx in range(rounds):
        for target in (targets if round_idx % 2 == 0 else targets[::-1]):
            step(target, round_idx)


def main() -> int:
    host, port, node_id, eds = sys.argv[1], int(sys.argv[2]), int(sys.argv[3], 0), sys.argv[4]
    expedited_rounds, large_rounds = int(sys.argv[5]), int(sys.argv[6])
    tune = sys.argv[7] == "tune"
    channels = sys.argv[8:]
    targets = [Target(host, port, channel, node_id, eds, tune) for channel in channels]
    answering = all(target.wait_until_answering() for target in targets)
    if answering:
        interleaved(targets, expedited_rounds, Target.expedited_upload)
        interleaved(targets, expedited_rounds, Target.expedited_download)
        interleaved(targets, large_rounds, Target.segmented)
        interleaved(targets, large_rounds, Target.block)
    for target in targets:
        target.network.disconnect()
    results = {channel: {kind: result.as_json() for kind, result in target.kinds.items()}
               for channel, target in zip(channels, targets)}
    print(json.dumps({"requests_answered": answering, "results": results}), flush=True)
    return 0 if answering else 1


if __name__ == "__main__":
    sys.exit(main())
