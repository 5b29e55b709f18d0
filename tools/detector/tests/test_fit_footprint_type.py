"""fit_footprint_type: the footprint type evidence fitted on matched application detections.

A synthetic run: compacts 3.9-4.2 m and estates 4.7-5.0 m long whose crop-network probabilities
cannot tell them apart (0.45 / 0.47 either way). The fit must learn that a short footprint means
a compact, type every vehicle right, and leave out what the application leaves out (the frame
edge, a most likely Large, a detection not lifted, an ignored reference); bad input names the
file and row.
"""
import csv
import io
import os
import tempfile
import unittest
from contextlib import redirect_stdout

import numpy as np

import _common  # noqa: F401  (puts tools/ on sys.path)

from detector import fit_footprint_type as fft
from detector.datasets import OBJECT_COLUMNS_AFTER_GAMMA, OBJECT_COLUMNS_BEFORE_GAMMA

GT_COLUMNS = OBJECT_COLUMNS_BEFORE_GAMMA + ["gamma_0", "gamma_1", "gamma_2"] + \
    OBJECT_COLUMNS_AFTER_GAMMA
DET_COLUMNS = ["frame_id", "det_id", "score", "box_cx_px", "box_cy_px", "box_length_px",
               "box_width_px", "box_angle_rad", "at_frame_edge"] + \
    ["p_" + t for t in fft.TYPES] + ["lift_status", "length_m", "width_m"]


def write_csv(path, columns, rows, comment=""):
    with open(path, "w", newline="") as f:
        f.write(comment)
        w = csv.DictWriter(f, fieldnames=columns)
        w.writeheader()
        w.writerows(rows)


def make_run(root, sequences=4, per_frame=10, frames=3):
    """Run and data folders; returns (run_dir, data_dir)."""
    run, data = os.path.join(root, "run"), os.path.join(root, "data")
    os.makedirs(run)
    rng = np.random.default_rng(1)
    for s in range(sequences):
        seq = f"seq_{s}"
        os.makedirs(os.path.join(data, seq, "ground_truth"))
        gt, det = [], []
        for f in range(frames):
            for k in range(per_frame):
                compact = (k + s) % 2 == 0
                length_m = rng.uniform(3.9, 4.2) if compact else rng.uniform(4.7, 5.0)
                box = {"box_cx_px": 100.0 + 150.0 * k, "box_cy_px": 300.0,
                       "box_length_px": length_m / 0.05, "box_width_px": 1.8 / 0.05,
                       "box_angle_rad": 0.3}
                gt.append({"frame_id": f, "track_id": k, "type": "compact" if compact else "estate",
                           "truncation": 0, "occlusion": 0.9 if k == 9 else 0, **box})
                p = {"p_" + t: 0.02 for t in fft.TYPES}
                # Either way round: the crop network cannot tell these two apart.
                p["p_estate"], p["p_compact"] = (0.47, 0.45) if k % 4 < 2 else (0.45, 0.47)
                row = {"frame_id": f, "det_id": k, "score": 0.9, "at_frame_edge": 0,
                       "lift_status": "ok", "length_m": length_m, "width_m": 1.8, **box, **p}
                if k == 6:
                    row["at_frame_edge"] = 1
                if k == 7:
                    row["lift_status"] = "no_pose"
                if k == 8:
                    row.update({"p_large": 0.6, "p_estate": 0.1, "p_compact": 0.2})
                det.append(row)
        gt = [{c: row.get(c, 0) for c in GT_COLUMNS} for row in gt]
        write_csv(os.path.join(data, seq, "ground_truth", "objects.csv"), GT_COLUMNS, gt)
        write_csv(os.path.join(data, seq, "frames.csv"), ["frame_id", "timestamp_ns", "file"],
                  [{"frame_id": f, "timestamp_ns": f * 100000000, "file": f"frames/{f:06d}.png"}
                   for f in range(frames)])
        write_csv(os.path.join(run, seq + "_detections.csv"), DET_COLUMNS, det,
                  comment="# format_version: 2\n")
    return run, data


class FitFootprintTypeTest(unittest.TestCase):
    def test_learns_that_a_short_footprint_is_a_compact(self):
        with tempfile.TemporaryDirectory() as root:
            run, data = make_run(root)
            x, y, seq = fft.matched_pairs(run, data)
            # 10 per frame less the edge, the unlifted, the Large and the ignored reference.
            self.assertEqual(len(y), 4 * 3 * 6)
            self.assertEqual(sorted(set(seq.tolist())), [0, 1, 2, 3])
            w = fft.fit(x, y, 0.01)
            before, after = fft.accuracy(x, y, w)
            self.assertLess(before, 0.75)
            self.assertEqual(after, 1.0)
            compact, estate = fft.TYPES.index("compact"), fft.TYPES.index("estate")
            # Longer (and longer for its width): less of a compact than an estate.
            self.assertLess(w[compact, 0] + w[compact, 1], w[estate, 0] + w[estate, 1])
            out = io.StringIO()
            with redirect_stdout(out):
                code = fft.main(["--run", run, "--data", data, "--folds", "2",
                                 "--check", run, "--check-data", data])
            self.assertEqual(code, 0)
            text = out.getvalue()
            self.assertIn("fitted on 72 lifted car detections", text)
            self.assertIn("lengthWeight{", text)
            self.assertIn("gain over 2 sequence folds: +", text)

    def test_terms_are_clamped(self):
        x = np.zeros((2, 9))
        x[:, 7] = [20.0, 1.0]
        x[:, 8] = [1.8, 1.8]
        t = fft.terms(x)
        np.testing.assert_allclose(t, [[2.5, 2.5], [-2.5, -2.5]])

    def test_bad_input_names_the_file_and_row(self):
        with tempfile.TemporaryDirectory() as root:
            run, data = make_run(root, sequences=1)
            path = os.path.join(run, "seq_0_detections.csv")
            with open(path) as f:
                text = f.read().replace("0.9,", "high,", 1)
            with open(path, "w") as f:
                f.write(text)
            with self.assertRaisesRegex(fft.FitError, r"seq_0_detections.csv: row 2: column 'score'"):
                fft.matched_pairs(run, data)
            with self.assertRaisesRegex(fft.FitError, "no <sequence>_detections.csv"):
                fft.matched_pairs(data, data)


if __name__ == "__main__":
    unittest.main()
