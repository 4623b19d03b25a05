"""Baseline for BENCHMARKS.md: a minimal socketcand hub in pure Python (stdlib selectors, one thread).

It implements the same semantics as `canopener bus serve` (handshake replies sent alone, 20 ms hold-back after
rawmode, delivery to every other raw client of the bus, lossless with a per-client output buffer) so that
python-can and python canopen can be measured through both hubs in one run. It is deliberately simple: the
kind of hub a Python user would write. Not used by any test.

Usage: baseline_hub.py PORT   (prints "listening on PORT" when ready)
"""

import selectors
import socket
import sys
import time

HOLD_BACK_S = 0.020


class Client:
    def __init__(self, sock):
        self.sock = sock
        self.inbuf = b""
        self.outbuf = bytearray()
        self.bus = None
        self.raw = False
        self.hold_until = 0.0
        self.held = bytearray()


def main() -> int:
    port = int(sys.argv[1])
    sel = selectors.DefaultSelector()
    server = socket.socket()
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind(("127.0.0.1", port))
    server.listen(128)
    server.setblocking(False)
    sel.register(server, selectors.EVENT_READ, None)
    clients = {}
    print(f"listening on {server.getsockname()[1]}", flush=True)

    def want_write(client):
        events = selectors.EVENT_READ | (selectors.EVENT_WRITE if client.outbuf else 0)
        sel.modify(client.sock, events, client)

    def reply(client, text):
        # Each reply in its own send, as python-can reads it with one recv.
        client.sock.sendall(text.encode())

    def drop(client):
        sel.unregister(client.sock)
        client.sock.close()
        clients.pop(client.sock, None)

    def broadcast(sender, frames):
        for other in list(clients.values()):
            if other is sender or not other.raw or other.bus != sender.bus:
                continue
            # Frames keep queueing behind held ones until the hold is flushed, or they would overtake them.
            if time.monotonic() < other.hold_until or other.held:
                other.held += frames
            else:
                other.outbuf += frames
                want_write(other)

    while True:
        now = time.monotonic()
        for client in list(clients.values()):
            if client.held and now >= client.hold_until:
                client.outbuf += client.held
                client.held = bytearray()
                want_write(client)
        for key, events in sel.select(timeout=0.005):
            if key.data is None:
                sock, _ = server.accept()
                sock.setblocking(True)
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                client = Client(sock)
                clients[sock] = client
                reply(client, "< hi >")
                sock.setblocking(False)
                sel.register(sock, selectors.EVENT_READ, client)
                continue
            client = key.data
            if events & selectors.EVENT_WRITE and client.outbuf:
                try:
                    sent = client.sock.send(client.outbuf)
                    del client.outbuf[:sent]
                except BlockingIOError:
                    pass
                except OSError:
                    drop(client)
                    continue
                want_write(client)
            if not events & selectors.EVENT_READ:
                continue
            try:
                data = client.sock.recv(65536)
            except BlockingIOError:
                continue
            except OSError:
                data = b""
            if not data:
                drop(client)
                continue
            client.inbuf += data
            frames = bytearray()
            stamp = time.time()
            while True:
                start = client.inbuf.find(b"<")
                end = client.inbuf.find(b">", start + 1)
                if start < 0 or end < 0:
                    break
                tokens = client.inbuf[start + 1:end].decode("ascii", "replace").split()
                client.inbuf = client.inbuf[end + 1:]
                if not tokens:
                    continue
                verb = tokens[0]
                if verb == "open" and len(tokens) == 2:
                    client.bus = tokens[1]
                    client.sock.setblocking(True)
                    reply(client, "< ok >")
                    client.sock.setblocking(False)
                elif verb == "rawmode":
                    client.sock.setblocking(True)
                    reply(client, "< ok >")
                    client.sock.setblocking(False)
                    client.raw = True
                    client.hold_until = time.monotonic() + HOLD_BACK_S
                elif verb == "send" and len(tokens) >= 3 and client.raw:
                    try:
                        length = int(tokens[2])
                        payload = "".join(f"{int(b, 16):02X}" for b in tokens[3:3 + length])
                    except ValueError:
                        continue
                    if len(tokens) != 3 + length:
                        continue
                    secs = int(stamp)
                    usecs = int((stamp - secs) * 1e6)
                    frames += f"< frame {tokens[1]} {secs}.{usecs:06d} {payload} >".encode()
            if frames:
                broadcast(client, frames)


if __name__ == "__main__":
    sys.exit(main())
