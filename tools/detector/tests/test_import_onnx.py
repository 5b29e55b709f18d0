"""import_onnx.py: a checkpoint rebuilt from exported files computes what the files compute,
in eval mode and, on its calibration batch, in train mode too; it loads where a training
checkpoint loads; a file that does not fit the model is refused with the reason."""

import os
import tempfile
import unittest

import numpy as np
import onnx
import torch

import _common  # noqa: F401
from detector import export, import_onnx
from detector.model import CROP_H, CROP_W, NORMALIZATION, CropNet, Detector

qdq = import_onnx.qdq
INPUT_HW = (64, 96)


def randomized(module):
    """Trained-looking weights and batch-norm statistics, so that folding matters."""
    torch.manual_seed(0)
    with torch.no_grad():
        for name, t in module.state_dict().items():
            if name.endswith("running_var"):
                t.copy_(torch.rand_like(t) + 0.5)
            elif name.endswith("running_mean") or name.endswith("bias"):
                t.copy_(torch.randn_like(t) * 0.2)
            elif t.is_floating_point() and name.endswith("weight") and t.dim() == 1:
                t.copy_(torch.rand_like(t) + 0.5)
            elif t.is_floating_point():
                t.copy_(torch.randn_like(t) * 0.3)
    return module.eval()


def write_files(folder, name, module, shape):
    module.export_mode = True
    fp32 = qdq.export_torch(module, (1, 3, *shape), output_names=module.output_names(),
                            path=os.path.join(folder, f"{name}_fp32.onnx"))
    module.export_mode = False
    cfg = qdq.QuantConfig(model_name="vp_test", model_version="42", method="minmax", **NORMALIZATION)
    calib = qdq.preprocess(qdq.synthetic_images(4, *shape, seed=3), cfg)
    path = os.path.join(folder, f"{name}_int8.onnx")
    onnx.save(qdq.quantize_model(fp32, calib, cfg), path)
    return path


class ImportOnnx(unittest.TestCase):
    def setUp(self):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.tmp = tmp.name
        self.det = randomized(Detector(n_s=3))
        self.crop = randomized(CropNet(n_s=3, verifier=True))
        self.det_int8 = write_files(self.tmp, "detector", self.det, INPUT_HW)
        self.crop_int8 = write_files(self.tmp, "crop", self.crop, (CROP_H, CROP_W))
        rng = np.random.default_rng(5)
        self.calib_det = rng.integers(0, 256, (3, *INPUT_HW, 3), dtype=np.uint8)
        self.calib_crop = rng.integers(0, 256, (12, CROP_H, CROP_W, 3), dtype=np.uint8)

    def test_int8_files_come_back_as_they_compute(self):
        ck = import_onnx.import_files(self.det_int8, self.crop_int8, 3, self.calib_det,
                                      self.calib_crop, log=lambda *_: None)
        self.assertEqual(ck["step"], 42)
        crop = CropNet.from_state_dict(ck["crop"], n_s=3).eval()
        self.assertTrue(crop.verifier)
        x = import_onnx.normalized(self.calib_crop[:3])
        errs = import_onnx.check_against_file(crop, onnx.load(self.crop_int8), x)
        self.assertEqual(set(errs), set(crop.output_names()))
        self.assertLess(max(errs.values()), 1e-5)
        # The dequantized int8 weights, not the float ones: the import differs from the float
        # module by about the weights' rounding.
        with torch.no_grad():
            diff = (crop(x)["shape"] - self.crop(x)["shape"]).abs().max().item()
        self.assertGreater(diff, 1e-6)

    def test_the_branch_layout_is_read_from_the_file(self):
        # One extra fully connected Conv is a front/back or a verifier branch: the file's outputs
        # tell which; both branches make two.
        # A verifier branch twice as wide holds two verifiers averaged (verifier_ensemble.py).
        for flip_branch, verifier_branch, width in [(True, False, 192), (False, True, 192),
                                                    (True, True, 192), (True, True, 384)]:
            net = CropNet(n_s=3, verifier=True, flip_branch=flip_branch,
                          verifier_branch=verifier_branch, verifier_width=width)
            path = write_files(self.tmp, f"crop_{flip_branch}_{verifier_branch}_{width}",
                               randomized(net), (CROP_H, CROP_W))
            ck = import_onnx.import_files(self.det_int8, path, 3, self.calib_det,
                                          self.calib_crop, log=lambda *_: None)
            crop = CropNet.from_state_dict(ck["crop"], n_s=3).eval()
            self.assertEqual((crop.flip_branch, crop.verifier_branch),
                             (flip_branch, verifier_branch))
            if verifier_branch:
                self.assertEqual(crop.verifier_fc[0].out_channels, width)
            errs = import_onnx.check_against_file(
                crop, onnx.load(path), import_onnx.normalized(self.calib_crop[:3]))
            self.assertLess(max(errs.values()), 1e-5)

    def test_train_mode_on_the_calibration_batch_is_eval_mode(self):
        ck = import_onnx.import_files(self.det_int8, self.crop_int8, 3, self.calib_det,
                                      self.calib_crop, log=lambda *_: None)
        crop = CropNet.from_state_dict(ck["crop"], n_s=3)
        x = import_onnx.normalized(self.calib_crop)
        with torch.no_grad():
            evals = crop.eval()(x)
            trains = crop.train()(x)  # batch statistics = the imported running statistics
        for k in evals:
            scale = evals[k].abs().max().item()
            self.assertLess((evals[k] - trains[k]).abs().max().item(), 1e-3 * scale, k)
        # Without calibration inputs train mode is far from it: the statistics matter.
        ck0 = import_onnx.import_files(self.det_int8, self.crop_int8, 3, log=lambda *_: None)
        crop0 = CropNet.from_state_dict(ck0["crop"], n_s=3)
        with torch.no_grad():
            far = (crop0.train()(x)["shape"] - evals["shape"]).abs().max().item()
        self.assertGreater(far, 1e-2 * evals["shape"].abs().max().item())

    def test_checkpoint_loads_like_a_training_run(self):
        out = os.path.join(self.tmp, "run", "checkpoint.pt")
        import_onnx.main(["--detector", self.det_int8, "--crop", self.crop_int8, "--out", out])
        ck, det, crop = export.load_run(out)
        self.assertEqual(ck["imported_from"], [self.det_int8, self.crop_int8])
        x = torch.from_numpy(np.random.default_rng(2).normal(0, 1, (1, 3, *INPUT_HW)).astype(np.float32))
        errs = import_onnx.check_against_file(det, onnx.load(self.det_int8), x)
        self.assertLess(max(errs.values()), 1e-5)

    def test_a_files_activation_ranges_requantize_it_exactly(self):
        # export.py --ranges-from: the ranges read back from a QDQ file, with other calibration
        # inputs, give that file's activation scales and zero points again.
        fp32 = onnx.load(os.path.join(self.tmp, "crop_fp32.onnx"))
        shipped = onnx.load(self.crop_int8)
        ranges = qdq.ranges_of_qdq(shipped)
        self.assertGreater(len(ranges), 10)
        cfg = qdq.QuantConfig(model_name="vp_test", model_version="42", method="minmax", **NORMALIZATION)
        other = qdq.preprocess(qdq.synthetic_images(2, CROP_H, CROP_W, seed=9), cfg)
        calibrated = qdq.collect_ranges(qdq.prepare_float_model(fp32), other, cfg)
        calibrated.update(ranges)
        again = qdq.quantize_model(fp32, other, cfg, calibrated)
        fresh = qdq.quantize_model(fp32, other, cfg)  # calibrated on the other inputs alone

        def scales(m):
            return {t.name: onnx.numpy_helper.to_array(t) for t in m.graph.initializer
                    if t.name.endswith("_scale") or t.name.endswith("_zero_point")}
        a, b, c = scales(shipped), scales(again), scales(fresh)
        self.assertEqual(set(a), set(b))
        for name in a:
            np.testing.assert_array_equal(a[name], b[name], err_msg=name)
        self.assertTrue(any(not np.array_equal(a[n], c[n]) for n in a))

    def test_a_file_of_another_model_is_refused(self):
        with self.assertRaisesRegex(ValueError, "Detector does not run at the file's input size"):
            import_onnx.import_files(self.crop_int8, None, 3, log=lambda *_: None)
        with self.assertRaisesRegex(ValueError, "the crop network takes"):
            import_onnx.import_files(self.det_int8, self.det_int8, 3, log=lambda *_: None)
        text = os.path.join(self.tmp, "notes.onnx")
        with open(text, "w") as f:
            f.write("not a model\n")
        with self.assertRaisesRegex(ValueError, "notes.onnx' is not an ONNX model"):
            import_onnx.import_files(text, None, 3, log=lambda *_: None)
        other = randomized(CropNet(n_s=5))
        path = write_files(self.tmp, "crop5", other, (CROP_H, CROP_W))
        with self.assertRaisesRegex(ValueError, "weight shape"):
            import_onnx.import_files(self.det_int8, path, 3, log=lambda *_: None)


if __name__ == "__main__":
    unittest.main()
