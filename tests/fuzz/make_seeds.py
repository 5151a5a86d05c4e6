#!/usr/bin/env python3
"""Writes the binary seed inputs of tests/fuzz/corpus/ that are easier made than typed: link frames
(frame_decoder, board_client) from common/regmap.json's frame types and layouts. The text seeds
(CSV, JSON, numbers, command lines, control requests) are written by hand. Run from anywhere:
python3 tests/fuzz/make_seeds.py (rewrites the generated files only)."""
import json
import os
import struct

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
