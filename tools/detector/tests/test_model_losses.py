"""Model shapes, engine-only export, the two shape losses, target encoding and decoding."""

import math
import unittest

import numpy as np
import torch

import _common  # noqa: F401
from detector import asm as asm_mod
from detector import evaluate, export, losses, targets
from detector.datasets import Sample, empty_like_arrays
from detector.model import CROP_H, CROP_W, NUM_TYPES, CropNet, Detector, macs


class ModelShapes(unittest.TestCase):
    def test_detector_outputs(self):
        m = Detector(single_stage=True).eval()
        out = m(torch.zeros(2, 3, 128, 160))
        self.assertEqual(out["heatmap"].shape, (2, 1, 32, 40))
        for k, c in (("offset", 2), ("size", 2), ("direction", 2), ("type", NUM_TYPES), ("shape", 3)):
            self.assertEqual(out[k].shape, (2, c, 32, 40), k)

    def test_crop_outputs(self):
        out = CropNet().eval()(torch.zeros(3, 3, CROP_H, CROP_W))
        self.assertEqual(out["type_logits"].shape, (3, NUM_TYPES, 1, 1))
        self.assertEqual(out["shape"].shape, (3, 3, 1, 1))
        self.assertEqual(out["flip_logit"].shape, (3, 1, 1, 1))
        self.assertEqual(out["refine"].shape, (3, 5, 1, 1))

    def test_mac_budget(self):
        # design budget: <= 1 GMAC per frame at 672 x 512 (<= 0.2 GMAC per camera megapixel)
        total = macs(Detector(), (512, 672))["total"]
        self.assertLess(total, 1.0e9)
        self.assertLess(macs(CropNet(), (CROP_H, CROP_W))["total"], 10e6)


class ExportUsesEngineOpsOnly(unittest.TestCase):
    def test_float_and_qdq_graphs(self):
        import sys

        sys.path.insert(0, _common.os.path.join(_common.REPO, "tools", "quantize"))
        import qdq

        for module, shape in ((Detector(single_stage=True), (1, 3, 64, 96)), (CropNet(), (1, 3, CROP_H, CROP_W))):
            module.export_mode = True
            fp32 = qdq.export_torch(module, shape, output_names=module.output_names())
            self.assertEqual(export.engine_ops_only(fp32), [])
            self.assertEqual(fp32.opset_import[0].version, 13)
            ops = {n.op_type for n in fp32.graph.node}
            self.assertNotIn("BatchNormalization", ops)
            cfg = qdq.QuantConfig()
            calib = qdq.preprocess(qdq.synthetic_images(2, shape[2], shape[3], seed=1), cfg)
            q = qdq.quantize_model(fp32, calib, cfg)
            self.assertEqual(export.engine_ops_only(q), [])
            self.assertEqual([o.name for o in q.graph.output], module.output_names())
            self.assertGreater(export.onnx_macs(fp32), 0)

    def test_walker_rejects_other_ops(self):
        import onnx
        from onnx import helper, TensorProto

        g = helper.make_graph([helper.make_node("Softmax", ["x"], ["y"], name="sm")], "g",
                              [helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 3, 4, 4])],
                              [helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, 3, 4, 4])])
        self.assertEqual(export.engine_ops_only(helper.make_model(g)), ["sm (Softmax)"])


class ShapeLosses(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.asm = asm_mod.load_asm()

    def test_asm_file(self):
        self.assertEqual(self.asm.n_s, 3)
        self.assertEqual(self.asm.mean.shape, (36, 3))
        # Eq. 1 at gamma = 0 is the mean; gamma_1 = +2 makes the car longer (docs/asm.md table)
        m0 = self.asm.shape([0, 0, 0])
        np.testing.assert_allclose(m0, self.asm.mean)
        m2 = self.asm.shape([2, 0, 0])
        length = lambda m: m[:, 0].max() - m[:, 0].min()  # noqa: E731
        self.assertAlmostEqual(length(m2), 5.10, delta=0.02)

    def test_zero_at_truth_positive_otherwise(self):
        g = torch.tensor([[0.3, -1.2, 0.5], [1.0, 0.0, -0.4]])
        for loss in (losses.shape_loss_l1, losses.ShapeLossL2(self.asm)):
            self.assertEqual(float(loss(g.clone(), g)), 0.0)
            p = g.clone()
            p[0, 1] += 0.1
            self.assertGreater(float(loss(p, g)), 0.0)
            pr = g.clone().requires_grad_(True)
            loss(pr, g).backward()
            self.assertTrue(torch.isfinite(pr.grad).all())

    def test_l2_is_mean_keypoint_distance_in_metres(self):
        g = torch.zeros(1, 3)
        p = torch.tensor([[1.0, 0.0, 0.0]])
        expect = np.linalg.norm(self.asm.shape([1, 0, 0]) - self.asm.shape([0, 0, 0]), axis=1).mean()
        self.assertAlmostEqual(float(losses.ShapeLossL2(self.asm)(p, g)), expect, places=5)
        # V_L1 of the same error: gamma units
        self.assertAlmostEqual(float(losses.shape_loss_l1(p, g)), 1.0)


def one_car(h=64, w=96, box=(40.3, 30.6, 24, 10, 2.5)):
    a = empty_like_arrays(1, 3)
    a["boxes"][0] = box
    a["direction_known"][0] = True
    a["types"][0] = 3
    a["gammas"][0] = [0.1, 0.2, 0.3]
    return Sample(image_path=None, image=np.zeros((h, w, 3), np.uint8), **a)


class TargetsAndDecode(unittest.TestCase):
    def test_encode_decode_round_trip(self):
        s = one_car()
        t = targets.encode(s)
        self.assertEqual(t["heatmap"].shape, (1, 16, 24))
        self.assertEqual(float(t["heatmap"].max()), 1.0)
        self.assertEqual(t["mask"].sum(), 1)
        # the perfect network output: heatmap = target, regression maps = targets at the peak
        out = {"heatmap": t["heatmap"], "offset": np.zeros((2, 16, 24)), "size": np.zeros((2, 16, 24)),
               "direction": np.zeros((2, 16, 24))}
        iy, ix = divmod(int(t["ind"][0]), 24)
        out["offset"][:, iy, ix] = t["offset"][0]
        out["size"][:, iy, ix] = t["log_size"][0]
        out["direction"][:, iy, ix] = t["direction"][0]
        det = evaluate.decode(out, threshold=0.5)
        self.assertEqual(len(det), 1)
        np.testing.assert_allclose(det[0, :5], s.boxes[0], atol=1e-5)

    def test_detector_loss_handles_all_label_kinds(self):
        s = one_car()
        aa = empty_like_arrays(1, 3)
        aa["boxes"][0] = [50, 20, 20, 12, 0]
        aa["aa_only"][0] = True
        s2 = Sample(image_path=None, image=np.zeros((64, 96, 3), np.uint8), **aa)
        batch = {k: torch.from_numpy(v) for k, v in targets.collate([targets.encode(s), targets.encode(s2)]).items()}
        m = Detector(single_stage=True)
        total, terms = losses.detector_loss(m(torch.zeros(2, 3, 64, 96)), batch, losses.ShapeLossL2(self.asm if hasattr(self, "asm") else asm_mod.load_asm()))
        self.assertTrue(math.isfinite(float(total)))
        for k in ("heatmap", "offset", "size", "direction", "aa", "type", "shape"):
            self.assertIn(k, terms)
            self.assertTrue(math.isfinite(terms[k]), k)
        self.assertGreater(terms["aa"], 0)
        total.backward()

    def test_matching_metrics(self):
        acc = evaluate.Accumulator()
        gt = np.array([[10, 10, 20, 8, 0.0], [60, 60, 20, 8, 1.0]])
        pred = np.array([[10.5, 10, 20, 8, math.radians(2), 0.9], [100, 100, 20, 8, 0, 0.8]])
        acc.add(pred, gt, np.array([False, False]), np.array([True, True]), np.array([0.1, 0.1]))
        r = acc.result()
        self.assertEqual((r["tp"], r["fp"], r["fn"]), (1, 1, 1))
        self.assertAlmostEqual(r["f1"], 0.5)
        self.assertAlmostEqual(r["orientation_median_deg"], 2.0, places=6)
        self.assertAlmostEqual(r["position_median_m"], 0.05, places=6)


if __name__ == "__main__":
    unittest.main()
