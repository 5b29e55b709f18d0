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
from test_train_smoke import tiny_run_args, write_synthetic_sequence

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
        image, cx, cy, score, length, width, angle, gsd, label = rows[0]
        self.assertEqual(image, os.path.abspath(self.frames[1].image_path))
        self.assertEqual((cx, cy, score), (x, y, 0.6))
        # The box as detected, the frame's vehicle GSD (the crop scale), background.
        self.assertEqual((length, width, angle, label), (24.0, 10.0, 0.3, 0))
        self.assertAlmostEqual(gsd, float(np.nanmedian(self.frames[1].gsd_m)))

        out = os.path.join(self.root, "neg", "negatives.csv")
        with redirect_stderr(io.StringIO()), redirect_stdout(io.StringIO()):
            self.assertEqual(mine_negatives.main(["--data", self.seq, "--detections", self.dets,
                                                  "--out", out]), 0)
        with open(out, newline="") as f:
            written = list(csv.DictReader(f))
        self.assertEqual([(r["image"], float(r["cx_px"]), float(r["cy_px"])) for r in written],
                         [(image, x, y)])

    def test_furniture_in_view_becomes_car_sized_background_boxes(self):
        car = self.frames[0].boxes[0]
        x, y = self.empty_spot(1)
        with open(os.path.join(self.seq, "ground_truth", "furniture.csv"), "w") as f:
            f.write("frame_id,kind,index,cx_px,cy_px,length_px,width_px,angle_rad,visible_px\n")
            f.write(f"1,bench,0,{x},{y},3.0,1.0,0.5,40\n")       # listed: a negative
            f.write(f"1,kiosk,1,{x},{y},3.0,1.0,0.5,5\n")        # too little in view
            f.write(f"0,shelter,2,{car[0]},{car[1]},3.0,1.0,0.5,99\n")  # on a vehicle
        rows, counts = mine_negatives.furniture_samples([self.seq], min_visible_px=20,
                                                         max_iou=0.1)
        self.assertEqual(counts, {"seq_7": 1})
        image, cx, cy, score, length, width, angle, gsd, label = rows[0]
        self.assertEqual((image, cx, cy, angle, label),
                         (os.path.abspath(self.frames[1].image_path), x, y, 0.5, 0))
        # At least a car's size at the frame's vehicle GSD: what the first stage would box.
        self.assertAlmostEqual(length, 4.6 / gsd)
        self.assertAlmostEqual(width, 1.9 / gsd)
        os.remove(os.path.join(self.seq, "ground_truth", "furniture.csv"))
        with redirect_stderr(io.StringIO()) as err, redirect_stdout(io.StringIO()):
            self.assertEqual(mine_negatives.main(["--data", self.seq, "--furniture", "--out",
                                                  os.path.join(self.root, "f.csv")]), 1)
        self.assertIn("furniture.csv", err.getvalue())

    def test_false_detections_are_counted_by_the_furniture_they_lie_on(self):
        x, y = self.empty_spot(1)
        with open(os.path.join(self.seq, "ground_truth", "furniture.csv"), "w") as f:
            f.write("frame_id,kind,index,cx_px,cy_px,length_px,width_px,angle_rad,visible_px\n")
            f.write(f"1,motorbikes,0,{x},{y},8.0,4.0,0.0,90\n")    # in view, under a false box
            f.write(f"0,pedestrians,1,{x},{y},3.0,3.0,0.0,90\n")   # in view, no false box
            f.write(f"1,bench,2,{x},{y},3.0,1.0,0.0,5\n")          # too little in view
        self.write_detections([
            (1, 0, 0.6, x + 3.0, y + 1.5, 24.0, 10.0, 0.3),  # centre inside the motorbikes' box
            (1, 1, 0.6, x + 5.0, y, 24.0, 10.0, 0.3),        # beside it: elsewhere
        ])
        rows, _ = mine_negatives.mine([self.seq], self.dets, min_score=0.4, max_iou=0.1)
        kinds = mine_negatives.false_boxes_by_kind([self.seq], rows, min_visible_px=20)
        self.assertEqual(kinds, {"motorbikes": [1, 1], "pedestrians": [1, 0],
                                 "(elsewhere)": [0, 1]})
        out = io.StringIO()
        with redirect_stderr(io.StringIO()), redirect_stdout(out):
            self.assertEqual(mine_negatives.main(["--data", self.seq, "--detections", self.dets,
                                                  "--by-kind", "--min-visible-px", "20",
                                                  "--out", os.path.join(self.root, "n.csv")]), 0)
        self.assertRegex(out.getvalue(), r"motorbikes +1 +1")

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
        self.assertEqual(list(negatives), [("seq", 1)])
        np.testing.assert_array_equal(negatives[("seq", 1)], [[40.0, 50.0], [41.0, 51.0]])
        # Real training images are keyed apart from the sequence frames (mined with --images).
        negatives = train.read_hard_negatives(path, self.frames[:1], real=self.frames[1:2])
        self.assertEqual(list(negatives), [("real", 0)])
        np.testing.assert_array_equal(negatives[("real", 0)], [[40.0, 50.0], [41.0, 51.0]])
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



class Verifier(unittest.TestCase):
    """The crop network's verifier head: mined boxes (vehicle or not) and its training batch."""

    def setUp(self):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.root = tmp.name
        import cv2

        # A YOLO folder with one 200 x 100 image and one labelled car at (50..90, 20..40).
        os.makedirs(os.path.join(self.root, "real", "images"))
        os.makedirs(os.path.join(self.root, "real", "labels"))
        cv2.imwrite(os.path.join(self.root, "real", "images", "0_1.png"),
                    np.full((100, 200, 3), 128, np.uint8))
        with open(os.path.join(self.root, "real", "labels", "0_1.txt"), "w") as f:
            f.write("0 0.35 0.3 0.2 0.2\n")
        self.dets = os.path.join(self.root, "real.csv")
        with open(self.dets, "w") as f:
            f.write("# format_version: 1\nimage,det_id,score,box_cx_px,box_cy_px,box_length_px,"
                    "box_width_px,box_angle_rad,type\n")
            f.write("0_1,0,0.9,69.5,29.5,40.0,20.0,0.0,sedan\n")    # the car: IoU 1
            f.write("0_1,1,0.7,150.0,70.0,40.0,20.0,1.57,sedan\n")  # background
            f.write("0_1,2,0.6,95.0,29.5,40.0,20.0,0.0,sedan\n")    # partly on the car: neither
            f.write("0_1,3,0.3,150.0,20.0,40.0,20.0,0.0,sedan\n")   # below --min-score

    def test_mines_real_images_against_their_axis_aligned_labels(self):
        rows, counts = mine_negatives.mine_images(os.path.join(self.root, "real"), self.dets,
                                                  None, 0.047, 0.4, 0.1, positives=True)
        self.assertEqual(counts, {"0_1": 1})
        self.assertEqual(sorted((r[1], r[-1]) for r in rows), [(69.5, 1), (150.0, 0)])
        self.assertTrue(all(r[7] == 0.047 for r in rows))
        rows, _ = mine_negatives.mine_images(os.path.join(self.root, "real"), self.dets,
                                             {"other"}, 0.047, 0.4, 0.1, positives=True)
        self.assertEqual(rows, [])  # not listed
        err = io.StringIO()
        with redirect_stderr(err):
            with self.assertRaises(SystemExit):
                mine_negatives.main(["--images", os.path.join(self.root, "real"), "--detections",
                                     self.dets, "--out", os.path.join(self.root, "v.csv")])
        self.assertIn("--gsd-m", err.getvalue())

    def sequence_and_list(self, name, rows):
        """A synthetic sequence and a verifier list of ``rows`` (the columns after image and
        the centre: score, box, GSD, label) on its first frame: (sequence, frame, list path)."""
        seq = os.path.join(self.root, name)
        write_synthetic_sequence(seq, frames=2)
        frame = read_sequence(seq)[0]
        listed = os.path.join(self.root, name + "_verifier.csv")
        with open(listed, "w") as f:
            f.write(",".join(mine_negatives.OUT_COLUMNS) + "\n")
            for row in rows:
                f.write(f"{frame.image_path},{row}\n")
        return seq, frame, listed

    def test_training_batch_holds_verifier_crops_and_the_loss_uses_them(self):
        from detector import losses
        from detector.model import CropNet

        seq, frame, listed = self.sequence_and_list("seq_3", [
            "60,60,0.7,30,12,0.2,0.05,0",
            "60,60,0.7,30,12,0.2,nan,0",  # no GSD: skipped
            "30,30,0.9,30,12,0.0,0.05,1"])
        self.assertEqual([r[-1] for r in train.read_verifier_samples(listed)], [0, 1])
        args = train.parse_args(["--data", seq, "--out", os.path.join(self.root, "run"),
                                 "--crop-batch", "4", "--verifier-samples", listed,
                                 "--verifier-batch", "6"])
        data = train.Data(args, 3, log=lambda *_: None)
        batch = data.crop_arrays(np.random.default_rng(1))
        self.assertEqual(batch["image"].shape[0], 10)
        np.testing.assert_array_equal(batch["full"], [True] * 4 + [False] * 6)
        self.assertTrue((batch["vehicle"][:4] == 1).all())
        self.assertTrue((batch["type"][4:] == -1).all() and np.isnan(batch["gamma"][4:]).all())
        net = CropNet(n_s=3, verifier=True)
        self.assertEqual(net.output_names()[-1], "vehicle_logit")
        self.assertNotIn("vehicle_logit", CropNet(n_s=3).output_names())
        tb = train.to_device(batch, "cpu")
        total, terms = losses.crop_loss(net(tb["input"]), tb, lambda p, g: (p - g).abs().mean())
        self.assertIn("vehicle", terms)
        self.assertTrue(math.isfinite(float(total)))
        # Export: the int8 calibration of a verifier crop network sees background crops too.
        from detector import export

        cal = train.parse_args(["--data", seq, "--out", "x"])  # any namespace with the fields
        cal.calib_data, cal.calib_real, cal.calib_real_split = [seq], None, None
        cal.calib_count, cal.working_width, cal.calib_verifier_samples = 2, 128, [listed]
        _, plain = export.calibration_images(cal, (128, 128), 3, np.random.default_rng(0))
        _, mixed = export.calibration_images(cal, (128, 128), 3, np.random.default_rng(0),
                                             verifier=True)
        self.assertGreater(len(mixed), len(plain))
        np.testing.assert_array_equal(mixed[0], plain[0])  # interleaved: vehicle, background, ...
        bad = os.path.join(self.root, "bad.csv")
        with open(bad, "w") as f:
            f.write(",".join(mine_negatives.OUT_COLUMNS) + "\n")
            f.write(f"{frame.image_path},60,60,0.7,30,12,0.2,0.05,2\n")
        with self.assertRaises(SystemExit) as e:
            train.read_verifier_samples(bad)
        self.assertIn("bad.csv:2: label must be 0 or 1", str(e.exception))

    def test_head_only_training_leaves_the_other_outputs_as_they_were(self):
        import torch

        seq, _, listed = self.sequence_and_list("seq_4", ["60,60,0.7,30,12,0.2,0.05,0"])
        first = os.path.join(self.root, "first")
        with redirect_stdout(io.StringIO()):
            train.train(train.parse_args(tiny_run_args(seq, first, 1) + ["--max-steps", "1"]))
            second = os.path.join(self.root, "second")
            train.train(train.parse_args(
                tiny_run_args(seq, second, 1) + ["--max-steps", "3", "--crop-only", "--init-from",
                                                 os.path.join(first, "checkpoint.pt"),
                                                 "--verifier-samples", listed,
                                                 "--verifier-head-only"]))
        before = torch.load(os.path.join(first, "checkpoint.pt"))["crop"]
        after = torch.load(os.path.join(second, "checkpoint.pt"))["crop"]
        self.assertEqual(set(after) - set(before), {"vehicle_logit.weight", "vehicle_logit.bias"})
        for k, v in before.items():  # weights and batch-norm statistics alike
            self.assertTrue(torch.equal(v, after[k]), k)
        with self.assertRaises(SystemExit) as e:
            train.train(train.parse_args(tiny_run_args(seq, second, 1) + [
                "--verifier-samples", listed, "--verifier-head-only"]))
        self.assertIn("--verifier-head-only needs", str(e.exception))
        # With its own fully connected layer (started as a copy of the shared one) the verifier
        # trains that layer and its output; every other weight and statistic stays.
        third = os.path.join(self.root, "third")
        with redirect_stdout(io.StringIO()):
            train.train(train.parse_args(
                tiny_run_args(seq, third, 1) + ["--max-steps", "3", "--crop-only", "--init-from",
                                                os.path.join(second, "checkpoint.pt"),
                                                "--verifier-samples", listed, "--verifier-branch",
                                                "--verifier-head-only"]))
        branched = torch.load(os.path.join(third, "checkpoint.pt"))["crop"]
        self.assertEqual(set(branched) - set(after), {"verifier_fc.0.weight", "verifier_fc.0.bias"})
        changed = sorted(k for k, v in after.items() if not torch.equal(v, branched[k]))
        self.assertEqual(changed, ["vehicle_logit.bias", "vehicle_logit.weight"])
        self.assertFalse(torch.equal(branched["verifier_fc.0.weight"], after["fc.0.weight"]))


if __name__ == "__main__":
    unittest.main()
