"""Quantization-aware fine-tuning (qat.py): the trainable graph computes exactly what the QDQ
file computes, an untrained export gives the same file back, and after training the export
still computes exactly what was trained."""

import os
import tempfile
import unittest

import numpy as np
import onnx
import torch
from onnx import numpy_helper

import _common  # noqa: F401
from detector import qat, train
from detector.model import NORMALIZATION, Detector
from test_train_smoke import tiny_run_args, write_synthetic_sequence

qdq = qat.qdq
INPUT_HW = (64, 96)


def write_tiny_export(folder):
    """A random first stage exported as export.py does: float graph + its QDQ rewrite."""
    torch.manual_seed(0)
    det = Detector(n_s=3).eval()
    with torch.no_grad():  # no two equal tensors (the exporter would share them)
        for t in list(det.parameters()) + [b for b in det.buffers() if b.is_floating_point()]:
            t.copy_(torch.rand_like(t) * 0.5 + 0.5 if t.dim() == 1 else t)
    det.export_mode = True
    fp32 = qdq.export_torch(det, (1, 3, *INPUT_HW), output_names=det.output_names(),
                            path=os.path.join(folder, "detector_fp32.onnx"))
    cfg = qdq.QuantConfig(model_name="vp_detector", model_version="7", method="minmax",
                          **NORMALIZATION)
    calib = qdq.preprocess(qdq.synthetic_images(4, *INPUT_HW, seed=3), cfg)
    onnx.save(qdq.quantize_model(fp32, calib, cfg), os.path.join(folder, "detector_int8.onnx"))


def qdq_outputs(model, qdq_path, x):
    """The QDQ file's outputs for ``model``'s outputs (the heatmap before its Sigmoid)."""
    env = qdq.Evaluator(onnx.load(qdq_path)).run({model.input_name: x}, keep_all=True)
    return {name: env[f"{model.sigmoid_inputs[name]}_DequantizeLinear_Output"]
            if name in model.sigmoid_inputs else env[name] for name in model.output_names}


def initializers(path):
    return {t.name: numpy_helper.to_array(t) for t in onnx.load(path).graph.initializer}


class QuantizationAwareTraining(unittest.TestCase):
    def setUp(self):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.tmp = tmp.name
        self.export_dir = os.path.join(tmp.name, "export")
        os.makedirs(self.export_dir)
        write_tiny_export(self.export_dir)
        self.x = np.random.default_rng(1).normal(0, 1, (1, 3, *INPUT_HW)).astype(np.float32)

    def files(self, folder):
        return {k: os.path.join(folder, f"detector_{k}.onnx") for k in ("fp32", "int8")}

    def assert_same_as_qdq_file(self, model, folder):
        with torch.no_grad():
            ours = model(torch.from_numpy(self.x))
        ref = qdq_outputs(model, self.files(folder)["int8"], self.x)
        self.assertEqual(set(ours), {"heatmap", "offset", "size", "direction"})
        for name, value in ref.items():
            np.testing.assert_allclose(ours[name].numpy(), value, rtol=0, atol=1e-5, err_msg=name)

    def test_forward_is_the_int8_graph(self):
        model = qat.QatDetector.from_export(self.export_dir)
        self.assert_same_as_qdq_file(model, self.export_dir)
        # and not the float graph: the fake quantization is on
        fp32 = qdq.Evaluator(onnx.load(self.files(self.export_dir)["fp32"])).run({"input": self.x})
        with torch.no_grad():
            self.assertGreater(np.abs(model(torch.from_numpy(self.x))["size"].numpy()
                                      - fp32["size"]).max(), 1e-3)

    def test_untrained_export_gives_the_same_int8_file(self):
        out = os.path.join(self.tmp, "again")
        qat.QatDetector.from_export(self.export_dir).export(out)
        a, b = initializers(self.files(self.export_dir)["int8"]), initializers(self.files(out)["int8"])
        self.assertEqual(set(a), set(b))
        for name in a:
            np.testing.assert_array_equal(a[name], b[name], err_msg=name)
        meta = [{p.key: p.value for p in onnx.load(self.files(d)["int8"]).metadata_props}
                for d in (self.export_dir, out)]
        meta[0].pop("vp.quantize.calibration_inputs")
        meta[1].pop("vp.quantize.calibration_inputs")
        self.assertEqual(meta[0], meta[1])

    def test_fine_tuning_then_export_runs_what_was_trained(self):
        seq, run, out = (os.path.join(self.tmp, n) for n in ("seq", "run", "qat_export"))
        write_synthetic_sequence(seq)
        args = tiny_run_args(seq, run, 1) + ["--qat-from", self.export_dir, "--max-steps", "20"]
        history = train.train(train.parse_args(args))["history"]
        self.assertEqual(len(history), 20)
        self.assertLess(np.mean([r["det_loss"] for r in history[-5:]]),
                        np.mean([r["det_loss"] for r in history[:5]]))
        self.assertNotIn("crop_loss", history[0])  # first stage only
        self.assertEqual(qat.main(["--checkpoint", os.path.join(run, "checkpoint.pt"), "--out", out]), 0)
        before, after = (initializers(self.files(d)["int8"]) for d in (self.export_dir, out))
        changed = [n for n in before if n.endswith("_quantized") and not np.array_equal(before[n], after[n])]
        self.assertTrue(changed, "training changed no int8 weight")
        # activation parameters stay those of the calibration
        for name in before:
            if name.endswith("_zero_point") or (name.endswith("_scale") and f"{name[:-6]}_quantized" not in before):
                np.testing.assert_array_equal(before[name], after[name], err_msg=name)
        trained = qat.QatDetector.from_export(self.export_dir)
        trained.load_state_dict(torch.load(os.path.join(run, "checkpoint.pt"))["detector"])
        self.assert_same_as_qdq_file(trained, out)
        meta = {p.key: p.value for p in onnx.load(self.files(out)["int8"]).metadata_props}
        self.assertEqual(meta["vp.model.version"], "7+qat20")

    def test_refuses_a_folder_without_the_two_files(self):
        os.remove(self.files(self.export_dir)["int8"])
        with self.assertRaises(SystemExit):
            qat.QatDetector.from_export(self.export_dir)

    def test_refuses_other_training_modes(self):
        args = train.parse_args(["--out", os.path.join(self.tmp, "r"), "--qat-from", self.export_dir,
                                 "--crop-only"])
        with self.assertRaises(SystemExit):
            train.train(args)


if __name__ == "__main__":
    unittest.main()
