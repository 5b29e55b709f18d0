"""Real driving-direction labels: real_headings.py labels vehicles from their lane-mates (and
from motion), eval_rotated_real.py measures heading on rotated real labels (failure_sheet.py
draws its failure lists), and train.py
--heading-samples / --flip-branch / --flip-head-only train the front/back output on them."""

import io
import math
import os
import tempfile
import unittest
from contextlib import redirect_stdout
from types import SimpleNamespace

import cv2
import numpy as np

import _common  # noqa: F401
from detector import eval_rotated_real, failure_sheet, mine_negatives, real_headings, train
from detector.datasets import read_sequence
from test_train_smoke import tiny_run_args, write_synthetic_sequence

LANE_OPTS = SimpleNamespace(max_across=0.5, max_axis_deg=15.0, lane_frames=2, lane_length_m=60.0,
                            min_votes=3, min_agreement=0.8, min_response=0.0)


def lane_frame(stem, index, path, headings_up):
    """A frame of one clip with two vertical lanes: x = 100 drives up (-v, angle 3pi/2),
    x = 200 drives down (angle pi/2); ``headings_up`` gives each vehicle's vote."""
    boxes, votes = [], []
    for k, up in enumerate(headings_up):
        x = 100.0 if k % 2 == 0 else 200.0
        true = 1.5 * math.pi if x == 100.0 else 0.5 * math.pi
        boxes.append([x, 40.0 + 60.0 * (k // 2), 40.0, 16.0, true, 0.9])
        votes.append(true if up else true + math.pi)
    return {"stem": stem, "path": path, "clip": "c", "index": index,
            "vehicles": np.array(boxes), "votes": np.array(votes)}


class LaneVotes(unittest.TestCase):
    def setUp(self):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.image = os.path.join(tmp.name, "c_1.png")
        rng = np.random.default_rng(0)
        cv2.imwrite(self.image, rng.integers(0, 255, (320, 320, 3), dtype=np.uint8))

    def test_a_vehicle_reversed_against_its_lane_is_labelled_against_its_own_vote(self):
        # Frame 1: vehicle 2 (lane x = 100) votes reversed; its lane-mates 0 and 4 do not, and
        # frames 0 and 2 (the same image: no camera drift) add agreeing votes of both lanes.
        frames = [lane_frame("c_0", 0, self.image, [True] * 8),
                  lane_frame("c_1", 1, self.image, [True, True, False, True, True, True, True, True]),
                  lane_frame("c_2", 2, self.image, [True] * 8)]
        rows = real_headings.label_lanes(frames, 0.05, LANE_OPTS)
        mine = {r["stem"] + f"/{int(r['box'][1])}x{int(r['box'][0])}": r for r in rows}
        reversed_one = mine["c_1/100x100"]
        self.assertEqual(reversed_one["det_reversed"], 1)
        self.assertAlmostEqual(reversed_one["angle"], 1.5 * math.pi)  # the lane's direction
        # Every vehicle of the two lanes gets its lane's direction, never the other lane's.
        for r in rows:
            expect = 1.5 * math.pi if r["box"][0] == 100.0 else 0.5 * math.pi
            self.assertAlmostEqual(math.cos(r["angle"] - expect), 1.0)
        self.assertEqual(sum(r["det_reversed"] for r in rows), 1)

    def test_judge_counts_another_runs_reversals_against_the_labels(self):
        frames = [lane_frame("c_0", 0, self.image, [True] * 8),
                  lane_frame("c_1", 1, self.image, [True] * 8)]
        rows = real_headings.label_lanes(frames, 0.05, LANE_OPTS)
        self.assertEqual(len(rows), 16)
        # Another run: the same boxes, one turned by pi, one moved 10 px (not matched), and
        # one 2 px off its box with the lane's direction (matched).
        path = os.path.join(os.path.dirname(self.image), "other.csv")
        with open(path, "w") as f:
            f.write("# format_version: 1\nimage,det_id,score,box_cx_px,box_cy_px,box_length_px,"
                    "box_width_px,box_angle_rad\n")
            for k, r in enumerate(rows):
                cx, cy, angle = r["box"][0], r["box"][1], r["angle"]
                if k == 0:
                    angle += math.pi
                elif k == 1:
                    cx += 10.0
                elif k == 2:
                    cy += 2.0
                f.write(f"{r['stem']},{k},0.9,{cx},{cy},40,16,{angle % (2 * math.pi)}\n")
        self.assertEqual(real_headings.judge(rows, path), (15, 1, 1))

    def test_a_split_lane_gives_no_label(self):
        frames = [lane_frame("c_1", 1, self.image, [True, True, False, True, True, True, False, True])]
        opts = SimpleNamespace(**{**vars(LANE_OPTS), "min_votes": 2})
        rows = real_headings.label_lanes(frames, 0.05, opts)
        self.assertFalse([r for r in rows if r["box"][0] == 100.0])  # 2 against 2: undecided
        self.assertEqual(len([r for r in rows if r["box"][0] == 200.0]), 4)

    def test_motion_labels_a_moving_vehicle_and_not_a_standing_one(self):
        opts = SimpleNamespace(max_across=0.5, max_axis_deg=15.0, max_gap=2, max_step_m=16.0,
                               min_step_m=0.6)
        frames = []
        for t in range(3):  # vehicle A drives +u 30 px per frame, B stands
            boxes = np.array([[50.0 + 30 * t, 100.0, 40.0, 16.0, math.pi, 0.9],
                              [150.0, 250.0, 40.0, 16.0, 0.0, 0.9]])
            frames.append({"stem": f"c_{t}", "path": self.image, "clip": "c", "index": t,
                           "vehicles": boxes, "votes": boxes[:, 4].copy()})
        rows = real_headings.label_motion(frames, 0.05, opts)
        self.assertEqual(len(rows), 1)
        self.assertAlmostEqual(rows[0]["angle"], 0.0)  # its box said pi: reversed
        self.assertEqual(rows[0]["det_reversed"], 1)


class RotatedRealEvaluation(unittest.TestCase):
    def test_precision_recall_and_reversed_share(self):
        labels = {"a": np.array([[100, 100, 60, 25, 0.0], [300, 100, 60, 25, math.pi / 2]]),
                  "b": np.array([[100, 100, 60, 25, 1.0]])}
        dets = {"a": [(0.9, np.array([101, 100, 60, 25, math.pi + 0.01])),   # reversed
                      (0.8, np.array([300, 101, 58, 25, math.pi / 2 + 0.02])),  # good
                      (0.7, np.array([500, 500, 60, 25, 0.0]))],              # false
                "b": []}
        failures = {}
        report, rows = eval_rotated_real.evaluate(labels, dets, failures=failures)
        self.assertEqual([(f[0], f[1]) for f in failures["false"]], [("a", 0.7)])
        self.assertEqual([(m[0], m[1]) for m in failures["missed"]], [("b", 100.0)])
        self.assertEqual(report["true_positives"], 2)
        self.assertAlmostEqual(report["precision"], 2 / 3)
        self.assertAlmostEqual(report["recall"], 2 / 3)
        self.assertEqual(report["reversed"], 1)
        self.assertEqual([r[0] for r in rows], ["a"])
        # With the image sizes, a false box reaching beyond the image is counted apart.
        dets["b"] = [(0.6, np.array([10.0, 300.0, 60, 25, 0.0]))]
        report, _ = eval_rotated_real.evaluate(labels, dets, sizes={"a": (640, 640), "b": (640, 480)})
        self.assertEqual(report["false_detections"], 2)
        self.assertEqual(report["false_reaching_border"], 1)
        self.assertAlmostEqual(report["precision_inside"], 2 / 3)

    def test_malformed_label_names_file_and_line(self):
        with tempfile.TemporaryDirectory() as root:
            os.makedirs(os.path.join(root, "labels"))
            with open(os.path.join(root, "labels", "x.txt"), "w") as f:
                f.write("car 1 2 3 4 0.5\ncar 1 2 3\n")
            with self.assertRaises(Exception) as e:
                eval_rotated_real.read_rotated_labels(root)
            self.assertIn("x.txt:2:", str(e.exception))


class FailureSheet(unittest.TestCase):
    def setUp(self):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.root = tmp.name
        os.makedirs(os.path.join(self.root, "images"))
        cv2.imwrite(os.path.join(self.root, "images", "f_1.png"), np.full((200, 300, 3), 128, np.uint8))

    def write_list(self, text):
        path = os.path.join(self.root, "list.csv")
        with open(path, "w") as f:
            f.write(text)
        return path

    def test_a_tile_per_row_with_the_detection_drawn_in_red(self):
        listing = self.write_list("image,score,det_cx_px,det_cy_px,det_length_px,det_width_px,det_angle_rad\n"
                                  "f_1,0.9,150,100,60,25,0.0\nf_1,0.8,10,10,60,25,1.0\n")
        out = os.path.join(self.root, "sheet.png")
        with redirect_stdout(io.StringIO()):
            self.assertEqual(failure_sheet.main(["--root", self.root, "--list", listing, "--out", out,
                                                 "--tile-px", "64", "--columns", "3"]), 0)
        sheet = cv2.imread(out)
        self.assertEqual(sheet.shape[:2], (64 + 16, 3 * 64))  # two tiles and a blank, one row
        first = sheet[:64, :64].astype(int)
        red = (first[..., 2] > 180) & (first[..., 1] < 100)
        self.assertGreater(int(red.sum()), 20)
        self.assertGreater(int(red[:, 12:20].sum()), 0)  # the back edge, a quarter of the tile in

    def test_a_row_without_a_box_names_the_file_and_line(self):
        listing = self.write_list("image,score\nf_1,0.9\n")
        with self.assertRaises(failure_sheet.SheetError) as e:
            failure_sheet.read_list(listing)
        self.assertIn("list.csv:2", str(e.exception))


class HeadingTraining(unittest.TestCase):
    def setUp(self):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.root = tmp.name
        self.seq = os.path.join(tmp.name, "seq_5")
        write_synthetic_sequence(self.seq, frames=2)
        frame = read_sequence(self.seq)[0]
        self.listed = os.path.join(tmp.name, "headings.csv")
        with open(self.listed, "w") as f:
            f.write(",".join(real_headings.COLUMNS) + "\n")
            b = frame.boxes[0]
            f.write(f"{frame.image_path},{b[0]},{b[1]},0.9,{b[2]},{b[3]},{b[4]},0.05,1,0\n")
        self.assertEqual(real_headings.COLUMNS[:9], mine_negatives.OUT_COLUMNS)

    def test_heading_crops_train_only_the_flip_output(self):
        from detector import losses
        from detector.model import CropNet

        args = train.parse_args(["--data", self.seq, "--out", os.path.join(self.root, "run"),
                                 "--crop-batch", "4", "--heading-samples", self.listed,
                                 "--heading-batch", "5"])
        data = train.Data(args, 3, log=lambda *_: None)
        batch = data.crop_arrays(np.random.default_rng(2))
        self.assertEqual(batch["image"].shape[0], 9)
        np.testing.assert_array_equal(batch["full"], [True] * 4 + [False] * 5)
        self.assertTrue(batch["flip_known"].all())
        self.assertTrue((batch["type"][4:] == -1).all() and np.isnan(batch["gamma"][4:]).all())
        net = CropNet(n_s=3, flip_branch=True)
        tb = train.to_device(batch, "cpu")
        total, terms = losses.crop_loss(net(tb["input"]), tb, lambda p, g: (p - g).abs().mean())
        self.assertTrue(math.isfinite(float(total)))
        # A flip branch started from the shared layer gives the shared layer's flip output.
        net.start_flip_branch_from_shared()
        net.eval()
        plain = CropNet(n_s=3)
        plain.load_state_dict({k: v for k, v in net.state_dict().items() if not k.startswith("flip_fc.")})
        plain.eval()
        x = tb["input"][:3]
        self.assertTrue(np.allclose(net(x)["flip_logit"].detach(), plain(x)["flip_logit"].detach()))

    def test_flip_head_only_leaves_everything_else_as_it_was(self):
        import torch

        first = os.path.join(self.root, "first")
        second = os.path.join(self.root, "second")
        with redirect_stdout(io.StringIO()):
            train.train(train.parse_args(tiny_run_args(self.seq, first, 1) + ["--max-steps", "1"]))
            train.train(train.parse_args(
                tiny_run_args(self.seq, second, 1) + [
                    "--max-steps", "3", "--crop-only", "--init-from",
                    os.path.join(first, "checkpoint.pt"), "--heading-samples", self.listed,
                    "--flip-branch", "--flip-head-only"]))
        before = torch.load(os.path.join(first, "checkpoint.pt"))["crop"]
        after = torch.load(os.path.join(second, "checkpoint.pt"))["crop"]
        self.assertEqual(set(after) - set(before), {"flip_fc.0.weight", "flip_fc.0.bias"})
        changed = [k for k, v in before.items() if not torch.equal(v, after[k])]
        self.assertEqual(sorted(changed), ["flip_logit.bias", "flip_logit.weight"])
        with self.assertRaises(SystemExit) as e:
            train.train(train.parse_args(tiny_run_args(self.seq, second, 1) + ["--flip-head-only"]))
        self.assertIn("--flip-head-only needs", str(e.exception))


if __name__ == "__main__":
    unittest.main()
