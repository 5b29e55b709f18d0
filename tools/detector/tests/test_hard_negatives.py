"""Hard negatives: mine_negatives.py lists a detector's false detections on training frames, and
train.py --hard-negatives centres a share of those frames' tiles on them."""

import csv
import io
import math
import os
import tempfile
import unittest
from contextlib import redirect_stderr, redirect_stdout
from unittest import mock

import numpy as np

import _common  # noqa: F401
from detector import augment, mine_negatives, train
from detector.datasets import read_sequence
from test_train_smoke import write_synthetic_sequence

HEADER = ("frame_id,det_id,score,box_cx_px,box_cy_px,box_length_px,box_width_px,box_angle_rad,"
          "type\n")


class HardNegatives(unittest.TestCase):
    def setUp(self):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.root = tmp.name
        self.seq = os.path.join(tmp.name, "seq_7")
        write_synthetic_sequence(self.seq, frames=2)
        self.frames = read_sequence(self.seq, max_occlusion=1.0, max_truncation=1.0)
        self.dets = os.path.join(tmp.name, "dets")
        os.makedirs(self.dets)

    def write_detections(self, rows, name="seq_7"):
        with open(os.path.join(self.dets, name + ".csv"), "w") as f:
            f.write("# format_version: 1\n" + HEADER)
            for r in rows:
                f.write(",".join(str(v) for v in r) + ",sedan\n")

    def empty_spot(self, frame):
        """A point of the frame at least 30 px from every vehicle's centre."""
        boxes = self.frames[frame].boxes
        for y in range(8, 128, 4):
            for x in range(8, 128, 4):
                if np.hypot(boxes[:, 0] - x, boxes[:, 1] - y).min() > 30:
                    return float(x), float(y)
        self.fail("synthetic frame without an empty spot")

    def test_mines_confident_detections_that_overlap_no_vehicle(self):
        car = self.frames[0].boxes[0]
        x, y = self.empty_spot(1)
        self.write_detections([
            (0, 0, 0.9, *car),                      # a vehicle: not a negative
            (1, 0, 0.6, x, y, 24.0, 10.0, 0.3),     # background: a negative
            (1, 1, 0.2, x, y, 24.0, 10.0, 0.3),     # background, below --min-score
        ])
        rows, counts = mine_negatives.mine([self.seq], self.dets, min_score=0.4, max_iou=0.1)
        self.assertEqual(counts, {"seq_7": 1})
        self.assertEqual(len(rows), 1)
        image, cx, cy, score = rows[0]
        self.assertEqual(image, os.path.abspath(self.frames[1].image_path))
        self.assertEqual((cx, cy, score), (x, y, 0.6))

        out = os.path.join(self.root, "neg", "negatives.csv")
        with redirect_stderr(io.StringIO()), redirect_stdout(io.StringIO()):
            self.assertEqual(mine_negatives.main(["--data", self.seq, "--detections", self.dets,
                                                  "--out", out]), 0)
        with open(out, newline="") as f:
            written = list(csv.DictReader(f))
        self.assertEqual([(r["image"], float(r["cx_px"]), float(r["cy_px"])) for r in written],
                         [(image, x, y)])

    def test_refuses_missing_or_malformed_detections(self):
        def refusal():
            err = io.StringIO()
            with redirect_stderr(err):
                code = mine_negatives.main(["--data", self.seq, "--detections", self.dets,
                                            "--out", os.path.join(self.root, "n.csv")])
            self.assertEqual(code, 1)
            return err.getvalue()

        self.assertIn("no detections for sequence", refusal())
        with open(os.path.join(self.dets, "seq_7.csv"), "w") as f:
            f.write("frame_id,score\n0,0.5\n")
        self.assertIn("not a detections CSV", refusal())

    def negatives_file(self, rows, name="negatives.csv"):
        path = os.path.join(self.root, name)
        with open(path, "w") as f:
            f.write("image,cx_px,cy_px,score\n")
            for r in rows:
                f.write(",".join(str(v) for v in r) + "\n")
        return path

    def test_training_reads_the_list_per_frame_and_names_a_bad_row(self):
        path = self.negatives_file([
            (self.frames[1].image_path, 40.0, 50.0, 0.6),
            (self.frames[1].image_path, 41.0, 51.0, 0.5),
            ("/elsewhere/frames/000000.png", 10.0, 10.0, 0.7),  # not a training frame: skipped
        ])
        negatives = train.read_hard_negatives(path, self.frames)
        self.assertEqual(list(negatives), [1])
        np.testing.assert_array_equal(negatives[1], [[40.0, 50.0], [41.0, 51.0]])
        bad = self.negatives_file([(self.frames[0].image_path, "x", 5.0, 0.5)], "bad.csv")
        with self.assertRaises(SystemExit) as e:
            train.read_hard_negatives(bad, self.frames)
        self.assertIn("bad.csv:2: cx_px, cy_px", str(e.exception))
        with self.assertRaises(SystemExit) as e:
            train.train(train.parse_args(["--data", self.seq, "--out",
                                          os.path.join(self.root, "run"),
                                          "--negative-share", "1.5"]))
        self.assertIn("--negative-share", str(e.exception))

    def test_listed_frames_give_tiles_around_their_negatives(self):
        points = [(self.frames[0].image_path, 100.0, 20.0, 0.6),
                  (self.frames[1].image_path, 30.0, 110.0, 0.6)]
        path = self.negatives_file(points)
        args = train.parse_args(["--data", self.seq, "--out", os.path.join(self.root, "run"),
                                 "--tile", "48", "--working-width", "128",
                                 "--hard-negatives", path, "--negative-share", "1"])
        data = train.Data(args, 3, log=lambda *_: None)
        calls = []
        crop_near = augment.crop_near

        def spy(s, point, size, rng):
            calls.append((s.image.shape[1], s.image.shape[0], point))
            return crop_near(s, point, size, rng)

        rng = np.random.default_rng(3)
        with mock.patch.object(train.augment, "crop_near", side_effect=spy):
            for _ in range(8):
                self.assertEqual(data.tile(rng).image.shape[:2], (48, 48))
        self.assertEqual(len(calls), 8)  # every tile: both frames are listed, share 1
        def at_a_negative(call):
            width, height, (u, v) = call
            fx, fy = width / 128.0, height / 128.0  # the frame as scaled for this tile
            a, b = (u + 0.5) / fx - 0.5, (v + 0.5) / fy - 0.5  # back in the stored frame
            return any(math.isclose(a, p[1], abs_tol=1e-6) and math.isclose(b, p[2], abs_tol=1e-6)
                       for p in points)

        self.assertTrue(all(at_a_negative(c) for c in calls), calls)

        args.negative_share = 0.0
        data = train.Data(args, 3, log=lambda *_: None)
        calls.clear()
        with mock.patch.object(train.augment, "crop_near", side_effect=spy):
            for _ in range(8):
                data.tile(rng)
        # Share 0: object-centred tiles (crop_near around a vehicle) or uniform ones only.
        self.assertFalse(any(at_a_negative(c) for c in calls), calls)

    def test_crop_near_keeps_the_point_in_the_window(self):
        frame = self.frames[0].loaded()
        one = np.zeros(len(frame), bool)
        one[0] = True
        rng = np.random.default_rng(0)
        for point in [(5.0, 5.0), (64.0, 64.0), (120.0, 100.0)]:
            s = frame.subset(one)  # one small marker object at the point shows where it went
            s.boxes[0] = [point[0], point[1], 4.0, 4.0, 0.0]
            for _ in range(20):
                t = augment.crop_near(s, point, (48, 48), rng)
                self.assertEqual(t.image.shape[:2], (48, 48))
                self.assertEqual(len(t), 1, point)  # its centre stayed inside the window
                self.assertTrue(0 <= t.boxes[0, 0] < 48 and 0 <= t.boxes[0, 1] < 48, point)


if __name__ == "__main__":
    unittest.main()
