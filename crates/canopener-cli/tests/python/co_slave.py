"""A python `canopen` LocalNode (a CANopen device built from an EDS) on a socketcand hub.

Usage: co_slave.py HOST PORT CHANNEL NODE_ID EDS_PATH

Prints {"ready": true} once connected; on the stdin line "go" it boots (boot-up message, then PRE-OPERATIONAL with
a 100 ms heartbeat) and serves SDO and NMT until stdin closes. Then it prints {"done": true, "sdo_requests": N}.
"""

import json
import logging
import sys

import canopen

logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)


def main() -> int:
    host, port, channel = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    node_id, eds = int(sys.argv[4], 0), sys.argv[5]
    network = canopen.Network()
    network.connect(interface="socketcand", host=host, port=port, channel=channel)
    node = canopen.LocalNode(node_id, eds)
    network.add_node(node)
    requests = {"count": 0}
    network.subscribe(0x600 + node_id, lambda *_: requests.__setitem__("count", requests["count"] + 1))
    print(json.dumps({"ready": True}), flush=True)
    if sys.stdin.readline().strip() != "go":
        return 2
    node.sdo[0x1017].raw = 100
    node.nmt.state = "INITIALISING"  # canopen sends the boot-up message on this transition only
    node.nmt.state = "PRE-OPERATIONAL"  # and starts the heartbeat from 1017h
    sys.stdin.read()  # serve until the driver closes stdin
    node.nmt.stop_heartbeat()
    network.disconnect()
    print(json.dumps({"done": True, "sdo_requests": requests["count"]}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
