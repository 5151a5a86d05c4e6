"""The daemon's control channel (docs/DAEMON.md, "Control channel"): one JSON request per UDP
datagram to 127.0.0.1:<control_port>, one JSON reply back. ``Control`` sends a request and waits
for the reply with the same id; an error reply raises ``ControlError`` with the daemon's text."""

import itertools
import json
import socket

DEFAULT_PORT = 5601


class ControlError(Exception):
    """The daemon refused a request (its "error" text), or did not answer in time."""


class Control:
    """A client of one daemon's control channel. Usable as a context manager."""

    def __init__(self, port: int = DEFAULT_PORT, host: str = "127.0.0.1", timeout_s: float = 1.0):
        self.address = (host, port)
        self.timeout_s = timeout_s
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._ids = itertools.count(1)

    def close(self):
        self._sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def request(self, cmd: str, **fields) -> dict:
        """Sends {"id", "cmd", **fields}; returns the reply's fields (without "id" and "ok")."""
        rid = next(self._ids)
        self._sock.sendto(json.dumps({"id": rid, "cmd": cmd, **fields}).encode(), self.address)
        self._sock.settimeout(self.timeout_s)
        while True:
            try:
                data = self._sock.recv(65536)
            except socket.timeout:
                raise ControlError(f"{cmd}: no reply from {self.address[0]}:{self.address[1]} within "
                                   f"{self.timeout_s} s (is omnilocd running with this control_port?)") from None
            reply = json.loads(data)
            # An error reply with id null answers a request the daemon could not read (ours: one at
            # a time); any other id is a late reply to an earlier request that timed out.
            if reply.get("id") != rid and not (reply.get("id") is None and not reply.get("ok")):
                continue
            if not reply.get("ok"):
                raise ControlError(reply.get("error", "error reply without a text"))
            return {k: v for k, v in reply.items() if k not in ("id", "ok")}

    def status(self) -> dict:
        return self.request("status")

    def set_pose(self, x_cm: float, y_cm: float, yaw_deg: float) -> dict:
        return self.request("set_pose", x_cm=x_cm, y_cm=y_cm, yaw_deg=yaw_deg)

    def set_side(self, side: str) -> dict:
        return self.request("set_side", side=side)

    def relocalize(self) -> dict:
        return self.request("relocalize")

    def record_start(self, directory: str) -> dict:
        return self.request("record", action="start", dir=str(directory))

    def record_stop(self) -> dict:
        return self.request("record", action="stop")
