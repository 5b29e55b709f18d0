"""pack_real_split.py: only the training side of a split travels, within a size limit."""

import importlib.util
import json
import os
import tempfile
import unittest

import _common  # noqa: F401

_SPEC = importlib.util.spec_from_file_location(
    "pack_real_split", os.path.join(_common.TOOLS, "detector", "device", "pack_real_split.py"))
pack_real_split = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(pack_real_split)


class PackRealSplit(unittest.TestCase):
    def make(self, root, stems):
        os.makedirs(os.path.join(root, "images"))
        os.makedirs(os.path.join(root, "labels"))
        for s in stems:
            with open(os.path.join(root, "images", s + ".jpg"), "wb") as f:
                f.write(b"\0" * 100_000)  # ~0.095 MiB each
            with open(os.path.join(root, "labels", s + ".txt"), "w") as f:
                f.write("0 0.5 0.5 0.1 0.05\n")

    def test_training_side_only_and_within_the_limit(self):
        with tempfile.TemporaryDirectory() as d:
            real = os.path.join(d, "real")
            train = [f"0_{i}" for i in range(8)]
            self.make(real, train + ["2_1", "2_2", "4_7"])  # 4_7: dropped from both sides
            split = os.path.join(d, "split.json")
            with open(split, "w") as f:
                json.dump({"train_stems": train, "val_stems": ["2_1", "2_2"]}, f)
            out = os.path.join(d, "out")
            pack_real_split.main(["--real", real, "--split", split, "--out", out,
                                  "--max-mib", "0.7"])  # 7 of the 8 fit
            copied = sorted(os.listdir(os.path.join(out, "images")))
            self.assertEqual(len(copied), 7)
            self.assertTrue(all(c.startswith("0_") for c in copied))  # never a validation image
            self.assertEqual(len(os.listdir(os.path.join(out, "labels"))), 7)
            with open(os.path.join(out, "split.json")) as f:
                self.assertEqual(json.load(f)["val_stems"], ["2_1", "2_2"])

    def test_refuses_a_split_without_training_list(self):
        with tempfile.TemporaryDirectory() as d:
            self.make(os.path.join(d, "real"), ["0_1"])
            split = os.path.join(d, "split.json")
            with open(split, "w") as f:
                json.dump({"val_stems": []}, f)
            with self.assertRaises(SystemExit) as e:
                pack_real_split.main(["--real", os.path.join(d, "real"), "--split", split,
                                      "--out", os.path.join(d, "out")])
            self.assertIn("train_stems", str(e.exception))


if __name__ == "__main__":
    unittest.main()
