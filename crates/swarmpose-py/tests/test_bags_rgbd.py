"""swarmpose.Sequence and swarmpose.odometry on RGB-D input: a textured wall with a
relief of whole millimetres, seen by a camera moving sideways, written at test time as
a TUM RGB-D folder (PNG) and as ROS 2 bags by the independent `rosbags` writer (colour
mono8 and depth registered to it, with camera_info; depth in 16UC1 millimetres and in
32FC1 metres). Every input gives the same frames (gray uint8, depth float32 metres) and
the same trajectory, bit for bit, in Python and from `swarmpose odometry` on the same
bag; a bag's topics can be named; what is not RGB-D input raises the command line's
one line."""

import struct
import subprocess
import zlib
from pathlib import Path

import numpy as np
import pytest

import swarmpose
from bags import require_rosbags

W, H, FX, CX, CY = 320, 240, 262.5, 159.5, 119.5
FRAMES = 6
SHIFT_PX = 6  # the view slides by this much a frame
T0_NS = 1_305_031_102_000_000_000
PERIOD_NS = 33_333_333
COLOUR = "/camera/color/image_raw"
DEPTH = "/camera/aligned_depth_to_color/image_raw"


def wall():
    """The wall's texture (uint8 blobs) and depth (whole millimetres: 2 m and a relief
    of up to 8 mm), wide enough for the camera's slide."""
    rng = np.random.default_rng(11)
    width = W + SHIFT_PX * FRAMES
    coarse = rng.uniform(0, 255, size=(H // 4 + 1, width // 4 + 1))
    texture = np.kron(coarse, np.ones((4, 4)))[:H, :width].astype(np.uint8)
    relief = (np.arange(width) // 16 % 5) * 2
    depth_mm = np.broadcast_to(2000 + relief, (H, width)).astype(np.uint16)
    return texture, depth_mm


def frames():
    """Each frame's (gray uint8, depth uint16 millimetres), (H, W)."""
    texture, depth_mm = wall()
    return [(np.ascontiguousarray(texture[:, k * SHIFT_PX:k * SHIFT_PX + W]),
             np.ascontiguousarray(depth_mm[:, k * SHIFT_PX:k * SHIFT_PX + W]))
            for k in range(FRAMES)]


def metres(mm):
    """Millimetres as the readers give metres: the nearest float32 to mm / 1000."""
    return (mm.astype(np.float64) / 1000.0).astype(np.float32)


def png(path: Path, pixels) -> None:
    """A grayscale PNG of uint8 or uint16 (big-endian) pixels, written by hand (zlib)."""
    depth = 16 if pixels.dtype == np.uint16 else 8
    rows = pixels.astype(">u2" if depth == 16 else "u1")
    raw = b"".join(b"\x00" + row.tobytes() for row in rows)

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    ihdr = struct.pack(">IIBBBBB", pixels.shape[1], pixels.shape[0], depth, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
                     + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def seconds(k: int) -> float:
    """Frame k's time as a bag's reader gives it: seconds since the first header stamp."""
    return float(k * PERIOD_NS) * 1e-9


def tum_folder(out: Path) -> Path:
    """The TUM RGB-D folder of the frames (depth: 5000 units per metre)."""
    for sub in ("rgb", "depth"):
        (out / sub).mkdir(parents=True)
    rgb, depth = [], []
    for k, (gray, mm) in enumerate(frames()):
        png(out / "rgb" / f"{k}.png", gray)
        png(out / "depth" / f"{k}.png", (mm * 5).astype(np.uint16))
        rgb.append(f"{seconds(k)!r} rgb/{k}.png\n")
        depth.append(f"{seconds(k)!r} depth/{k}.png\n")
    (out / "rgb.txt").write_text("".join(rgb))
    (out / "depth.txt").write_text("".join(depth))
    (out / "intrinsics.txt").write_text(f"{FX} {FX} {CX} {CY}\n")
    return out


def rgbd_bag(out: Path, encoding: str) -> Path:
    """The frames as an MCAP RGB-D bag (a rosbag2 folder) written by `rosbags`: colour
    mono8 and depth in `encoding`, each with its camera_info; returns the MCAP file."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    t = store.types
    time, header_t = t["builtin_interfaces/msg/Time"], t["std_msgs/msg/Header"]
    image_t, info_t = t["sensor_msgs/msg/Image"], t["sensor_msgs/msg/CameraInfo"]
    roi = t["sensor_msgs/msg/RegionOfInterest"]

    def header(ns):
        return header_t(stamp=time(sec=ns // 10**9, nanosec=ns % 10**9),
                        frame_id="camera_color_optical_frame")

    def info(ns):
        k = [FX, 0.0, CX, 0.0, FX, CY, 0.0, 0.0, 1.0]
        p = [FX, 0.0, CX, 0.0, 0.0, FX, CY, 0.0, 0.0, 0.0, 1.0, 0.0]
        return info_t(header=header(ns), height=H, width=W, distortion_model="plumb_bob",
                      d=np.zeros(5), k=np.array(k), r=np.eye(3).reshape(9), p=np.array(p),
                      binning_x=0, binning_y=0,
                      roi=roi(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False))

    def image(ns, enc, pixels):
        little = pixels.astype(pixels.dtype.newbyteorder("<"))
        data = np.frombuffer(little.tobytes(), dtype=np.uint8)
        return image_t(header=header(ns), height=H, width=W, encoding=enc, is_bigendian=0,
                       step=W * pixels.dtype.itemsize, data=data)

    writer = Writer(out, version=8, storage_plugin=StoragePlugin.MCAP)
    with writer:
        conns = {}
        for name, ty in ((COLOUR, image_t), (DEPTH, image_t)):
            ns = name.rsplit("/", 1)[0]
            conns[name] = writer.add_connection(name, ty.__msgtype__, typestore=store)
            conns[ns] = writer.add_connection(f"{ns}/camera_info", info_t.__msgtype__,
                                              typestore=store)
        for k, (gray, mm) in enumerate(frames()):
            ns = T0_NS + k * PERIOD_NS
            depth = mm if encoding == "16UC1" else metres(mm)
            for name, msg in ((COLOUR, image(ns, "mono8", gray)),
                              (DEPTH, image(ns, encoding, depth))):
                writer.write(conns[name], ns, store.serialize_cdr(msg, msg.__msgtype__))
                ci = info(ns)
                writer.write(conns[name.rsplit("/", 1)[0]], ns,
                             store.serialize_cdr(ci, ci.__msgtype__))
    return next(out.glob("*.mcap"))


@pytest.fixture
def rgbd_inputs(tmp_path):
    """{name: path}: the TUM folder, and the bags with 16UC1 and 32FC1 depth."""
    require_rosbags()
    inputs = {"folder": tum_folder(tmp_path / "tum")}
    for encoding in ("16UC1", "32FC1"):
        inputs[encoding] = rgbd_bag(tmp_path / f"bag_{encoding}", encoding)
    return inputs


def test_rgbd_frames_are_gray_and_metres(rgbd_inputs):
    want = frames()
    for name, path in rgbd_inputs.items():
        seq = swarmpose.Sequence(path)
        assert seq.rgbd and len(seq) == FRAMES, name
        assert seq.layout == ("tum rgb-d" if name == "folder" else "ros2 bag, rgb-d")
        assert seq.camera == {"fx": FX, "fy": FX, "cx": CX, "cy": CY, "baseline": None,
                              "width": W, "height": H}, name
        for k in (0, FRAMES - 1):
            gray, depth = seq[k]
            assert (gray.dtype, gray.shape) == (np.uint8, (H, W)), name
            assert (depth.dtype, depth.shape) == (np.float32, (H, W)), name
            assert np.array_equal(gray, want[k][0]), (name, k)
            assert np.array_equal(depth, metres(want[k][1])), (name, k)
        if name == "folder":
            assert seq.topics is None and seq.stamps_ns is None
        else:
            assert seq.topics == (COLOUR, DEPTH)
            assert seq.stamps_ns == [T0_NS + k * PERIOD_NS for k in range(FRAMES)]
            assert seq.unpaired == []


def kitti_poses(text: str):
    """The (N, 4, 4) poses of a KITTI trajectory file's text."""
    rows = np.array([[float(x) for x in line.split()] for line in text.splitlines()])
    poses = np.tile(np.eye(4), (len(rows), 1, 1))
    poses[:, :3, :] = rows.reshape(-1, 3, 4)
    return poses


def test_rgbd_bags_run_as_their_folder_and_the_command_line(rgbd_inputs, swarmpose_bin,
                                                             tmp_path):
    want = swarmpose.odometry(rgbd_inputs["folder"])
    assert len(want) == FRAMES
    assert all(s == "tracked" for s in want.statuses[1:]), want.statuses
    moved = want.poses[-1][0, 3]
    assert moved == pytest.approx((FRAMES - 1) * SHIFT_PX * 2.0 / FX, rel=0.05)
    for encoding in ("16UC1", "32FC1"):
        bag = rgbd_inputs[encoding]
        run = swarmpose.odometry(bag)
        assert np.array_equal(run.poses, want.poses), encoding
        assert run.statuses == want.statuses, encoding
        assert np.array_equal(run.timestamps, want.timestamps), encoding
        named = swarmpose.odometry(bag, left=COLOUR, depth=DEPTH)
        assert np.array_equal(named.poses, want.poses), encoding
        out = tmp_path / f"cli_{encoding}"
        cli = subprocess.run([str(swarmpose_bin), "odometry", str(bag), "--out", str(out),
                              "--quiet"], capture_output=True, text=True)
        assert cli.returncode == 0, cli.stderr
        cli_poses = kitti_poses((out / "trajectory.kitti.txt").read_text())
        assert np.array_equal(cli_poses, want.poses), encoding


def test_what_is_not_rgbd_input_raises_the_command_line_line(rgbd_inputs, swarmpose_bin,
                                                             tmp_path):
    bag = rgbd_inputs["16UC1"]
    for call in (lambda: swarmpose.Sequence(bag, depth=COLOUR),
                 lambda: swarmpose.odometry(bag, depth=COLOUR)):
        with pytest.raises(ValueError) as e:
            call()
        message = str(e.value)
        assert "\n" not in message
        assert COLOUR in message, message
    cli = subprocess.run([str(swarmpose_bin), "odometry", str(bag), "--depth", COLOUR,
                          "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert cli.returncode == 2
    assert cli.stderr.strip() == f"swarmpose: error: {message}"
    with pytest.raises(ValueError, match="topics are named for a ROS 2 bag"):
        swarmpose.Sequence(rgbd_inputs["folder"], depth=DEPTH)
