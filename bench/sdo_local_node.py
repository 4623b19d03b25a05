"""The baseline SDO server of bench/sdo_server.py: a python canopen LocalNode built from an EDS, on a socketcand hub.

Usage: sdo_local_node.py HOST PORT CHANNEL NODE_ID EDS_PATH [tune|default]

Connects, boots the way the simulator does (boot-up message, then PRE-OPERATIONAL with the heartbeat period 1017h
has in the EDS) and prints {"ready": true}. It then serves SDO and NMT until stdin closes, and prints
{"done": true, "sdo_requests": N} (N = request frames seen on 600h + node-ID).
With "tune" (the default) python-can's socketcand client sets TCP_NODELAY and TCP_QUICKACK (`tcp_tune=True`), as
canopener's own socketcand client and hub set TCP_NODELAY: without it Nagle's algorithm can hold back frames sent
in a burst until the peer's delayed ACK (tens of ms).
"""

import json
import logging
import sys

import canopen

# The LocalNode logs every refused request (block transfers among them) at ERROR level; the client reports them.
logging.getLogger("canopen").setLevel(logging.CRITICAL)
logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)


def main() -> int:
    host, port, channel = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    node_id, eds = int(sys.argv[4], 0), sys.argv[5]
    tune = (sys.argv[6] if len(sys.argv) > 6 else "tune") == "tune"
    network = canopen.Network()
    network.connect(interface="socketcand", host=host, port=port, channel=channel, tcp_tune=tune)
    node = canopen.LocalNode(node_id, eds)
    network.add_node(node)
    requests = {"count": 0}
    network.subscribe(0x600 + node_id, lambda *_: requests.__setitem__("count", requests["count"] + 1))
    node.nmt.state = "INITIALISING"  # python canopen sends the boot-up message on this transition only
    node.nmt.state = "PRE-OPERATIONAL"  # and starts the heartbeat from 1017h
    print(json.dumps({"ready": True}), flush=True)
    sys.stdin.read()  # serve until the driver closes stdin
    node.nmt.stop_heartbeat()
    network.disconnect()
    print(json.dumps({"done": True, "sdo_requests": requests["count"]}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
