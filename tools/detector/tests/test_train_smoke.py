"""A 20-step training run on a synthetic recorded sequence: the loss decreases, checkpoints are
written and a resumed run continues from them."""

import json
import math
import os
import tempfile
import unittest

import cv2
import numpy as np

import _common  # noqa: F401
from detector import geometry, train
from detector.datasets import OBJECT_COLUMNS_AFTER_GAMMA


def write_synthetic_sequence(root, frames=3, size=128, seed=0):
    """Minimal frames.csv + ground_truth/objects.csv (what the reader needs): grey road,
    bright 'cars' (24 x 10 px boxes, darker rear half) with random headings."""
    rng = np.random.default_rng(seed)
    os.makedirs(os.path.join(root, "frames"))
    os.makedirs(os.path.join(root, "ground_truth"))
    fr = ["frame_id,timestamp_ns,file"]
    ob = ["frame_id,track_id,type,gamma_0,gamma_1,gamma_2," + ",".join(OBJECT_COLUMNS_AFTER_GAMMA)]
    types = ["estate", "compact", "sports", "sedan", "suv", "van"]
    for f in range(frames):
        img = np.full((size, size, 3), 90, np.uint8)
        img += rng.integers(0, 20, img.shape, dtype=np.uint8)
        for t in range(4):
            cx, cy = rng.uniform(20, size - 20, 2)
            a = rng.uniform(0, 2 * math.pi)
            box = np.array([cx, cy, 24.0, 10.0, a])
            cv2.fillPoly(img, [np.round(geometry.box_corners(box)[0]).astype(np.int32)], (230, 230, 230))
            rear = box.copy()
            rear[:2] -= 6 * np.array([math.cos(a), math.sin(a)])
            rear[2] = 12
            cv2.fillPoly(img, [np.round(geometry.box_corners(rear)[0]).astype(np.int32)], (150, 150, 160))
            g = rng.normal(0, 1, 3)
            vals = [4.5, 1.8, 1.5, 0, 0, 0, 0, 0, 0, cx, cy, 24, 10, a, 0, 0, 0]
            ob.append(f"{f},{t},{types[t % 6]},{g[0]},{g[1]},{g[2]}," + ",".join(repr(float(v)) for v in vals))
        cv2.imwrite(os.path.join(root, "frames", f"{f:06d}.png"), img)
        fr.append(f"{f},{1000 + f},frames/{f:06d}.png")
    with open(os.path.join(root, "frames.csv"), "w") as fh:
        fh.write("\n".join(fr) + "\n")
    with open(os.path.join(root, "ground_truth", "objects.csv"), "w") as fh:
        fh.write("\n".join(ob) + "\n")


def tiny_run_args(seq, run, threads):
    """A run small enough for a test: 64 px tiles, 4 tiles and 4 crops per step, on the CPU."""
    return ["--data", seq, "--out", run, "--batch", "4", "--tile", "64", "--crop-batch", "4",
            "--working-width", "128", "--warmup-steps", "2", "--lr", "3e-3",
            "--threads", str(threads), "--device", "cpu", "--log-every", "100", "--no-eval"]


class SmokeTraining(unittest.TestCase):
    def setUp(self):
        """A synthetic recorded sequence and a run directory, both in a fresh temp folder."""
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.seq = os.path.join(tmp.name, "seq")
        self.run = os.path.join(tmp.name, "run")
        write_synthetic_sequence(self.seq)

    def train_20_steps(self, args):
        """Trains 20 steps; the detector's loss must fall. Returns the step records."""
        h = train.train(train.parse_args(args + ["--max-steps", "20"]))["history"]
        self.assertEqual(len(h), 20)
        self.assertLess(np.mean([r["det_loss"] for r in h[-5:]]),
                        np.mean([r["det_loss"] for r in h[:5]]))
        return h

    def test_loss_decreases_and_resume(self):
        common = tiny_run_args(self.seq, self.run, 2) + ["--shape-loss", "l2", "--single-stage"]
        h = self.train_20_steps(common)
        cfirst = np.mean([r["crop_loss"] for r in h[:5]])
        clast = np.mean([r["crop_loss"] for r in h[-5:]])
        self.assertLess(clast, cfirst)
        self.assertTrue(os.path.isfile(os.path.join(self.run, "checkpoint.pt")))
        # resume: continues at step 20 and runs 2 more
        res2 = train.train(train.parse_args(common + ["--max-steps", "22", "--resume"]))
        self.assertEqual(res2["steps"], 22)
        self.assertEqual(len(res2["history"]), 2)
        with open(os.path.join(self.run, "train_log.jsonl")) as fh:
            self.assertEqual(len(fh.readlines()), 22)

    def test_workers_and_session_limit(self):
        """Batches made by worker processes train too; --session-minutes ends a run early with
        a checkpoint that --resume continues."""
        common = tiny_run_args(self.seq, self.run, 1) + ["--workers", "2", "--preload"]
        h = self.train_20_steps(common)
        self.assertTrue(all(math.isfinite(r["crop_loss"]) for r in h))
        # a session of ~0 minutes (over before the workers start): no step, checkpointed
        res2 = train.train(train.parse_args(common + ["--max-steps", "40", "--resume",
                                                      "--session-minutes", "1e-6"]))
        self.assertEqual(res2["steps"], 20)
        self.assertEqual(res2["history"], [])

    def test_type_head_only_changes_only_the_type_output(self):
        """--type-head-only trains the type output layer alone: every other weight and batch-norm
        statistic of the crop network stays --init-from's, bit for bit."""
        import torch
        from contextlib import redirect_stdout
        import io

        with redirect_stdout(io.StringIO()):
            train.train(train.parse_args(tiny_run_args(self.seq, self.run, 1) + ["--max-steps", "1"]))
            second = self.run + "_type"
            train.train(train.parse_args(
                tiny_run_args(self.seq, second, 1) + [
                    "--max-steps", "3", "--crop-only", "--type-head-only",
                    "--init-from", os.path.join(self.run, "checkpoint.pt")]))
        before = torch.load(os.path.join(self.run, "checkpoint.pt"))["crop"]
        after = torch.load(os.path.join(second, "checkpoint.pt"))["crop"]
        changed = sorted(k for k, v in before.items() if not torch.equal(v, after[k]))
        self.assertEqual(changed, ["type_logits.bias", "type_logits.weight"])
        with self.assertRaises(SystemExit) as e:
            train.train(train.parse_args(tiny_run_args(self.seq, second, 1) + ["--type-head-only"]))
        self.assertIn("--type-head-only needs", str(e.exception))

    def test_init_from_two_verifiers_with_the_borders_own(self):
        """--init-from a checkpoint whose crop network holds two verifiers in one branch and the
        border's own head (verifier_ensemble.py --edge-base, as v14's import) trains with that
        layout; the border's head, untrained here, stays as it was."""
        import torch
        from contextlib import redirect_stdout
        import io
        from detector.model import CropNet

        with redirect_stdout(io.StringIO()):
            train.train(train.parse_args(tiny_run_args(self.seq, self.run, 1) + ["--max-steps", "1"]))
        ck = torch.load(os.path.join(self.run, "checkpoint.pt"))
        wide = CropNet(n_s=ck["n_s"], verifier=True, verifier_branch=True, verifier_width=384,
                       verifier_edge=True).state_dict()
        wide.update(ck["crop"])
        ck["crop"] = wide
        start = os.path.join(self.run, "two_verifiers.pt")
        torch.save(ck, start)
        second = self.run + "_two"
        with redirect_stdout(io.StringIO()):
            train.train(train.parse_args(tiny_run_args(self.seq, second, 1) + [
                "--max-steps", "2", "--crop-only", "--type-head-only", "--init-from", start]))
        after = torch.load(os.path.join(second, "checkpoint.pt"))["crop"]
        self.assertEqual(tuple(after["verifier_fc.0.weight"].shape[:2]), (384, 128))
        for k in ("vehicle_logit_edge.weight", "vehicle_logit_edge.bias"):
            self.assertTrue(torch.equal(after[k], wide[k]), k)

    def test_batch_stream_is_reproducible_from_its_start(self):
        args = train.parse_args(["--data", self.seq, "--out", self.run, "--batch", "2",
                                 "--tile", "64", "--crop-batch", "3", "--working-width", "128"])
        data = train.Data(args, 3, log=lambda *_: None)

        def first(seed, step):
            det, crop = next(iter(train.BatchStream(data, seed, step, True, True)))
            return det["image"], crop["image"], crop["refine"]

        a, b = first(7, 0), first(7, 0)
        for x, y in zip(a, b):
            np.testing.assert_array_equal(x, y)
        c = first(7, 100)  # a resumed run draws other batches
        self.assertFalse(np.array_equal(a[0], c[0]))

    def test_real_split_does_not_follow_the_training_seed(self):
        a = train.parse_args(["--out", "/tmp/x", "--seed", "4"])
        self.assertEqual(a.split_seed, 0)

    def test_refuses_run_dir_inside_repo(self):
        with self.assertRaises(SystemExit):
            train._check_out_dir(os.path.join(_common.REPO, "runs", "x"))


if __name__ == "__main__":
    unittest.main()


class LargeVehicleEndCrops(unittest.TestCase):
    """--large-crop-share draws crops from the buses and trucks; --large-end-share cuts them at
    one end of the vehicle, and such a crop trains the front/back output only."""

    def setUp(self):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.seq = os.path.join(tmp.name, "seq")
        write_synthetic_sequence(self.seq, frames=1)
        path = os.path.join(self.seq, "ground_truth", "objects.csv")
        with open(path) as f:
            rows = f.read().splitlines()
        head = rows[0].split(",")
        first = rows[1].split(",")
        first[head.index("type")] = "large"
        first[head.index("length_m")] = "12.0"  # 24 px at 0.5 m/px: longer than the 5.76 m window
        rows[1] = ",".join(first)
        with open(path, "w") as f:
            f.write("\n".join(rows) + "\n")
        self.run = os.path.join(tmp.name, "run")

    def batch(self, end_share):
        args = train.parse_args(["--data", self.seq, "--out", self.run, "--crop-batch", "16",
                                 "--large-crop-share", "1", "--large-end-share", str(end_share)])
        return train.Data(args, 3, log=lambda *_: None).crop_arrays(np.random.default_rng(5))

    def test_end_crops_train_only_front_back(self):
        from detector.datasets import LARGE
        whole = self.batch(0.0)
        self.assertTrue(whole["full"].all())
        self.assertTrue((whole["type"] == LARGE).all())
        ends = self.batch(1.0)
        self.assertFalse(ends["full"].any())
        self.assertTrue(ends["flip_known"].all())
        self.assertTrue((ends["type"] == -1).all() and np.isnan(ends["gamma"]).all())
        self.assertTrue((ends["refine"] == 0).all())
        self.assertEqual(set(np.unique(ends["flip"])), {0.0, 1.0})
        # Cut at the ends, not the middle: the crops differ from the whole vehicle's.
        self.assertGreater(np.abs(ends["image"].astype(float) - whole["image"].astype(float)).mean(), 1.0)
