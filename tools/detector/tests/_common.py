"""Shared helpers of the detector tests: puts tools/ on sys.path, locates the repo and data."""

import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.path.dirname(os.path.dirname(HERE))
REPO = os.path.dirname(TOOLS)
if TOOLS not in sys.path:
    sys.path.insert(0, TOOLS)

FIXTURE_SEQ = os.path.join(REPO, "tests", "fixtures", "sequence_min")
# The shared data sit beside the repository (../shared), as on developer machines and in CI.
REAL_DIR = os.environ.get(
    "VP_REAL_DATA", os.path.join(os.path.dirname(REPO), "shared", "data", "real", "cats-madison"))


def find_simulator():
    if os.access(os.environ.get("VP_SIMULATE", ""), os.X_OK):
        return os.environ["VP_SIMULATE"]
    for rel in ("build/ci/tools/simulator/vp_simulate", "build/release/tools/simulator/vp_simulate",
                "build-sim/tools/simulator/vp_simulate", "build/tools/simulator/vp_simulate"):
        p = os.path.join(REPO, rel)
        if os.access(p, os.X_OK):
            return p
    return None
