"""Angle conventions of the augmentations (docs/conventions.md: angle from +u towards +v) and
the rotated-box geometry (corners, polygon clipping IoU)."""

import math
import unittest

import numpy as np

import _common  # noqa: F401
from detector import augment, geometry
from detector.datasets import Sample, empty_like_arrays


def arrow_image(h=40, w=60, center=(20.0, 15.0), angle=0.3, length=16, width=6):
    """An image with a bright box whose front half is brighter (so the heading is visible)."""
    import cv2

    img = np.zeros((h, w, 3), np.uint8)
    box = np.array([center[0], center[1], length, width, angle])
    cv2.fillPoly(img, [np.round(geometry.box_corners(box)[0]).astype(np.int32)], (100, 100, 100))
    front = box.copy()
    front[:2] += 0.25 * length * np.array([math.cos(angle), math.sin(angle)])
    front[2] = length / 2
    cv2.fillPoly(img, [np.round(geometry.box_corners(front)[0]).astype(np.int32)], (250, 250, 250))
    a = empty_like_arrays(1, 3)
    a["boxes"][0] = box
    a["direction_known"][0] = True
    kp = np.full((1, 36, 3), np.nan, np.float32)
    kp[0, 0] = [*(box[:2] + 0.25 * length * np.array([math.cos(angle), math.sin(angle)])), 1]
    return Sample(image_path=None, image=img, keypoints=kp, **a)


def front_centroid(img):
    ys, xs = np.nonzero(img[..., 0] > 200)
    return np.array([xs.mean(), ys.mean()])


def body_centroid(img):
    ys, xs = np.nonzero(img[..., 0] > 50)
    return np.array([xs.mean(), ys.mean()])


class AngleConsistency(unittest.TestCase):
    def check(self, s):
        """The box angle must point from the body centroid to the bright front half, the centre
        must be at the body centroid, the keypoint at the front centroid."""
        b = s.boxes[0]
        body, front = body_centroid(s.image), front_centroid(s.image)
        np.testing.assert_allclose(b[:2], body, atol=0.6)
        d = front - body
        self.assertLess(float(geometry.abs_angle_difference(math.atan2(d[1], d[0]), b[4])), 0.12)
        np.testing.assert_allclose(s.keypoints[0, 0, :2], front, atol=0.8)
        self.assertTrue(0 <= b[4] < 2 * math.pi)

    def test_identity(self):
        self.check(arrow_image())

    def test_hflip_maps_a_to_pi_minus_a(self):
        for a in (0.3, 2.0, 4.0, 5.9):
            s = augment.hflip(arrow_image(angle=a))
            self.assertAlmostEqual(s.boxes[0, 4], (math.pi - a) % (2 * math.pi), places=9)
            self.check(s)

    def test_vflip_maps_a_to_minus_a(self):
        for a in (0.3, 2.0, 4.0):
            s = augment.vflip(arrow_image(angle=a))
            self.assertAlmostEqual(s.boxes[0, 4], (-a) % (2 * math.pi), places=9)
            self.check(s)

    def test_rot90_clockwise_adds_half_pi(self):
        for k in (1, 2, 3):
            s = augment.rot90(arrow_image(angle=0.3), k)
            self.assertAlmostEqual(s.boxes[0, 4], (0.3 + k * math.pi / 2) % (2 * math.pi), places=9)
            self.assertEqual(s.image.shape[:2], (40, 60) if k % 2 == 0 else (60, 40))
            self.check(s)

    def test_four_rotations_and_two_flips_are_identity(self):
        s0 = arrow_image(angle=1.1)
        s = augment.rot90(augment.rot90(s0, 2), 2)
        s = augment.hflip(augment.hflip(s))
        np.testing.assert_allclose(s.boxes, s0.boxes, atol=1e-9)
        np.testing.assert_array_equal(s.image, s0.image)

    def test_scale_and_crop(self):
        s = augment.scale(arrow_image(angle=0.8), 2.0)
        self.assertAlmostEqual(s.boxes[0, 2], 32.0, places=6)
        self.check(s)
        c = augment.crop(s, 10, 5, 50, 50)
        self.assertEqual(c.image.shape[:2], (50, 50))
        self.check(c)

    def test_axis_aligned_boxes_stay_axis_aligned(self):
        a = empty_like_arrays(1, 3)
        a["boxes"][0] = [10, 5, 8, 4, 0]
        a["aa_only"][0] = True
        s = Sample(image_path=None, image=np.zeros((20, 30, 3), np.uint8), **a)
        r = augment.rot90(s, 1)
        np.testing.assert_allclose(r.boxes[0], [20 - 1 - 5, 10, 4, 8, 0])
        f = augment.hflip(s)
        np.testing.assert_allclose(f.boxes[0], [30 - 1 - 10, 5, 8, 4, 0])

    def test_photometric_keeps_geometry(self):
        s = arrow_image()
        p = augment.photometric(s, np.random.default_rng(0))
        np.testing.assert_array_equal(p.boxes, s.boxes)
        self.assertEqual(p.image.dtype, np.uint8)

    def test_cast_shadow_darkens_and_keeps_geometry(self):
        s = arrow_image()
        s.image[:] = np.maximum(s.image, 200)  # a bright tile: any shadow shows
        darker = 0
        for seed in range(20):
            p = augment.cast_shadow(s, np.random.default_rng(seed))
            np.testing.assert_array_equal(p.boxes, s.boxes)
            self.assertTrue(np.all(p.image.astype(int) <= s.image.astype(int) + 1))
            dark = p.image.mean(2) < 0.7 * s.image.mean(2)
            darker += int(dark.any())
            if dark.any():  # bluer in the shadow: blue (channel 0) keeps more than red
                self.assertGreaterEqual(p.image[dark][:, 0].mean(), p.image[dark][:, 2].mean())
        self.assertGreaterEqual(darker, 15)

    def test_compress_keeps_geometry_and_stays_close(self):
        s = arrow_image()
        p = augment.compress(s, np.random.default_rng(0))
        np.testing.assert_array_equal(p.boxes, s.boxes)
        self.assertEqual(p.image.shape, s.image.shape)
        self.assertLess(np.abs(p.image.astype(int) - s.image.astype(int)).mean(), 12)


class WeightedFocus(unittest.TestCase):
    """Object-centred tiles follow the per-object weights (train.py --hard-weight)."""

    @staticmethod
    def two_far_objects():
        a = empty_like_arrays(2, 3)
        a["boxes"][0] = [20, 20, 10, 4, 0]
        a["boxes"][1] = [380, 380, 10, 6, 0]  # tagged by its width: the crop tells which it kept
        return Sample(image_path=None, image=np.zeros((400, 400, 3), np.uint8), **a)

    def test_uniform_and_weighted(self):
        s, rng = self.two_far_objects(), np.random.default_rng(1)
        picks = []
        for weights in (None, np.array([1.0, 19.0])):
            near_second = 0
            for _ in range(400):
                c = augment.random_crop(s, (64, 64), rng, focus_objects=1.0, weights=weights)
                near_second += bool(len(c)) and bool((c.boxes[:, 3] == 6).any())
            picks.append(near_second / 400)
        self.assertAlmostEqual(picks[0], 0.5, delta=0.1)  # v1's rule: uniform over objects
        self.assertAlmostEqual(picks[1], 0.95, delta=0.05)

    def test_hard_example_weights_mark_large_and_occluded(self):
        from detector.datasets import LARGE
        from detector.train import hard_example_weights

        a = empty_like_arrays(4, 3)
        a["types"][:] = [0, LARGE, 1, 2]
        a["occlusion"][:] = [0.0, 0.0, 0.3, 0.9]
        a["ignore"][3] = True  # too occluded to train on: not hard, just ignored
        s = Sample(image_path=None, **a)
        np.testing.assert_array_equal(hard_example_weights(s, 8.0, 0.2), [1, 8, 8, 1])
        self.assertIsNone(hard_example_weights(s, 1.0, 0.2))


class RotatedIoU(unittest.TestCase):
    def test_identical_and_disjoint(self):
        b = [10, 10, 8, 4, 0.7]
        self.assertAlmostEqual(geometry.rotated_iou(b, b), 1.0, places=9)
        self.assertEqual(geometry.rotated_iou(b, [50, 50, 8, 4, 0.7]), 0.0)

    def test_shifted_axis_aligned(self):
        # two 4x2 boxes shifted by 2 along the length: overlap 2x2 = 4, union 12
        self.assertAlmostEqual(geometry.rotated_iou([0, 0, 4, 2, 0], [2, 0, 4, 2, 0]), 4 / 12, places=9)
        # heading does not change the area: 180 degrees gives IoU 1
        self.assertAlmostEqual(geometry.rotated_iou([0, 0, 4, 2, 0], [0, 0, 4, 2, math.pi]), 1.0, places=9)

    def test_cross(self):
        # a 4x2 box and the same box turned 90 degrees: overlap 2x2 = 4, union 12
        self.assertAlmostEqual(geometry.rotated_iou([0, 0, 4, 2, 0], [0, 0, 4, 2, math.pi / 2]), 4 / 12, places=9)

    def test_against_raster(self):
        import cv2

        rng = np.random.default_rng(3)
        for _ in range(5):
            a = [50 + rng.normal(0, 3), 50 + rng.normal(0, 3), rng.uniform(20, 40), rng.uniform(8, 16), rng.uniform(0, 6.28)]
            b = [50 + rng.normal(0, 3), 50 + rng.normal(0, 3), rng.uniform(20, 40), rng.uniform(8, 16), rng.uniform(0, 6.28)]
            masks = []
            for box in (a, b):
                m = np.zeros((400, 400), np.uint8)
                cv2.fillPoly(m, [np.round(geometry.box_corners(box)[0] * 4).astype(np.int32)], 1)
                masks.append(m.astype(bool))
            raster = (masks[0] & masks[1]).sum() / (masks[0] | masks[1]).sum()
            self.assertAlmostEqual(geometry.rotated_iou(a, b), raster, delta=0.03)

    def test_angle_helpers(self):
        self.assertAlmostEqual(float(geometry.angle_difference(0.1, 2 * math.pi - 0.1)), 0.2)
        self.assertAlmostEqual(float(geometry.axis_angle_difference(0.0, math.pi)), 0.0)
        self.assertAlmostEqual(float(geometry.abs_angle_difference(0.0, math.pi)), math.pi)


if __name__ == "__main__":
    unittest.main()


class RefineInverse(unittest.TestCase):
    """evaluate.apply_refine undoes crops.refine_target: a crop at a jittered (and possibly
    reversed) pose plus its exact targets gives back the true box."""

    def test_round_trip(self):
        from detector import crops, evaluate

        rng = np.random.default_rng(5)
        for _ in range(200):
            gsd = rng.uniform(0.03, 0.2)
            box = np.array([rng.uniform(0, 500), rng.uniform(0, 400), 4.5 / gsd, 1.8 / gsd,
                            rng.uniform(0, 2 * math.pi)])
            cen, ang, _, flip, refine = crops.jittered_crop_target(box, gsd, rng)
            det = np.array([[cen[0], cen[1], 30.0, 12.0, ang, 0.9]])
            out = evaluate.apply_refine(det, np.array([bool(flip)]), refine[None].astype(np.float64), gsd)[0]
            np.testing.assert_allclose(out[:4], box[:4], atol=1e-4)
            self.assertLess(geometry.abs_angle_difference(out[4], box[4]), 1e-5)
            self.assertEqual(out[5], 0.9)
