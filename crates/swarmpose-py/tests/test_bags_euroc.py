"""A raw EuRoC bag through Python: the first frames of euroc_v1_01_easy_micro written by
the independent `rosbags` writer as raw (distorted, unrectified) CompressedImage PNGs with
each camera's CameraInfo (K, D plumb_bob, R raw to rectified, P the rectified pinhole),
in SQLite. The rectification is computed here from the sensor.yaml files, independently
of swarmpose (the Bouguet-style split of crates/swarmpose-vision/src/rectify, written
from its description); `swarmpose.Sequence` of the bag gives the folder's rectified
camera and pixels, and `swarmpose.odometry` of the bag agrees with the folder's run
within 1 mm and 0.01 degree (the issue's bound; the cargo test
crates/swarmpose-cli/tests/cli/ros_bags.rs checks the same for an MCAP bag of mono8 Images)."""

import json
import re
import shutil

import numpy as np
import pytest

import swarmpose
from bags import make_bag, require_rosbags
from conftest import data_root, require

FRAMES = 10


def sensor(path):
    """(K as fx fy cx cy, D as k1 k2 p1 p2, (width, height), body_from_camera 4x4) of a
    EuRoC sensor.yaml."""
    text = path.read_text()

    def numbers(key):
        block = re.search(key + r":\s*\[([^\]]*)\]", text, re.S)
        return [float(x) for x in block.group(1).replace("\n", " ").split(",")]

    t_bs = np.array(numbers(r"T_BS:[^\[]*data")).reshape(4, 4)
    return numbers("intrinsics"), numbers("distortion_coefficients"), \
        tuple(int(x) for x in numbers("resolution")), t_bs


def rectification(cam0, cam1):
    """(rect_from_left, rect_from_right, f, cx, cy, baseline metres): the new x axis along
    the baseline, the new z axis the mean of the optical axes, the smallest raw focal
    length, the principal point that keeps the raw principal rays near their raw
    principal points (the mean of the two cameras)."""
    right_from_left = np.linalg.inv(cam1[3]) @ cam0[3]
    r, t = right_from_left[:3, :3], right_from_left[:3, 3]
    c_right = -(r.T @ t)
    baseline = np.linalg.norm(c_right)
    ex = c_right / baseline * np.sign(c_right[0])
    z_mean = np.array([0.0, 0.0, 1.0]) + r.T @ np.array([0.0, 0.0, 1.0])
    z_mean /= np.linalg.norm(z_mean)
    ey = np.cross(z_mean, ex)
    ey /= np.linalg.norm(ey)
    rect_from_left = np.array([ex, ey, np.cross(ex, ey)])
    rect_from_right = rect_from_left @ r.T
    f = min(cam0[0][0], cam0[0][1], cam1[0][0], cam1[0][1])
    c = np.zeros(2)
    for cam, rot in ((cam0, rect_from_left), (cam1, rect_from_right)):
        ray = rot[:, 2]
        c += 0.5 * (np.array(cam[0][2:4]) - f * ray[:2] / ray[2])
    return rect_from_left, rect_from_right, f, c[0], c[1], baseline


def euroc_clip(euroc, out, n):
    """A EuRoC folder of the first `n` frames of `euroc` (data.csv, images, sensor.yaml)."""
    for cam in ("cam0", "cam1"):
        src, dst = euroc / "mav0" / cam, out / "mav0" / cam
        (dst / "data").mkdir(parents=True)
        shutil.copy(src / "sensor.yaml", dst / "sensor.yaml")
        lines = (src / "data.csv").read_text().splitlines()[: n + 1]
        (dst / "data.csv").write_text("\n".join(lines) + "\n")
        for line in lines[1:]:
            name = line.split(",")[1].strip()
            shutil.copy(src / "data" / name, dst / "data" / name)
    return out


def raw_frames(folder, out, n):
    """The bag maker's input: each frame's raw PNGs and meta.json with each camera's
    CameraInfo K, D, R (row-major) and P."""
    out.mkdir(parents=True)
    cams = [sensor(folder / "mav0" / c / "sensor.yaml") for c in ("cam0", "cam1")]
    rect_left, rect_right, f, cx, cy, baseline = rectification(*cams)
    stamps = []
    for side, cam in (("left", "cam0"), ("right", "cam1")):
        rows = (folder / "mav0" / cam / "data.csv").read_text().splitlines()[1: n + 1]
        for k, row in enumerate(rows):
            stamp, name = (x.strip() for x in row.split(","))
            shutil.copy(folder / "mav0" / cam / "data" / name, out / f"{side}_{k}.png")
            if side == "left":
                stamps.append(int(stamp))

    def camera(c, r):
        (fx, fy, cx_raw, cy_raw), d = c[0], c[1]
        return {"k": [fx, 0.0, cx_raw, 0.0, fy, cy_raw, 0.0, 0.0, 1.0], "d": d + [0.0],
                "r": r.reshape(9).tolist()}

    def p(tx):
        return [f, 0.0, cx, tx, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0]

    width, height = cams[0][2]
    meta = {"width": width, "height": height, "p_left": p(0.0), "p_right": p(-f * baseline),
            "stamps_ns": stamps,
            "raw": {"left": camera(cams[0], rect_left), "right": camera(cams[1], rect_right)}}
    (out / "meta.json").write_text(json.dumps(meta))
    return out, {"fx": f, "fy": f, "cx": cx, "cy": cy, "baseline": baseline}


def largest_differences(a, b):
    """The largest translation (metres) and rotation (degrees) difference of two pose
    stacks (N, 4, 4)."""
    dt = np.linalg.norm(a[:, :3, 3] - b[:, :3, 3], axis=1).max()
    rel = np.einsum("nji,njk->nik", a[:, :3, :3], b[:, :3, :3])
    cos = np.clip((np.trace(rel, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    return dt, np.degrees(np.arccos(cos)).max()


def test_a_raw_euroc_bag_agrees_with_the_folder(tmp_path):
    require_rosbags()
    euroc = data_root() / "euroc_v1_01_easy_micro"
    require(f"data set {euroc}", euroc.is_dir(), "set SWARMPOSE_DATA to the data root")
    folder = euroc_clip(euroc, tmp_path / "euroc", FRAMES)
    frames, rig = raw_frames(folder, tmp_path / "frames", FRAMES)
    bag = make_bag(frames, tmp_path / "bag", "sqlite3", "png")
    folder_seq, bag_seq = swarmpose.Sequence(folder), swarmpose.Sequence(bag)
    assert (bag_seq.layout, len(bag_seq)) == ("ros2 bag", FRAMES)
    assert bag_seq.topics == ("/stereo/left/image_raw/compressed",
                              "/stereo/right/image_raw/compressed")
    # This test's rectification is swarmpose's (to rounding), and the bag's camera is the
    # folder's.
    for key, value in rig.items():
        assert folder_seq.camera[key] == pytest.approx(value, rel=1e-9, abs=1e-9), key
        assert bag_seq.camera[key] == pytest.approx(folder_seq.camera[key], rel=1e-9), key
    assert bag_seq.stamps_ns == json.loads((frames / "meta.json").read_text())["stamps_ns"]
    # The same rectified pixels (a level may differ by one where a rotation rounded
    # differently puts a sample on the other side of a half).
    for k in (0, FRAMES - 1):
        for got, want in zip(bag_seq[k], folder_seq[k]):
            diff = np.abs(got.astype(int) - want.astype(int))
            assert diff.max() <= 1 and (diff > 0).mean() < 1e-3, (k, diff.max())
    want, got = swarmpose.odometry(folder), swarmpose.odometry(bag)
    assert (len(want), len(got)) == (FRAMES, FRAMES)
    assert got.statuses == want.statuses
    assert sum(s == "tracked" for s in got.statuses) >= FRAMES - 2, got.statuses
    dt, dr = largest_differences(want.poses, got.poses)
    print(f"EuRoC raw bag (SQLite, PNG) vs folder: {FRAMES} frames, largest difference "
          f"{dt:.3e} m, {dr:.3e} deg")
    assert dt <= 1e-3 and dr <= 0.01, (dt, dr)
