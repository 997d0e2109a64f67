"""A run's odometry.mcap, decoded by two independent readers (Foxglove's
mcap-ros2-support and rosbags): one nav_msgs/Odometry per frame whose pose is the frame's
line of trajectory.kitti.txt and whose covariance is its row of motion_covariance.csv,
both converted as crates/swarmpose-ros/src/convert.rs documents (odom has ROS body axes:
x = optical z, y = -optical x, z = -optical y; covariance J C J^T, J = diag(R, R)); and
evo_ape on the MCAP's topics gives the ATE of `swarmpose evaluate`."""

import csv
import json
import shutil
import subprocess
import zipfile

import numpy as np
import pytest

from bags import kitti_clip
from conftest import require

FRAMES = 10
ODOMETRY = "/swarmpose/odometry"
TRUTH = "/swarmpose/ground_truth/pose"
# Optical camera axes to ROS body axes (convert.rs, odom_from_optical).
A = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
UNKNOWN_VARIANCE = 1e6


def rotation(q):
    """The rotation matrix of a geometry_msgs Quaternion."""
    x, y, z, w = q.x, q.y, q.z, q.w
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def as_arrays(msgs):
    """(stamps ns, positions (N, 3), rotations (N, 3, 3), covariances (N, 6, 6))."""
    stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in msgs]
    pos = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z]
                    for m in msgs])
    rot = np.array([rotation(m.pose.pose.orientation) for m in msgs])
    cov = np.array([np.asarray(m.pose.covariance, dtype=float).reshape(6, 6) for m in msgs])
    return stamps, pos, rot, cov


def read_mcap_ros2(path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [m for _, _, _, m in reader.iter_decoded_messages(topics=[ODOMETRY])]


def read_rosbags(path):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        conns = [c for c in reader.connections if c.topic == ODOMETRY]
        return [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(conns)]


def expected_covariances(out, rotations_odom):
    """motion_covariance.csv converted: J C J^T per tracked frame; the first frame zero,
    frames without a measured covariance UNKNOWN_VARIANCE on the diagonal."""
    n = len(rotations_odom)
    want = np.tile(np.eye(6) * UNKNOWN_VARIANCE, (n, 1, 1))
    want[0] = 0.0
    rows = [l for l in (out / "motion_covariance.csv").read_text().splitlines()
            if l and not l.startswith("#") and not l.startswith("frame")]
    iu = np.triu_indices(6)
    for row in rows:
        v = row.split(",")
        c = np.zeros((6, 6))
        c[iu] = [float(x) for x in v[9:]]
        c = c + np.triu(c, 1).T
        j = np.zeros((6, 6))
        j[:3, :3] = j[3:, 3:] = rotations_odom[int(v[0])]
        want[int(v[0])] = j @ c @ j.T
    return want, len(rows)


def evo_ate(mcap, out):
    """evo_ape's ATE RMSE (translation, metres) of the MCAP's Odometry against its ground
    truth, after SE(3) alignment."""
    results = out / "evo.zip"
    args = ["evo_ape", "bag2", str(mcap), TRUTH, ODOMETRY, "-a", "--save_results", str(results),
            "--no_warnings"]
    subprocess.run(args, check=True, capture_output=True, text=True)
    with zipfile.ZipFile(results) as z:
        return json.loads(z.read("stats.json"))["rmse"]


def require_readers():
    """Skips (fails under CI=true) without both independent readers."""
    for module in ("rosbags", "mcap_ros2"):
        try:
            __import__(module)
            found = True
        except ImportError:
            found = False
        require(f"the Python package {module}", found,
                "pip install rosbags==0.11.9 mcap-ros2-support==0.6.0")


def test_odometry_mcap_decodes_to_the_run(kitti_seq2, swarmpose_bin, tmp_path):
    require_readers()
    folder = kitti_clip(kitti_seq2, tmp_path / "kitti", FRAMES, ground_truth=True)
    out = tmp_path / "out"
    subprocess.run([str(swarmpose_bin), "odometry", str(folder), "--out", str(out), "--quiet"],
                   check=True, capture_output=True)
    mcap = out / "odometry.mcap"
    rows = np.loadtxt(out / "trajectory.kitti.txt").reshape(-1, 3, 4)
    assert len(rows) == FRAMES
    pos_want = rows[:, :, 3] @ A.T
    rot_want = A @ rows[:, :, :3]
    cov_want, measured = expected_covariances(out, rot_want)
    assert measured >= FRAMES - 2, "most frames carry a measured covariance"
    decoded = {"mcap-ros2-support": as_arrays(read_mcap_ros2(mcap)),
               "rosbags": as_arrays(read_rosbags(mcap))}
    for reader, (stamps, pos, rot, cov) in decoded.items():
        assert len(stamps) == FRAMES, reader
        assert stamps == [k * 100_000_000 for k in range(FRAMES)], reader
        # x = optical z, y = -optical x, z = -optical y (applied as a quaternion: to
        # rounding).
        assert np.max(np.abs(pos - pos_want)) <= 1e-12 * max(1.0, np.max(np.abs(pos_want))), reader
        assert np.max(np.abs(rot - rot_want)) < 1e-12, reader
        for c, w in zip(cov, cov_want):
            assert np.max(np.abs(c - w)) <= 1e-9 * np.max(np.abs(w)), reader
            assert np.max(np.abs(c - c.T)) <= 1e-12 * np.max(np.abs(c)), reader
            assert np.min(np.linalg.eigvalsh(c)) >= -1e-12 * np.max(np.abs(c)), reader
    assert all(np.array_equal(a, b) for a, b in zip(*decoded.values()))

    require("evo_ape", shutil.which("evo_ape") is not None, "pip install evo==1.38.1")
    ours = json.loads(subprocess.run(
        [str(swarmpose_bin), "evaluate", str(out / "trajectory.kitti.txt"),
         str(out / "groundtruth.kitti.txt"), "--json"],
        check=True, capture_output=True, text=True).stdout)
    # evo_ape -a: after the SE(3) alignment of Umeyama, as ate_aligned (evo's start-up
    # is most of this test's time: one call).
    theirs = evo_ate(mcap, tmp_path)
    assert theirs == pytest.approx(ours["ate_aligned"]["rmse"], rel=1e-6, abs=1e-9)
    assert theirs > 0.0


IMAGE = "/swarmpose/image/compressed"
POINTS = "/swarmpose/points"


def png_size(data):
    """(width, height, colour type) from a PNG file's IHDR."""
    assert bytes(data[:8]) == b"\x89PNG\r\n\x1a\n"
    assert bytes(data[12:16]) == b"IHDR"
    return (int.from_bytes(bytes(data[16:20]), "big"), int.from_bytes(bytes(data[20:24]), "big"),
            data[25])


def test_mcap_images_every_nth_frame(kitti_seq2, swarmpose_bin, tmp_path):
    """--mcap-images 3: frames 0, 3, 6 and 9 carry the left image with the inliers drawn
    (PNG, the image's size) and the inliers' points (x, y, z float32, metres, in the
    camera frame: in front of it), as many as frames.csv's inliers, the same as decoded
    by both readers; and config.json records the setting."""
    require_readers()
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    folder = kitti_clip(kitti_seq2, tmp_path / "kitti", FRAMES)
    out = tmp_path / "out"
    subprocess.run([str(swarmpose_bin), "odometry", str(folder), "--out", str(out), "--quiet",
                    "--mcap-images", "3"], check=True, capture_output=True)
    assert json.loads((out / "config.json").read_text())["output"]["mcap_images"] == 3
    with open(out / "frames.csv", newline="") as f:
        inliers = [int(r["inliers"]) for r in csv.DictReader(f)]
    assert all(n >= 20 for n in inliers[1:]), inliers
    with open(out / "odometry.mcap", "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        msgs = {IMAGE: [], POINTS: []}
        for _, channel, message, decoded in reader.iter_decoded_messages(topics=list(msgs)):
            msgs[channel.topic].append((message.log_time, decoded))
    want_stamps = [k * 100_000_000 for k in range(0, FRAMES, 3)]
    for topic in (IMAGE, POINTS):
        assert [t for t, _ in msgs[topic]] == want_stamps, topic
    width, height, _ = png_size((folder / "image_0" / "000000.png").read_bytes())
    camera_frame = "camera_optical"
    for (t, img), (_, cloud) in zip(msgs[IMAGE], msgs[POINTS]):
        k = t // 100_000_000
        assert img.format == "png" and img.header.frame_id == camera_frame
        assert png_size(img.data) == (width, height, 2)  # RGB
        assert cloud.header.frame_id == camera_frame
        assert [(fl.name, fl.offset, fl.datatype, fl.count) for fl in cloud.fields] == \
            [("x", 0, 7, 1), ("y", 4, 7, 1), ("z", 8, 7, 1)]
        assert (cloud.height, cloud.width, cloud.point_step) == (1, inliers[k], 12)
        assert cloud.row_step == 12 * inliers[k] and not cloud.is_bigendian
        points = np.frombuffer(bytes(cloud.data), dtype="<f4").reshape(-1, 3)
        assert len(points) == inliers[k]
        if k > 0:
            assert np.all(points[:, 2] > 0.5) and np.all(np.isfinite(points))
    # rosbags decodes the same clouds.
    with AnyReader([out / "odometry.mcap"],
                   default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as r:
        conns = [c for c in r.connections if c.topic == POINTS]
        clouds = [r.deserialize(raw, c.msgtype) for c, _, raw in r.messages(conns)]
    assert [bytes(c.data) for c in clouds] == [bytes(c.data) for _, c in msgs[POINTS]]
