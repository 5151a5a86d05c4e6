#!/usr/bin/env python3
"""Writes the binary seed inputs of tests/fuzz/corpus/ that are easier made than typed: link frames
(frame_decoder, board_client) from common/regmap.json's frame types and layouts. The text seeds
(CSV, JSON, numbers, command lines, control requests) are written by hand. Run from anywhere:
python3 tests/fuzz/make_seeds.py (rewrites the generated files only).

With --omniloc PATH (the built `omniloc` program) it also writes the feature_db seeds: databases of
tests/fuzz/feature_db_field.json built by `omniloc builddb` at 10, 15, 20 and 30 cm, and broken
variants of them (header fields patched; byte 0 of each seed is the harness's mode, fuzz_feature_db.cpp)."""
import argparse
import json
import math
import os
import struct
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPUS = os.path.join(ROOT, "tests", "fuzz", "corpus")
regmap = json.load(open(os.path.join(ROOT, "common", "regmap.json")))
frames = regmap["frames"]
SYNC = int(frames["sync"], 16)
SIZES = {"u8": 1, "i8": 1, "u16": 2, "i16": 2, "u32": 4, "i32": 4}
layout_bytes = {l["name"]: sum(SIZES[f["type"]] * f.get("count", 1) for f in l["fields"]) for l in frames["layouts"]}
TYPES = {t["name"]: (int(t["code"], 16), layout_bytes[t["layout"]]) for t in frames["types"]}


def crc16(data):
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def frame(name, body=b""):
    code, size = TYPES[name]
    body = body.ljust(size, b"\0")[:size]
    inner = bytes([size + 1, code]) + body
    return bytes([SYNC]) + inner + struct.pack(">H", crc16(inner))


def window(seq, t=1000, counts=(10, -20, 30, -40), d=0b1010, status=1):
    return struct.pack("<II4iBB", seq, t, *counts, d, status)


def write(harness, name, data):
    d = os.path.join(CORPUS, harness)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


every = b"".join([frame("READ_REQ", b"\x00"), frame("WRITE_REQ", b"\x01\x05\0\0\0"), frame("SNAPSHOT_REQ"),
                  frame("READ_RESP", b"\x00\x4c\x4f\x4d\x4f"), frame("WRITE_ACK", b"\x01"),
                  frame("SNAPSHOT_RESP", window(7)), frame("TELEMETRY", window(8)), frame("ERROR", b"\x01\x1f")])
telemetry = b"".join(frame("TELEMETRY", window(s)) for s in (1, 2, 4, 4, 3, 0xFFFFFFFF, 5))
good = frame("READ_RESP", b"\x02\x01\0\0\0")
garbage = b"\xa5\x06\x81\x00" + bytes([SYNC, 0x02, 0x90]) + good[:-1] + bytes([good[-1] ^ 1]) + b"\x00\xa5" + good
# frame_decoder: first byte chooses the chunking, the rest is the stream.
write("frame_decoder", "every_type", b"\x00" + every)
write("frame_decoder", "telemetry_gaps_and_stale", b"\x07" + telemetry)
write("frame_decoder", "garbage_between", b"\x21" + garbage)
write("frame_decoder", "truncated_tail", b"\x03" + every + frame("TELEMETRY", window(9))[:-3])

# board_client: 2 bytes of operations (3 bits each, fuzz_board_client.cpp), then the board's script.
T = {name: i for i, name in enumerate(t["name"] for t in frames["types"])}


def ops(*codes):
    v = 0
    for k, c in enumerate(codes):
        v |= c << (3 * k)
    return struct.pack("<H", v)


def step_frame(name, body=b""):
    return bytes([0x40 | T[name]]) + body.ljust(TYPES[name][1], b"\0")[:TYPES[name][1]]


def step_raw(data):
    return bytes([len(data) - 1]) + data


TIMEOUT, GONE = b"\xc0", b"\xfe"
read_id = step_frame("READ_RESP", b"\x00\x4c\x4f\x4d\x4f")
write_board = "board_client"
write(write_board, "read_id_answered", ops(0, 0, 0, 0, 0) + read_id * 5)
write(write_board, "read_after_timeouts_and_late_answer",
      ops(1, 0, 0, 0, 0) + TIMEOUT + step_frame("READ_RESP", b"\x00\x01\0\0\0") + TIMEOUT + TIMEOUT +
      step_frame("READ_RESP", b"\x02\x00\0\0\0") + read_id * 4)
write(write_board, "streaming_on_with_telemetry",
      ops(4, 6, 7, 3, 5) + step_frame("READ_RESP", b"\x02\x00\0\0\0") + step_frame("TELEMETRY", window(1)) +
      step_frame("WRITE_ACK", b"\x02") + step_frame("TELEMETRY", window(2)) + step_frame("TELEMETRY", window(2)) +
      step_frame("SNAPSHOT_RESP", window(3)) + step_frame("READ_RESP", b"\x02\x01\0\0\0") + step_frame("WRITE_ACK", b"\x02"))
write(write_board, "errors_bad_crc_then_refused",
      ops(2, 1, 0, 0, 0) + step_frame("ERROR", b"\x04\x02") + step_frame("ERROR", b"\x01\x02") +
      step_raw(b"\xa5\x06\x81\x02\x00\x00\x00\x00\x12\x34") + step_frame("WRITE_ACK", b"\x02") + GONE)
write(write_board, "garbage_and_unplug", ops(3, 0, 0, 0, 0) + step_raw(bytes(range(0xa0, 0xb0))) + TIMEOUT * 3 + GONE)


# feature_db: byte 0 is the mode (bit 0: the harness fixes the fingerprints and the checksum), the
# rest the file. Header offsets (docs/VISION.md): nx 16, ny 20, x0 24, y0 32, step 40, field
# fingerprint 56, camera fingerprint 64, payload bytes 72, radius step (px) 80, 88 bytes in all (format
# version 2); the FNV-1a 64 checksum is the last 8 bytes.
def fnv1a64(data):
    h = 0xcbf29ce484222325
    for b in data:
        h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return h


def resum(db):
    return db[:-8] + struct.pack("<Q", fnv1a64(db[:-8]))


def patch(db, offset, fmt, value):
    return resum(db[:offset] + struct.pack(fmt, value) + db[offset + struct.calcsize(fmt):])


def feature_db_seeds(omniloc):
    field = os.path.join(ROOT, "tests", "fuzz", "feature_db_field.json")
    dbs = {}
    with tempfile.TemporaryDirectory() as tmp:
        for step in (10, 15, 20, 30):
            out = os.path.join(tmp, f"s{step}.db")
            # At 20 and 30 cm the field's grid has one point along a side: builddb writes the file,
            # then its read-back refuses it (exit 1), which is what those seeds are for.
            subprocess.run([omniloc, "builddb", "--field", field, "--camera", "default", "--step", str(step),
                            "--threads", "1", "--out", out], check=step < 20, capture_output=True)
            dbs[step] = open(out, "rb").read()
    h = "feature_db"
    for step in (10, 15):
        write(h, f"valid_{step}cm", b"\x00" + dbs[step])
    # The field's own grids at 20 and 30 cm have one point along a side: refused.
    write(h, "covering_2x1_at_20cm", b"\x00" + dbs[20])
    write(h, "covering_1x1_at_30cm", b"\x01" + dbs[30])
    write(h, "valid_10cm_fixup", b"\x01" + dbs[10])
    write(h, "valid_15cm_raycast_local30", b"\x0f" + dbs[15])
    d = dbs[10]
    # Grid nonsense with a valid checksum (raw) or left to the harness's fix-up.
    write(h, "nan_origin", b"\x00" + patch(d, 24, "<d", math.nan))
    write(h, "inf_y_origin", b"\x01" + patch(d, 32, "<d", math.inf))
    write(h, "inf_step", b"\x00" + patch(d, 40, "<d", math.inf))
    write(h, "zero_step", b"\x01" + patch(d, 40, "<d", 0.0))
    write(h, "negative_step", b"\x00" + patch(d, 40, "<d", -10.0))
    write(h, "tiny_step", b"\x00" + patch(d, 40, "<d", 1e-300))
    write(h, "shifted_origin", b"\x00" + patch(d, 24, "<d", 6.0))
    write(h, "other_step", b"\x00" + patch(d, 40, "<d", 20.0))
    one = d[:88 + 1440] + b"\0" * 8
    one = one[:16] + struct.pack("<ii", 1, 1) + one[24:72] + struct.pack("<Q", 1440) + one[80:]
    write(h, "one_by_one_at_10cm", b"\x00" + resum(one))
    write(h, "nx_swapped", b"\x00" + resum(d[:16] + struct.pack("<ii", 3, 4) + d[24:]))
    write(h, "negative_nx", b"\x01" + d[:16] + struct.pack("<i", -4) + d[20:])
    write(h, "payload_size_wrong", b"\x00" + patch(d, 72, "<Q", 1440 * 11))
    write(h, "truncated", b"\x00" + d[:-1])
    write(h, "one_byte_more", b"\x01" + d + b"\0")
    write(h, "header_only", b"\x00" + d[:88])
    write(h, "checksum_wrong", b"\x00" + d[:-1] + bytes([d[-1] ^ 1]))
    write(h, "other_field", b"\x00" + patch(d, 56, "<Q", 0x1234))
    write(h, "other_camera", b"\x00" + patch(d, 64, "<Q", 0x1234))
    write(h, "version_1", b"\x00" + patch(d, 8, "<I", 1))
    write(h, "other_radius_step", b"\x01" + patch(d, 80, "<d", 2.0))
    write(h, "not_a_database", b"\x00" + b"OMNIFDX\0" + d[8:])
    write(h, "empty", b"\x00")


parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--omniloc", help="the built omniloc program: also write the feature_db seeds")
args = parser.parse_args()
if args.omniloc:
    feature_db_seeds(args.omniloc)
