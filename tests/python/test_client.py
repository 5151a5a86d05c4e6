"""The Python client (python/omniloc_client) against the real programs: omnilocd-sim publishes to a
PoseReceiver and records; the datagrams are checked against the documented schema and the
simulator's truth, the recording is read back, and a copy written by the client is replayed by
`omniloc replay` exactly as the original. Paths of the programs come from the environment (CTest)."""

import csv
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import unittest
from pathlib import Path

from omniloc_client import (ENCODERS_HEADER, POSE_KEYS, Control, ControlError, DatagramError, PoseReceiver, RecordingError, parse_pose,
                            read_recording, write_recording)
from omniloc_client.datagrams import OPTIONAL_KEYS

OMNILOCD_SIM = os.environ["OMNILOCD_SIM"]
OMNILOC_CLI = os.environ["OMNILOC_CLI"]


def replay(rec: Path, out: Path, db: Path) -> list:
    subprocess.run([OMNILOC_CLI, "replay", str(rec), "--out", str(out), "--db", str(db)], check=True,
                   capture_output=True, text=True, timeout=600)
    with out.open() as f:
        return list(csv.reader(f))


ROOT = Path(__file__).resolve().parents[2]


def daemon_doc_datagram_section() -> str:
    text = (ROOT / "docs" / "DAEMON.md").read_text()
    start = text.index("## UDP pose datagrams")
    return text[start:text.index("\n## ", start + 1)]


class ParsePose(unittest.TestCase):
    # The example datagram of docs/DAEMON.md, as documented (the C++ test checks the daemon writes it).
    GOOD = next(l.strip("`") for l in daemon_doc_datagram_section().splitlines() if l.startswith('`{"seq"'))

    def test_documented_table_is_the_client_schema(self):
        rows = [l for l in daemon_doc_datagram_section().splitlines() if l.startswith("| `")]
        keys, optional = [], []
        for row in rows:
            cells = [c.strip() for c in row.strip("|").split("|")]
            names = [n.strip().strip("`") for n in cells[0].split(",")]
            keys += names
            if "optional" in cells[1]:
                optional += names
        self.assertEqual(tuple(keys), POSE_KEYS)
        self.assertEqual(tuple(optional), OPTIONAL_KEYS)

    def test_optional_clock_uncertainty(self):
        self.assertAlmostEqual(parse_pose(self.GOOD).t_uncertainty_ms, 0.12)
        self.assertIsNone(parse_pose(self.GOOD.replace(',"t_uncertainty_ms":0.120', '')).t_uncertainty_ms)
        with self.assertRaises(DatagramError) as e:
            parse_pose(self.GOOD.replace('"t_uncertainty_ms":0.120', '"t_uncertainty_ms":-1.000'))
        self.assertIn("t_uncertainty_ms", str(e.exception))

    def test_optional_pose_uncertainty(self):
        # Without a pose from a fix (no board, no fix yet) the daemon leaves both keys out: 0 would
        # read as certain.
        p = parse_pose(self.GOOD)
        self.assertEqual((p.uncertainty_cm, p.uncertainty_yaw_deg), (1.5, 0.25))
        bare = self.GOOD.replace(',"uncertainty_cm":1.500,"uncertainty_yaw_deg":0.250', '')
        self.assertNotEqual(bare, self.GOOD)
        q = parse_pose(bare)
        self.assertIsNone(q.uncertainty_cm)
        self.assertIsNone(q.uncertainty_yaw_deg)

    def test_documented_example(self):
        p = parse_pose(self.GOOD)
        self.assertEqual((p.seq, p.x_cm, p.y_cm, p.yaw_deg, p.source, p.match_error, p.status),
                         (42, 375.125, -2.5, 179.75, "integrated", 7.25, "ok"))

    def test_bad_datagrams_name_the_key(self):
        cases = {
            self.GOOD.replace('"status":"ok"', '"status":"fine"'): "status",
            self.GOOD.replace('"seq":42', '"seq":0'): "seq",
            self.GOOD.replace('"x_cm":375.125', '"x_cm":"375"'): "x_cm",
            self.GOOD.replace(',"match_error":7.250', ''): "match_error",
            self.GOOD.replace('"status":"ok"}', '"status":"ok","extra":1}'): "extra",
            "[1,2]": "object",
            "{": "JSON",
        }
        for text, named in cases.items():
            with self.assertRaises(DatagramError) as e:
                parse_pose(text)
            self.assertIn(named, str(e.exception), text)


class ReadmeCommand(unittest.TestCase):
    def test_the_readme_line_runs(self):
        line = next(l for l in (ROOT / "python" / "README.md").read_text().splitlines() if l.startswith("PYTHONPATH="))
        out = subprocess.run(line, shell=True, cwd=ROOT, capture_output=True, text=True, timeout=60)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn(out.stdout.strip().split("(")[0], ("None", "PoseDatagram"))


class AgainstTheSimulatedDaemon(unittest.TestCase):
    def test_datagrams_recording_and_replay(self):
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            rec = tmp / "rec"
            poses, errors = [], []

            def receive_all():
                try:
                    poses.extend(rx)
                except Exception as e:  # a datagram off the schema: fail the test, not just the thread
                    errors.append(e)

            with PoseReceiver(timeout_s=10.0) as rx:
                reader = threading.Thread(target=receive_all)
                reader.start()
                run = subprocess.run([OMNILOCD_SIM, "--duration-s", "2", "--seed", "4", "--udp-port", str(rx.port),
                                      "--record-dir", str(rec), "--status-period-s", "0"],
                                     capture_output=True, text=True, timeout=600)
                rx.timeout_s = 0.5  # the daemon has stopped: drain and end
                reader.join()
                lost = rx.lost
            self.assertEqual(run.returncode, 0, run.stderr)
            self.assertEqual(errors, [])
            print(f"{len(poses)} datagrams, {lost} lost", file=sys.stderr)
            self.assertEqual(len(poses), 200)  # one per 10 ms window for 2 s
            self.assertEqual([p.seq for p in poses], list(range(1, 201)))
            self.assertEqual(lost, 0)

            recording = read_recording(rec)
            self.assertEqual(len(recording.encoders), 200)
            self.assertGreaterEqual(len(recording.frames), 100)  # 60 Hz camera
            self.assertIsNotNone(recording.truth)
            self.assertEqual(recording.meta["field"], "fira-robosot")
            # Against the simulator's truth at the same window times: once fixed, within 10 cm.
            truth = {round(t.t_ms, 3): t for t in recording.truth}
            fixed = [p for p in poses if p.status == "ok" and p.t_ms > 1000.0]
            self.assertGreater(len(fixed), 50)
            for p in fixed:
                t = truth[round(p.t_ms, 3)]
                self.assertLess(((p.x_cm - t.x_cm) ** 2 + (p.y_cm - t.y_cm) ** 2) ** 0.5, 10.0, p)

            # A copy written by the client replays exactly as the original.
            copy = write_recording(recording, tmp / "copy")
            db = tmp / "features.db"
            self.assertEqual(replay(rec, tmp / "a.csv", db), replay(copy, tmp / "b.csv", db))

            # A damaged header is refused by the client and by omniloc replay, both naming the file.
            enc = copy / "encoders.csv"
            enc.write_text(enc.read_text().replace(",".join(ENCODERS_HEADER), "t,seq,c1,c2,c3,c4,gyro"))
            with self.assertRaises(RecordingError) as e:
                read_recording(copy)
            self.assertIn("encoders.csv:1: header must be", str(e.exception))
            bad = subprocess.run([OMNILOC_CLI, "replay", str(copy), "--db", str(db)], capture_output=True, text=True)
            self.assertNotEqual(bad.returncode, 0)
            self.assertIn("encoders.csv:1", bad.stderr)


class ControlAgainstTheSimulatedDaemon(unittest.TestCase):
    def test_commands_and_errors(self):
        with tempfile.TemporaryDirectory() as tmp, PoseReceiver(timeout_s=30.0) as rx:
            probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            probe.bind(("127.0.0.1", 0))
            ctl_port = probe.getsockname()[1]
            probe.close()
            daemon = subprocess.Popen([OMNILOCD_SIM, "--duration-s", "6", "--udp-port", str(rx.port),
                                       "--control-port", str(ctl_port), "--status-period-s", "0"],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            try:
                first = next(iter(rx))  # the daemon is up and publishing
                with Control(ctl_port, timeout_s=5.0) as ctl:
                    st = ctl.status()
                    self.assertIn(st["status"], ("ok", "starting", "odometry_only"))  # the start pose is known
                    self.assertGreaterEqual(st["windows"], 1)
                    reply = ctl.set_pose(200.0, 150.0, first.yaw_deg)
                    self.assertEqual((reply["x_cm"], reply["y_cm"]), (200.0, 150.0))
                    after = next(p for p in rx if p.seq == reply["last_seq"] + 1)
                    self.assertLess(((after.x_cm - 200.0) ** 2 + (after.y_cm - 150.0) ** 2) ** 0.5, 3.0, after)
                    with self.assertRaises(ControlError) as e:
                        ctl.set_pose(float("inf"), 0.0, 0.0)  # json.dumps writes Infinity: not JSON
                    self.assertIn("not valid JSON", str(e.exception))
                    with self.assertRaises(ControlError) as e:
                        ctl.record_stop()
                    self.assertIn("record: not recording", str(e.exception))
                    rec = Path(tmp) / "rec"
                    self.assertEqual(ctl.record_start(rec)["dir"], str(rec))
                    self.assertEqual(ctl.status()["recording"], "on")
                    self.assertEqual(ctl.record_stop()["dir"], str(rec))
                    self.assertEqual(ctl.relocalize()["status"], "lost")
                self.assertTrue((rec / "meta.json").exists())
            finally:
                daemon.wait(timeout=600)
            self.assertEqual(daemon.returncode, 0, daemon.stderr.read())
            with self.assertRaises(ControlError) as e:
                with Control(ctl_port, timeout_s=0.2) as ctl:
                    ctl.status()
            self.assertIn("no reply", str(e.exception))


if __name__ == "__main__":
    unittest.main(verbosity=2)
