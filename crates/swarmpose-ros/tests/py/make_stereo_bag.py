"""Writes a rectified stereo ROS 2 bag with the independent `rosbags` writer.

Usage: python make_stereo_bag.py FRAMES_DIR OUT STORAGE [OPTION...]

FRAMES_DIR holds meta.json ({"width", "height", "p_left": [12], "p_right": [12],
"stamps_ns": [...]}) and, per frame k, left_K.raw and right_K.raw (8-bit gray, row-major)
or left_K.png and right_K.png with the `png` option. STORAGE: mcap (plain), mcap-zstd
(zstd chunks), mcap-lz4 (the plain bag rewritten by Foxglove's `mcap` writer with LZ4
chunks: rosbags writes no LZ4) or sqlite3. OUT is the bag folder to create (metadata.yaml and one file).

Options: png (CompressedImage PNG instead of Image mono8), no-info (no camera_info
topics), right-stamp-offset=NS (shift the right images' stamps), rgb8 (the gray pixels
as rgb8 images), drop=SIDE:K (leave out frame K's SIDE image, left or right; repeatable).

Topics: /stereo/left/image_rect, /stereo/right/image_rect (or .../compressed), and
/stereo/left/camera_info, /stereo/right/camera_info (plumb_bob, D = 0, R = I, K and P
from the projections).

Raw images: with "raw": {"left": {"k": [9], "d": [5], "r": [9]}, "right": {...}} in
meta.json, the pixels are the raw (distorted, unrectified) images, the topics are
/stereo/SIDE/image_raw, and each camera_info has that K, D (plumb_bob) and R (row-major),
with P from "p_SIDE".
"""

import json
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
from rosbags.typesys import Stores, get_typestore

STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types
Time = T["builtin_interfaces/msg/Time"]
Header = T["std_msgs/msg/Header"]
Image = T["sensor_msgs/msg/Image"]
CompressedImage = T["sensor_msgs/msg/CompressedImage"]
CameraInfo = T["sensor_msgs/msg/CameraInfo"]
Roi = T["sensor_msgs/msg/RegionOfInterest"]


def header(ns: int, frame: str):
    return Header(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=frame)


def info(ns, frame, meta, side):
    p = meta["p_" + side]
    raw = meta.get("raw", {}).get(side)
    if raw:
        k, d, r = raw["k"], raw["d"], raw["r"]
    else:
        k = [p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]]
        d, r = [0.0] * 5, np.eye(3).reshape(9)
    return CameraInfo(
        header=header(ns, frame),
        height=meta["height"],
        width=meta["width"],
        distortion_model="plumb_bob",
        d=np.array(d, dtype=np.float64),
        k=np.array(k, dtype=np.float64),
        r=np.array(r, dtype=np.float64),
        p=np.array(p, dtype=np.float64),
        binning_x=0,
        binning_y=0,
        roi=Roi(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False),
    )


def image(ns, frame, meta, pixels: bytes, rgb: bool):
    w, h = meta["width"], meta["height"]
    data = np.frombuffer(pixels, dtype=np.uint8)
    if rgb:
        data = np.repeat(data, 3)
    return Image(
        header=header(ns, frame),
        height=h,
        width=w,
        encoding="rgb8" if rgb else "mono8",
        is_bigendian=0,
        step=w * 3 if rgb else w,
        data=data,
    )


def main() -> None:
    frames, out, storage = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3]
    opts = sys.argv[4:]
    png = "png" in opts
    rgb = "rgb8" in opts
    shift = next((int(o.split("=")[1]) for o in opts if o.startswith("right-stamp-offset=")), 0)
    dropped = {tuple(o.split("=")[1].split(":")) for o in opts if o.startswith("drop=")}
    meta = json.loads((frames / "meta.json").read_text())
    plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
    writer = Writer(out, version=8, storage_plugin=plugin)
    if storage == "mcap-zstd":
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    with writer:
        conns = {}
        for side in ("left", "right"):
            ty = CompressedImage if png else Image
            kind = "image_raw" if "raw" in meta else "image_rect"
            name = f"/stereo/{side}/{kind}" + ("/compressed" if png else "")
            conns[side] = writer.add_connection(name, ty.__msgtype__, typestore=STORE)
            if "no-info" not in opts:
                conns[side + "_info"] = writer.add_connection(
                    f"/stereo/{side}/camera_info", CameraInfo.__msgtype__, typestore=STORE
                )
        for k, ns in enumerate(meta["stamps_ns"]):
            for side in ("left", "right"):
                if (side, str(k)) in dropped:
                    continue
                stamp = ns + (shift if side == "right" else 0)
                frame = f"camera_{side}_optical"
                if png:
                    data = np.frombuffer((frames / f"{side}_{k}.png").read_bytes(), dtype=np.uint8)
                    msg = CompressedImage(header=header(stamp, frame), format="png", data=data)
                else:
                    pixels = (frames / f"{side}_{k}.raw").read_bytes()
                    msg = image(stamp, frame, meta, pixels, rgb)
                writer.write(conns[side], stamp, STORE.serialize_cdr(msg, msg.__msgtype__))
                if "no-info" not in opts:
                    ci = info(stamp, frame, meta, side)
                    writer.write(conns[side + "_info"], stamp, STORE.serialize_cdr(ci, ci.__msgtype__))


def rewrite_lz4(bag: Path) -> None:
    """Rewrites the bag folder's MCAP file with LZ4-compressed chunks (Foxglove's writer)."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType
    from mcap.writer import Writer as McapWriter

    path = next(bag.glob("*.mcap"))
    plain = path.with_suffix(".plain")
    path.rename(plain)
    with plain.open("rb") as src, path.open("wb") as dst:
        out = McapWriter(dst, compression=CompressionType.LZ4)
        out.start(profile="ros2", library="make_stereo_bag.py")
        schemas, channels = {}, {}
        for schema, channel, msg in make_reader(src).iter_messages(log_time_order=False):
            if schema.id not in schemas:
                schemas[schema.id] = out.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = out.register_channel(
                    channel.topic, channel.message_encoding, schemas[schema.id], channel.metadata
                )
            out.add_message(channels[channel.id], msg.log_time, msg.data, msg.publish_time,
                            msg.sequence)
        out.finish()
    plain.unlink()


if __name__ == "__main__":
    main()
    if sys.argv[3] == "mcap-lz4":
        rewrite_lz4(Path(sys.argv[2]))
