"""The pose datagrams of omnilocd: one JSON object per 10 ms board window (docs/DAEMON.md)."""

from __future__ import annotations

import json
import math
import socket
from dataclasses import dataclass
from typing import Iterator, Optional

# The documented keys, in the order the daemon writes them. match_error and search_range_cm are
# absent before the first image result, t_uncertainty_ms while t_ms is not a board time (no board).
POSE_KEYS = ("seq", "t_ms", "t_uncertainty_ms", "x_cm", "y_cm", "yaw_deg", "source", "match_error", "search_range_cm",
             "uncertainty_cm", "uncertainty_yaw_deg", "vx_cm_s", "vy_cm_s", "omega_deg_s", "mono_ms", "wall_ms",
             "status")
OPTIONAL_KEYS = ("t_uncertainty_ms", "match_error", "search_range_cm", "uncertainty_cm", "uncertainty_yaw_deg")
SOURCES = ("none", "image", "integrated", "odometry", "lost")
STATUSES = ("no_board", "degraded", "odometry_only", "starting", "lost", "ok")


class DatagramError(ValueError):
    """A datagram that is not a pose of the documented schema (the message says which key)."""


@dataclass(frozen=True)
class PoseDatagram:
    seq: int
    t_ms: float
    t_uncertainty_ms: Optional[float]
    x_cm: float
    y_cm: float
    yaw_deg: float
    source: str
    match_error: Optional[float]
    search_range_cm: Optional[float]
    uncertainty_cm: Optional[float]
    uncertainty_yaw_deg: Optional[float]
    vx_cm_s: float
    vy_cm_s: float
    omega_deg_s: float
    mono_ms: float
    wall_ms: float
    status: str


def _number(obj: dict, key: str) -> float:
    v = obj[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise DatagramError(f"{key}: must be a finite number (got {v!r})")
    return float(v)


def parse_pose(data: bytes | str) -> PoseDatagram:
    """One datagram to a PoseDatagram; raises DatagramError for anything off the schema."""
    try:
        obj = json.loads(data)
    except (ValueError, UnicodeDecodeError) as e:
        raise DatagramError(f"not JSON: {e}") from None
    if not isinstance(obj, dict):
        raise DatagramError(f"not a JSON object (got {type(obj).__name__})")
    unknown = [k for k in obj if k not in POSE_KEYS]
    if unknown:
        raise DatagramError(f"unknown key {unknown[0]!r}")
    missing = [k for k in POSE_KEYS if k not in obj and k not in OPTIONAL_KEYS]
    if missing:
        raise DatagramError(f"missing key {missing[0]!r}")
    if list(obj) != [k for k in POSE_KEYS if k in obj]:
        raise DatagramError(f"keys out of the documented order: {list(obj)}")
    seq = obj["seq"]
    if isinstance(seq, bool) or not isinstance(seq, int) or seq < 1:
        raise DatagramError(f"seq: must be an integer >= 1 (got {seq!r})")
    if obj["source"] not in SOURCES:
        raise DatagramError(f"source: must be one of {', '.join(SOURCES)} (got {obj['source']!r})")
    if obj["status"] not in STATUSES:
        raise DatagramError(f"status: must be one of {', '.join(STATUSES)} (got {obj['status']!r})")
    if ("match_error" in obj) != ("search_range_cm" in obj):
        raise DatagramError("match_error and search_range_cm come together")
    t_uncertainty_ms = _number(obj, "t_uncertainty_ms") if "t_uncertainty_ms" in obj else None
    if t_uncertainty_ms is not None and t_uncertainty_ms < 0:
        raise DatagramError(f"t_uncertainty_ms: must be >= 0 (got {t_uncertainty_ms!r})")
    return PoseDatagram(
        seq=seq, t_ms=_number(obj, "t_ms"), t_uncertainty_ms=t_uncertainty_ms, x_cm=_number(obj, "x_cm"), y_cm=_number(obj, "y_cm"),
        yaw_deg=_number(obj, "yaw_deg"), source=obj["source"],
        match_error=_number(obj, "match_error") if "match_error" in obj else None,
        search_range_cm=_number(obj, "search_range_cm") if "search_range_cm" in obj else None,
        uncertainty_cm=_number(obj, "uncertainty_cm") if "uncertainty_cm" in obj else None,
        uncertainty_yaw_deg=_number(obj, "uncertainty_yaw_deg") if "uncertainty_yaw_deg" in obj else None,
        vx_cm_s=_number(obj, "vx_cm_s"), vy_cm_s=_number(obj, "vy_cm_s"), omega_deg_s=_number(obj, "omega_deg_s"),
        mono_ms=_number(obj, "mono_ms"), wall_ms=_number(obj, "wall_ms"), status=obj["status"])


class PoseReceiver:
    """Listens for pose datagrams on a UDP port (0: a free one, see ``port``).

    ``receive(timeout_s)`` returns the next pose or None after the timeout; iterating yields poses
    until ``timeout_s`` passes without one. ``lost`` counts the gaps in ``seq`` seen so far.
    """

    def __init__(self, port: int = 0, address: str = "127.0.0.1", timeout_s: float = 1.0):
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._sock.bind((address, port))
        self.port: int = self._sock.getsockname()[1]
        self.timeout_s = timeout_s
        self.lost = 0
        self._last_seq: Optional[int] = None

    def receive(self, timeout_s: Optional[float] = None) -> Optional[PoseDatagram]:
        self._sock.settimeout(self.timeout_s if timeout_s is None else timeout_s)
        try:
            data, _ = self._sock.recvfrom(65536)
        except socket.timeout:
            return None
        pose = parse_pose(data)
        if self._last_seq is not None and pose.seq > self._last_seq + 1:
            self.lost += pose.seq - self._last_seq - 1
        self._last_seq = pose.seq
        return pose

    def __iter__(self) -> Iterator[PoseDatagram]:
        while (pose := self.receive()) is not None:
            yield pose

    def close(self) -> None:
        self._sock.close()

    def __enter__(self) -> "PoseReceiver":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
