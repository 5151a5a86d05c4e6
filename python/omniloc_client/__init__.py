"""omniloc_client: the robot's localization daemon from Python, standard library only.

- ``datagrams``: the UDP pose datagrams ``omnilocd`` publishes (docs/DAEMON.md, "UDP pose
  datagrams"): ``parse_pose`` checks one strictly, ``PoseReceiver`` listens for them.
- ``recording``: recording directories (docs/DAEMON.md, "Recording"): ``read_recording`` and
  ``write_recording``, readable by ``omniloc replay``.

The control channel (set_pose, set_side, relocalize, record) is not in the daemon yet (issue [4/6]);
its client belongs here when it is.
"""

from .datagrams import POSE_KEYS, SOURCES, STATUSES, DatagramError, PoseDatagram, PoseReceiver, parse_pose
from .recording import (CAMERA_HEADER, ENCODERS_HEADER, TRUTH_HEADER, EncoderRow, FrameRow, Recording,
                        RecordingError, TruthRow, read_recording, write_recording)

__all__ = [
    "POSE_KEYS", "SOURCES", "STATUSES", "DatagramError", "PoseDatagram", "PoseReceiver", "parse_pose",
    "CAMERA_HEADER", "ENCODERS_HEADER", "TRUTH_HEADER", "EncoderRow", "FrameRow", "Recording", "RecordingError",
    "TruthRow", "read_recording", "write_recording",
]
