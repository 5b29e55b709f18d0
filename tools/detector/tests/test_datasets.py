"""Readers of the recorded-sequence, YOLO and DOTA formats and the near-duplicate-free split."""

import math
import json
import os
import shutil
import subprocess
import tempfile
import unittest

import numpy as np

import _common
from detector import datasets
from detector.asm import TYPES


class SequenceReader(unittest.TestCase):
    def test_committed_fixture(self):
        s = datasets.read_sequence(_common.FIXTURE_SEQ)
        self.assertEqual(len(s), 2)
        self.assertEqual([len(x) for x in s], [1, 2])
        f1 = s[1]
        np.testing.assert_allclose(f1.boxes[0], [16.5, 11.9, 1.8, 0.7, 4.71238898038469])
        self.assertEqual(TYPES[f1.types[0]], "sedan")
        self.assertEqual(TYPES[f1.types[1]], "large")
        np.testing.assert_allclose(f1.gammas[0], [0.25, -1.5, 0.125])
        self.assertTrue(np.isnan(f1.gammas[1]).all())
        self.assertTrue(f1.direction_known.all())
        self.assertFalse(f1.aa_only.any())
        self.assertAlmostEqual(float(f1.keypoints[0, 0, 0]), 16.2, places=5)
        img = f1.loaded().image
        self.assertEqual(img.shape, (24, 32, 3))

    def test_errors_name_file_and_line(self):
        with tempfile.TemporaryDirectory() as d:
            seq = os.path.join(d, "seq")
            shutil.copytree(_common.FIXTURE_SEQ, seq)
            path = os.path.join(seq, "ground_truth", "objects.csv")
            with open(path) as f:
                text = f.read().replace("sedan", "truckk", 1)
            with open(path, "w") as f:
                f.write(text)
            with self.assertRaisesRegex(datasets.DatasetError, r"objects.csv:2: type: unknown vehicle type 'truckk'"):
                datasets.read_sequence(seq)

    def test_simulated_sequence(self):
        sim = _common.find_simulator()
        if sim is None:
            self.skipTest("vp_simulate is not built")
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "sim")
            subprocess.run([sim, "--scene", "parking", "--seed", "5", "--frames", "2", "--width", "240",
                            "--height", "190", "--supersampling", "1", "--png", "--out", out],
                           check=True, capture_output=True, timeout=120)
            s = datasets.read_sequence(out)
            self.assertEqual(len(s), 2)
            n = sum(len(x) for x in s)
            self.assertGreater(n, 0)
            x = s[0].loaded()
            self.assertEqual(x.image.shape, (190, 240, 3))
            cars = x.types < TYPES.index("large")
            # every car has its GSD from the wheel keypoints: a few cm per pixel at this size
            # (240 px wide image: GSD ~ 0.3 m at 90 m altitude)
            g = x.gsd_m[cars]
            self.assertTrue(np.all(np.isfinite(g)))
            self.assertTrue(np.all((g > 0.1) & (g < 1.5)), g)
            # box length in metres close to the car length (the box also holds the height
            # when oblique, so it is at least the length)
            self.assertTrue(np.all(np.isfinite(x.gammas[cars])))


class YoloReaderAndSplit(unittest.TestCase):
    def make_yolo(self, root, names):
        import cv2

        os.makedirs(os.path.join(root, "images"))
        os.makedirs(os.path.join(root, "labels"))
        rng = np.random.default_rng(0)
        for i, n in enumerate(names):
            img = (rng.uniform(0, 255, (8, 8, 3))).astype(np.uint8)
            img = cv2.resize(img, (64, 64), interpolation=cv2.INTER_CUBIC)
            cv2.imwrite(os.path.join(root, "images", n + ".jpg"), img)
            with open(os.path.join(root, "labels", n + ".txt"), "w") as f:
                f.write("0 0.5 0.25 0.25 0.125\n")

    def test_reader_pixels_and_clip_ids(self):
        with tempfile.TemporaryDirectory() as d:
            self.make_yolo(d, ["0_13", "Drone2_(363)"])
            s = datasets.read_yolo(d)
            self.assertEqual([(x.group, x.frame_index) for x in s], [("0", 13), ("Drone2", 363)])
            x = s[0].loaded()
            np.testing.assert_allclose(x.boxes[0], [31.5, 15.5, 16, 8, 0])
            self.assertTrue(x.aa_only.all())
            self.assertEqual(x.types[0], -1)

    def test_split_keeps_clips_apart_and_drops_hash_duplicates(self):
        samples = []
        for clip in range(10):
            for k in range(10):
                a = datasets.empty_like_arrays(0, 3)
                samples.append(datasets.Sample(image_path=None, group=str(clip), frame_index=k, **a))
        rng = np.random.default_rng(1)
        base = rng.random((10, 64)) < 0.5
        hashes = np.repeat(base, 10, axis=0)
        hashes ^= rng.random(hashes.shape) < 0.03  # frames of a clip: near-identical
        hashes[95] = hashes[5]  # clip 9 holds an exact copy of a clip-0 frame
        train, val, rep = datasets.split_near_duplicate_free(samples, hashes=hashes, seed=0)
        tg = {s.group for s in train}
        vg = {s.group for s in val}
        self.assertFalse(tg & vg)
        self.assertEqual(rep["train"] + rep["val"] + rep["val_dropped_gap"] + rep["val_dropped_hash"], 100)
        self.assertGreater(rep["min_val_train_hash_distance"], rep["hash_threshold_bits"])
        self.assertGreater(len(val), 0)

    def test_real_split_has_no_near_duplicates(self):
        if not os.path.isdir(os.path.join(_common.REAL_DIR, "images")):
            self.skipTest("real images not available")
        s = datasets.read_yolo(_common.REAL_DIR)
        # a subset keeps the test fast: three short clips and the first 150 frames of Drone2
        s = [x for x in s if x.group in ("0", "3", "5") or (x.group == "Drone2" and x.frame_index <= 150)]
        train, val, rep = datasets.split_near_duplicate_free(s, seed=0)
        self.assertGreater(len(train), 0)
        self.assertGreater(len(val), 0)
        self.assertGreater(rep["min_val_train_hash_distance"], rep["hash_threshold_bits"])
        names = {x.image_path for x in train}
        self.assertFalse(names & {x.image_path for x in val})
        for v in val:
            if v.group == "Drone2":
                tf = [t.frame_index for t in train if t.group == "Drone2"]
                if tf:
                    self.assertGreater(min(abs(v.frame_index - f) for f in tf), 10)
            else:
                self.assertNotIn(v.group, {t.group for t in train})


    def test_split_from_file_holds_out_the_listed_stems(self):
        with tempfile.TemporaryDirectory() as d:
            self.make_yolo(d, ["0_13", "0_14", "Drone2_(363)"])
            s = datasets.read_yolo(d)
            split = os.path.join(d, "split.json")
            with open(split, "w") as f:
                json.dump({"val_stems": ["0_14", "9_1"]}, f)
            train, val, rep = datasets.split_from_file(s, split)
            self.assertEqual(sorted(os.path.basename(x.image_path) for x in val), ["0_14.jpg"])
            self.assertEqual(len(train), 2)
            self.assertEqual(rep["val_stems_missing"], 1)  # 9_1 is not in this folder
            with open(split, "w") as f:  # a train list: images in neither list are left out
                json.dump({"val_stems": ["0_14"], "train_stems": ["0_13"]}, f)
            train, val, _ = datasets.split_from_file(s, split)
            self.assertEqual([os.path.basename(x.image_path) for x in train], ["0_13.jpg"])
            self.assertEqual(len(val), 1)
            with open(split, "w") as f:
                f.write("{}")
            with self.assertRaises(SystemExit) as e:
                datasets.split_from_file(s, split)
            self.assertIn("val_stems", str(e.exception))


class DotaReader(unittest.TestCase):
    def test_quadrilaterals(self):
        import cv2

        with tempfile.TemporaryDirectory() as d:
            os.makedirs(os.path.join(d, "images"))
            os.makedirs(os.path.join(d, "labelTxt"))
            cv2.imwrite(os.path.join(d, "images", "P0001.png"), np.zeros((50, 60, 3), np.uint8))
            with open(os.path.join(d, "labelTxt", "P0001.txt"), "w") as f:
                f.write("imagesource:GoogleEarth\ngsd:0.15\n"
                        "10 10 30 10 30 20 10 20 small-vehicle 0\n"
                        "40 10 45 10 45 40 40 40 large-vehicle 1\n"
                        "1 1 2 1 2 2 1 2 plane 0\n")
            s = datasets.read_dota(d)[0]
            self.assertEqual(len(s), 2)
            np.testing.assert_allclose(s.boxes[0, :4], [20, 15, 20, 10])
            self.assertAlmostEqual(s.boxes[0, 4] % math.pi, 0.0)
            np.testing.assert_allclose(s.boxes[1, :4], [42.5, 25, 30, 5])
            self.assertAlmostEqual(s.boxes[1, 4] % math.pi, math.pi / 2)
            self.assertFalse(s.direction_known.any())
            self.assertEqual(list(s.types), [-1, TYPES.index("large")])
            self.assertEqual(list(s.ignore), [False, True])
            self.assertAlmostEqual(s.gsd_m[0], 0.15)


if __name__ == "__main__":
    unittest.main()
