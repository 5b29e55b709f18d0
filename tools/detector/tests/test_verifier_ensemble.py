"""verifier_ensemble.py: one crop network whose verifier is the mean of two verifiers' logits."""

import os
import tempfile
import unittest

import torch

import _common  # noqa: F401
from detector import verifier_ensemble
from detector.model import CROP_H, CROP_W, CropNet


def _checkpoint(net: CropNet) -> dict:
    return {"crop": {k: v.clone() for k, v in net.state_dict().items()}, "n_s": net.n_s,
            "detector": None}


class VerifierEnsemble(unittest.TestCase):
    def setUp(self):
        torch.manual_seed(3)
        # A verifier on the shared layer (as v6-v13) and a branch trained on top of the same body.
        self.shared = CropNet(verifier=True, flip_branch=True).eval()
        self.branched = CropNet(verifier=True, flip_branch=True, verifier_branch=True).eval()
        state = self.shared.state_dict()
        state.update({k: v for k, v in self.branched.state_dict().items()
                      if k.startswith("verifier_fc") or k.startswith("vehicle_logit")})
        self.branched.load_state_dict(state)
        for p in list(self.branched.verifier_fc.parameters()) + list(
                self.branched.vehicle_logit.parameters()):
            p.data.normal_(0.0, 0.05)
        self.x = torch.randn(5, 3, CROP_H, CROP_W)

    def _merged(self, weight: float) -> CropNet:
        state = verifier_ensemble.merge(_checkpoint(self.shared)["crop"],
                                        _checkpoint(self.branched)["crop"], weight)
        return CropNet.from_state_dict(state, n_s=3).eval()

    def test_logit_is_the_weighted_mean_and_the_rest_is_base(self):
        with torch.no_grad():
            a, b = self.shared(self.x), self.branched(self.x)
            for w in (0.5, 0.25):
                m = self._merged(w)(self.x)
                self.assertEqual(m["vehicle_logit"].shape, a["vehicle_logit"].shape)
                torch.testing.assert_close(
                    m["vehicle_logit"], (1 - w) * a["vehicle_logit"] + w * b["vehicle_logit"],
                    atol=1e-5, rtol=0)
                for k in ("type_logits", "shape", "flip_logit", "refine"):
                    torch.testing.assert_close(m[k], a[k], atol=0, rtol=0)
        # The two verifiers differ on these inputs, so the mean is neither of them.
        self.assertGreater((a["vehicle_logit"] - b["vehicle_logit"]).abs().max().item(), 1e-3)

    def test_edge_head_is_the_base_verifier_alone(self):
        state = verifier_ensemble.merge(_checkpoint(self.shared)["crop"],
                                        _checkpoint(self.branched)["crop"], 0.5, edge_base=True)
        net = CropNet.from_state_dict(state, n_s=3).eval()
        self.assertTrue(net.verifier_edge)
        self.assertEqual(net.output_names()[-2:], ["vehicle_logit", "vehicle_logit_edge"])
        with torch.no_grad():
            m, a, b = net(self.x), self.shared(self.x), self.branched(self.x)
            torch.testing.assert_close(m["vehicle_logit_edge"], a["vehicle_logit"], atol=1e-5,
                                       rtol=0)
            torch.testing.assert_close(m["vehicle_logit"],
                                       0.5 * (a["vehicle_logit"] + b["vehicle_logit"]),
                                       atol=1e-5, rtol=0)
        # Without the option there is no second head.
        self.assertFalse(self._merged(0.5).verifier_edge)

    def test_branch_is_twice_as_wide(self):
        self.assertEqual(self._merged(0.5).verifier_fc[0].out_channels, 384)

    def test_different_bodies_are_refused(self):
        other = _checkpoint(self.branched)["crop"]
        other["body.2.0.weight"] = other["body.2.0.weight"] + 0.1
        with self.assertRaisesRegex(SystemExit, "differ in body.2.0.weight"):
            verifier_ensemble.merge(_checkpoint(self.shared)["crop"], other, 0.5)

    def test_command_line(self):
        with tempfile.TemporaryDirectory() as d:
            a, b, out = (os.path.join(d, n) for n in ("a.pt", "b.pt", "ab.pt"))
            torch.save(_checkpoint(self.shared), a)
            torch.save(_checkpoint(self.branched), b)
            self.assertEqual(verifier_ensemble.main(["--base", a, "--other", b, "--out", out]), 0)
            ck = torch.load(out, map_location="cpu", weights_only=False)
            net = CropNet.from_state_dict(ck["crop"], n_s=ck["n_s"]).eval()
            with torch.no_grad():
                torch.testing.assert_close(
                    net(self.x)["vehicle_logit"],
                    0.5 * (self.shared(self.x)["vehicle_logit"]
                           + self.branched(self.x)["vehicle_logit"]), atol=1e-5, rtol=0)
            with self.assertRaisesRegex(SystemExit, "--weight must be in"):
                verifier_ensemble.main(["--base", a, "--other", b, "--out", out, "--weight", "2"])
            torch.save({"crop": None}, b)
            with self.assertRaisesRegex(SystemExit, "not a checkpoint with a crop network"):
                verifier_ensemble.main(["--base", a, "--other", b, "--out", out])


if __name__ == "__main__":
    unittest.main()
