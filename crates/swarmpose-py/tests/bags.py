"""ROS 2 bags made at test time for the pytest suite, by the independent `rosbags` writer
(crates/swarmpose-ros/tests/py/make_stereo_bag.py, the script the Rust tests use)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from conftest import REPO, require

MAKER = REPO / "crates" / "swarmpose-ros" / "tests" / "py" / "make_stereo_bag.py"
# The first frame's header stamp (nanoseconds) and the frame period.
T0_NS = 1_317_000_000_000_000_000
PERIOD_NS = 100_000_000


def require_rosbags() -> None:
    """Skips (fails under CI=true) without the `rosbags` writer in this Python."""
    try:
        import rosbags  # noqa: F401
        found = True
    except ImportError:
        found = False
    require("the Python package rosbags", found, "pip install rosbags==0.11.9")


def kitti_projection(calib: Path, key: str) -> list:
    line = next(l for l in calib.read_text().splitlines() if l.startswith(key))
    return [float(x) for x in line[len(key):].split()]


def kitti_clip(kitti: Path, out: Path, frames: int, ground_truth: bool = False) -> Path:
    """A KITTI folder of the first `frames` frames of `kitti` (calib.txt and images; and
    their poses.txt with `ground_truth`)."""
    for d in ("image_0", "image_1"):
        (out / d).mkdir(parents=True)
        for k in range(frames):
            name = f"{k:06}.png"
            (out / d / name).write_bytes((kitti / d / name).read_bytes())
    (out / "calib.txt").write_text((kitti / "calib.txt").read_text())
    if ground_truth:
        poses = (kitti / "poses.txt").read_text().splitlines(keepends=True)[:frames]
        (out / "poses.txt").write_text("".join(poses))
    return out


def frames_dir(seq, calib: Path, out: Path) -> Path:
    """The bag maker's input: meta.json and each frame's gray pixels from `seq` (a
    swarmpose.Sequence of a KITTI folder)."""
    out.mkdir(parents=True)
    cam = seq.camera
    meta = {
        "width": cam["width"], "height": cam["height"],
        "p_left": kitti_projection(calib, "P0:"), "p_right": kitti_projection(calib, "P1:"),
        "stamps_ns": [T0_NS + k * PERIOD_NS for k in range(len(seq))],
    }
    (out / "meta.json").write_text(json.dumps(meta))
    for k in range(len(seq)):
        left, right = seq[k]
        (out / f"left_{k}.raw").write_bytes(np.ascontiguousarray(left).tobytes())
        (out / f"right_{k}.raw").write_bytes(np.ascontiguousarray(right).tobytes())
    return out


def make_bag(frames: Path, out: Path, storage: str, *options: str) -> Path:
    """Writes the bag folder `out` (storage mcap, mcap-zstd or sqlite3)."""
    subprocess.run([sys.executable, str(MAKER), str(frames), str(out), storage, *options],
                   check=True, capture_output=True)
    return out


def file_in(bag: Path, ext: str) -> Path:
    """The bag's one storage file with this extension."""
    return next(p for p in bag.iterdir() if p.suffix == ext)
