"""eval_large_real: long labels of a YOLO set counted as boxed whole, in parts or missed."""

import json
import os
import tempfile
import unittest

import cv2
import numpy as np

import _common  # noqa: F401  (puts tools/ on sys.path)
from detector import eval_large_real


def _write_set(root, labels):
    """A 640 x 640 grey image 'a' with YOLO labels (cx, cy, w, h) in pixels."""
    os.makedirs(os.path.join(root, "images"))
    os.makedirs(os.path.join(root, "labels"))
    cv2.imwrite(os.path.join(root, "images", "a.jpg"), np.full((640, 640, 3), 128, np.uint8))
    with open(os.path.join(root, "labels", "a.txt"), "w") as f:
        for cx, cy, w, h in labels:
            f.write(f"0 {(cx + 0.5) / 640} {(cy + 0.5) / 640} {w / 640} {h / 640}\n")


def _write_detections(path, boxes):
    """Rows of vp_detect_images' image variant: (cx, cy, length, width, angle) per box."""
    with open(path, "w") as f:
        f.write("# format_version: 1\nimage,det_id,score,box_cx_px,box_cy_px,box_length_px,"
                "box_width_px,box_angle_rad\n")
        for i, (cx, cy, length, width, angle) in enumerate(boxes):
            f.write(f"a,{i},0.9,{cx},{cy},{length},{width},{angle}\n")


class EvalLargeRealTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.root = os.path.join(self.tmp.name, "set")
        # at 0.05 m/px: a 12 m bus along u, another along v, a third one, and a 4.5 m car
        _write_set(self.root, [(200, 100, 240, 60), (500, 350, 60, 240), (200, 500, 240, 60),
                               (400, 100, 90, 40)])
        self.dets = os.path.join(self.tmp.name, "dets.csv")

    def tearDown(self):
        self.tmp.cleanup()

    def run_tool(self, boxes, *extra):
        _write_detections(self.dets, boxes)
        out = os.path.join(self.tmp.name, "report.json")
        rc = eval_large_real.main(["--root", self.root, "--detections", self.dets,
                                   "--gsd-m", "0.05", "--out", out, *extra])
        self.assertEqual(rc, 0)
        with open(out) as f:
            return json.load(f)

    def test_whole_parts_and_missed(self):
        report = self.run_tool([
            (200, 100, 230, 58, 0.0),            # the first bus, whole
            (500, 290, 110, 55, np.pi / 2),      # the second bus's front half: a part
            (500, 410, 110, 55, 3 * np.pi / 2),  # ... and its rear half
            (400, 100, 90, 40, 0.0),             # the car (not a long vehicle)
        ])
        self.assertEqual(report["vehicles"], 3)  # the car is shorter than 8.5 m
        self.assertEqual((report["whole"], report["parts"], report["missed"]), (1, 1, 1))
        results = {(round(r["cx_px"]), round(r["cy_px"])): r["result"] for r in report["rows"]}
        self.assertEqual(results[(200, 100)], "whole")
        self.assertEqual(results[(500, 350)], "parts")
        self.assertEqual(results[(200, 500)], "missed")

    def test_failure_list_draws_with_failure_sheet(self):
        import csv
        from detector import failure_sheet

        left = os.path.join(self.tmp.name, "left.csv")
        self.run_tool([(500, 290, 110, 55, np.pi / 2), (200, 100, 230, 58, 0.0)],
                      "--list-failures", left)
        with open(left, newline="") as f:
            rows = list(csv.DictReader(f))
        # the whole bus is not listed; the part's bus with its detection, the missed one without
        self.assertEqual([(r["result"], round(float(r["cy_px"]))) for r in rows],
                         [("parts", 350), ("missed", 500)])
        self.assertAlmostEqual(float(rows[0]["heading_rad"]), np.pi / 2)  # along its long side
        self.assertAlmostEqual(float(rows[0]["length_px"]), 240.0, places=6)
        self.assertAlmostEqual(float(rows[0]["width_px"]), 60.0, places=6)
        self.assertEqual(float(rows[0]["det_cy_px"]), 290.0)
        self.assertEqual(rows[1]["det_cx_px"], "")
        sheet = os.path.join(self.tmp.name, "left.jpg")
        self.assertEqual(failure_sheet.main(["--root", self.root, "--list", left, "--out", sheet,
                                             "--tile-px", "64", "--columns", "2"]), 0)
        self.assertEqual(cv2.imread(sheet).shape[1], 2 * 64)  # two tiles in one row

    def test_min_length_and_list(self):
        report = self.run_tool([(200, 100, 230, 58, 0.0)], "--min-length-m", "13")
        self.assertEqual(report["vehicles"], 0)  # no label is 13 m long
        stems = os.path.join(self.tmp.name, "stems.txt")
        with open(stems, "w") as f:
            f.write("b\n")
        report = self.run_tool([(200, 100, 230, 58, 0.0)], "--list", stems)
        self.assertEqual(report["vehicles"], 0)  # image a is not listed

    def test_bad_detections_file_is_an_error(self):
        with open(self.dets, "w") as f:
            f.write("image,score\na,0.5\n")
        rc = eval_large_real.main(["--root", self.root, "--detections", self.dets,
                                   "--gsd-m", "0.05"])
        self.assertEqual(rc, 1)


if __name__ == "__main__":
    unittest.main()
