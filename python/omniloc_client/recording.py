"""Recording directories as omnilocd writes them and ``omniloc replay`` reads them (docs/DAEMON.md,
"Recording"): meta.json, encoders.csv, camera.csv with frames/NNNNNN.png, and truth.csv when a
simulator made it. Frames are kept as files (the standard library has no PNG decoder); the other
CSV files of a recording (heading.csv: the heading's trust and the board's raw gyro windows, and
the clock and frame-time logs) are kept verbatim, so a copy replays as the original does."""

from __future__ import annotations

import csv
import json
import math
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional

ENCODERS_HEADER = ("t_ms", "seq", "c1", "c2", "c3", "c4", "gyro_yaw_deg")
CAMERA_HEADER = ("t_ms", "file")
TRUTH_HEADER = ("t_ms", "x_cm", "y_cm", "yaw_deg")


class RecordingError(ValueError):
    """A recording that does not follow the contract; the message names the file and line."""


@dataclass(frozen=True)
class EncoderRow:
    t_ms: float
    seq: int
    counts: tuple  # four signed wheel counts of the 10 ms window
    gyro_yaw_deg: float


@dataclass(frozen=True)
class FrameRow:
    t_ms: float
    file: str  # relative to the recording directory


@dataclass(frozen=True)
class TruthRow:
    t_ms: float
    x_cm: float
    y_cm: float
    yaw_deg: float


@dataclass
class Recording:
    meta: dict
    encoders: List[EncoderRow] = field(default_factory=list)
    frames: List[FrameRow] = field(default_factory=list)
    truth: Optional[List[TruthRow]] = None
    directory: Optional[Path] = None  # where it was read from (frame files are there)
    other_files: dict = field(default_factory=dict)  # name -> text of the CSV files not parsed here


def _rows(path: Path, header: tuple):
    try:
        with path.open(newline="") as f:
            reader = csv.reader(f)
            got = next(reader, None)
            if got is None:
                raise RecordingError(f"{path}:1: empty file (no header)")
            if tuple(got) != header:
                raise RecordingError(f"{path}:1: header must be '{','.join(header)}' (got '{','.join(got)}')")
            for line, row in enumerate(reader, start=2):
                if len(row) != len(header):
                    raise RecordingError(f"{path}:{line}: expected {len(header)} columns, got {len(row)}")
                yield line, row
    except OSError as e:
        raise RecordingError(f"{path}: {e.strerror}") from None


def _float(text: str, path: Path, line: int, column: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise RecordingError(f"{path}:{line}: column '{column}': not a number ('{text}')") from None
    if not math.isfinite(v):
        raise RecordingError(f"{path}:{line}: column '{column}': not finite ('{text}')")
    return v


def _int(text: str, path: Path, line: int, column: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise RecordingError(f"{path}:{line}: column '{column}': not an integer ('{text}')") from None


def read_recording(directory: str | Path) -> Recording:
    d = Path(directory)
    try:
        meta = json.loads((d / "meta.json").read_text())
    except OSError as e:
        raise RecordingError(f"{d / 'meta.json'}: {e.strerror}") from None
    except ValueError as e:
        raise RecordingError(f"{d / 'meta.json'}: not JSON: {e}") from None
    rec = Recording(meta=meta, directory=d)
    path = d / "encoders.csv"
    for line, r in _rows(path, ENCODERS_HEADER):
        rec.encoders.append(EncoderRow(_float(r[0], path, line, "t_ms"), _int(r[1], path, line, "seq"),
                                       tuple(_int(r[i], path, line, f"c{i - 1}") for i in range(2, 6)),
                                       _float(r[6], path, line, "gyro_yaw_deg")))
    path = d / "camera.csv"
    if path.exists():
        for line, r in _rows(path, CAMERA_HEADER):
            rec.frames.append(FrameRow(_float(r[0], path, line, "t_ms"), r[1]))
    path = d / "truth.csv"
    if path.exists():
        rec.truth = [TruthRow(*(_float(r[i], path, line, TRUTH_HEADER[i]) for i in range(4)))
                     for line, r in _rows(path, TRUTH_HEADER)]
    for path in sorted(d.glob("*.csv")):
        if path.name not in ("encoders.csv", "camera.csv", "truth.csv"):
            rec.other_files[path.name] = path.read_text()
    return rec


def write_recording(rec: Recording, directory: str | Path) -> Path:
    """Writes ``rec`` as a new recording directory (refused if it exists); frame files are copied
    from ``rec.directory``."""
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=False)
    (d / "meta.json").write_text(json.dumps(rec.meta, indent=2) + "\n")
    with (d / "encoders.csv").open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(ENCODERS_HEADER)
        for e in rec.encoders:
            w.writerow([f"{e.t_ms:.6f}", e.seq, *e.counts, f"{e.gyro_yaw_deg:.6f}"])
    with (d / "camera.csv").open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(CAMERA_HEADER)
        for fr in rec.frames:
            w.writerow([f"{fr.t_ms:.6f}", fr.file])
            if rec.directory is not None:
                (d / fr.file).parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(rec.directory / fr.file, d / fr.file)
    if rec.truth is not None:
        with (d / "truth.csv").open("w", newline="") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(TRUTH_HEADER)
            for t in rec.truth:
                w.writerow([f"{t.t_ms:.6f}", f"{t.x_cm:.6f}", f"{t.y_cm:.6f}", f"{t.yaw_deg:.6f}"])
    for name, text in rec.other_files.items():
        (d / name).write_text(text)
    return d
