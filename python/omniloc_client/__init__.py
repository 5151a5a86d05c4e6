"""omniloc_client: the robot's localization daemon from Python, standard library only.

- ``datagrams``: the UDP pose datagrams ``omnilocd`` publishes (docs/DAEMON.md, "UDP pose
  datagrams"): ``parse_pose`` checks one strictly, ``PoseReceiver`` listens for them.
- ``recording``: recording directories (docs/DAEMON.md, "Recording"): ``read_recording`` and
  ``write_recording``, readable by ``omniloc replay``.

- ``control``: the daemon's control channel (docs/DAEMON.md, "Control channel"): ``Control``
  (status, set_pose, set_side, relocalize, record_start, record_stop), ``ControlError``.
"""

from .control import Control, ControlError
from .datagrams import POSE_KEYS, SOURCES, STATUSES, DatagramError, PoseDatagram, PoseReceiver, parse_pose
from .recording import (CAMERA_HEADER, ENCODERS_HEADER, TRUTH_HEADER, EncoderRow, FrameRow, Recording,
                        RecordingError, TruthRow, read_recording, write_recording)

__all__ = [
    "Control", "ControlError",
    "POSE_KEYS", "SOURCES", "STATUSES", "DatagramError", "PoseDatagram", "PoseReceiver", "parse_pose",
    "CAMERA_HEADER", "ENCODERS_HEADER", "TRUTH_HEADER", "EncoderRow", "FrameRow", "Recording", "RecordingError",
    "TruthRow", "read_recording", "write_recording",
]
