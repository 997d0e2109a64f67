"""The KITTI devkit's segment errors of swarmpose (Python and the CLI) against the
independent numpy implementation in tools/kitti_segments, on KITTI 00's ground truth
and the ORB-SLAM2 and S-PTAM estimates of it (../shared/data/trajectories): the same
segments, and every figure per length and overall within 1e-6 (percent, degrees per
100 m)."""

import importlib.util
import json
import subprocess

import numpy as np
import pytest

import swarmpose
from conftest import REPO, data_root, require

TOOL = REPO / "tools" / "kitti_segments" / "kitti_segments.py"
TOLERANCE = 1e-6


def numpy_tool():
    spec = importlib.util.spec_from_file_location("kitti_segments_numpy", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def trajectories():
    d = data_root() / "trajectories"
    gt = d / "KITTI_00_gt.txt"
    require(f"KITTI 00 trajectories in {d}", gt.is_file(), "set SWARMPOSE_DATA to the data root")
    return d


def assert_same(ours, theirs):
    assert len(ours["segments"]) == len(theirs["segments"])
    for a, b in zip(ours["segments"], theirs["segments"]):
        assert (a["first_frame"], a["last_frame"]) == (b["first_frame"], b["last_frame"])
        assert a["length_m"] == b["length_m"]
    keys = ("translation_percent", "rotation_deg_per_100m")
    for a, b in zip(ours["per_length"], theirs["per_length"], strict=True):
        assert (a["length_m"], a["n"]) == (b["length_m"], b["n"])
        for k in keys:
            assert abs(a[k] - b[k]) <= TOLERANCE, (a, b)
    for k in keys:
        assert abs(ours[k] - theirs[k]) <= TOLERANCE, (k, ours[k], theirs[k])
    # Per segment: translation within 1e-6 too; a rotation error near 0 is acos of a trace
    # near 3, where a rounding of 1e-15 in the trace moves the angle by about 5e-8 rad
    # (3e-6 deg/100 m on a 100 m segment): per segment the rotation agrees to 1e-5.
    pairs = list(zip(ours["segments"], theirs["segments"]))
    worst_t = max(abs(a[keys[0]] - b[keys[0]]) for a, b in pairs)
    worst_r = max(abs(a[keys[1]] - b[keys[1]]) for a, b in pairs)
    assert worst_t <= TOLERANCE and worst_r <= 10 * TOLERANCE, (worst_t, worst_r)


@pytest.mark.parametrize("name", ["gt", "ORB", "SPTAM"])
def test_python_agrees_with_the_numpy_devkit(trajectories, name):
    est, gt = trajectories / f"KITTI_00_{name}.txt", trajectories / "KITTI_00_gt.txt"
    theirs = numpy_tool().evaluate(est, gt)
    ours = swarmpose.evaluate(est, gt)["kitti"]
    assert len(ours["per_length"]) == 8 and len(ours["segments"]) == 3283
    assert_same(ours, theirs)
    if name == "gt":
        assert ours["translation_percent"] < 1e-9 and ours["rotation_deg_per_100m"] < 1e-4


def test_cli_agrees_with_the_numpy_devkit(trajectories, swarmpose_bin):
    est, gt = trajectories / "KITTI_00_ORB.txt", trajectories / "KITTI_00_gt.txt"
    out = subprocess.run([str(swarmpose_bin), "evaluate", str(est), str(gt), "--format", "kitti",
                          "--kitti-segments", "--json"], capture_output=True, text=True, check=True)
    assert_same(json.loads(out.stdout), numpy_tool().evaluate(est, gt))


def test_scaled_lengths_on_a_clip(trajectories):
    # The first 600 frames (about 430 m): at a tenth, 10-80 m segments, as the tool.
    tool = numpy_tool()
    gt = tool.read_kitti(trajectories / "KITTI_00_gt.txt")[:600]
    est = tool.read_kitti(trajectories / "KITTI_00_SPTAM.txt")[:600]
    theirs = tool.summary(tool.sequence_errors(tool.nearest_rotations(gt), tool.nearest_rotations(est),
                                               0.1), 0.1)
    ours = swarmpose.evaluate(est, gt, segment_scale=0.1)["kitti"]
    assert "not comparable" in ours["note"]
    assert_same(ours, theirs)
    with pytest.raises(ValueError, match="scale"):
        swarmpose.evaluate(est, gt, segment_scale=0.0)


def test_a_short_path_has_no_segment():
    steps = np.tile(np.eye(4), (20, 1, 1))
    steps[:, 2, 3] = np.arange(20.0)
    k = swarmpose.evaluate(steps, steps)["kitti"]
    assert k["translation_percent"] is None and k["segments"] == []
    assert "19.0 m" in k["note"]
