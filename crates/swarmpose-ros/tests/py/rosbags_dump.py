"""Every message of a ROS 2 bag as an independent reader reads it, as JSON: the `rosbags`
package, Foxglove's `mcap` with `mcap-ros2-support` (MCAP only), or Python's own sqlite3
with rosbags' CDR decoder (SQLite only).

Usage: python rosbags_dump.py BAG OUT.json [rosbags|mcap|sqlite] [raw]

With `raw`, nothing is decoded (the bytes only).

OUT.json: {"topics": {TOPIC: {"type": TYPE, "messages": [[log_time_ns, data_hex, decoded]]}}}
where `decoded` is the message as nested lists and objects for the types swarmpose
models (null for others), or {"error": MESSAGE} when the reader cannot read the bag.
"""

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

MODELLED = set() if "raw" in sys.argv[4:] else {
    "std_msgs/msg/String",
    "rcl_interfaces/msg/Log",
    "tf2_msgs/msg/TFMessage",
    "nav_msgs/msg/Odometry",
    "nav_msgs/msg/Path",
    "geometry_msgs/msg/PoseWithCovarianceStamped",
    "sensor_msgs/msg/Image",
    "sensor_msgs/msg/CompressedImage",
    "sensor_msgs/msg/CameraInfo",
    "sensor_msgs/msg/PointCloud2",
    "diagnostic_msgs/msg/DiagnosticArray",
}


def is_field(name: str) -> bool:
    """True for a message field (ROS 2 field names are lower case; constants upper)."""
    return not name.startswith("_") and not name.isupper()


def plain(value):
    """A decoded message as plain JSON values."""
    if dataclasses.is_dataclass(value):
        return {
            f.name: plain(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if is_field(f.name)
        }
    if hasattr(value, "__slots__") and not isinstance(value, np.generic):
        return {k: plain(getattr(value, k)) for k in value.__slots__ if is_field(k)}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, (bytes, bytearray, memoryview)):
        return list(bytes(value))
    if isinstance(value, np.generic):
        return value.item()
    return value


def dump(bag: Path) -> dict:
    topics: dict = {}
    store = get_typestore(Stores.ROS2_HUMBLE)
    with AnyReader([bag], default_typestore=store) as reader:
        for conn in reader.connections:
            topics.setdefault(conn.topic, {"type": conn.msgtype, "messages": []})
        for conn, stamp, raw in reader.messages():
            decoded = None
            if conn.msgtype in MODELLED:
                decoded = plain(reader.deserialize(raw, conn.msgtype))
            topics[conn.topic]["messages"].append([stamp, bytes(raw).hex(), decoded])
    return {"topics": topics}


def dump_mcap(bag: Path) -> dict:
    """The same with Foxglove's reader and ROS 2 decoder, file after file of a folder."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    files = sorted(bag.glob("*.mcap")) if bag.is_dir() else [bag]
    if not files:
        raise ValueError("no MCAP file")
    topics: dict = {}
    factory = DecoderFactory()
    for path in files:
        with path.open("rb") as f:
            reader = make_reader(f, decoder_factories=[factory])
            for schema, channel, message in reader.iter_messages(log_time_order=False):
                name = schema.name if schema else ""
                entry = topics.setdefault(channel.topic, {"type": name, "messages": []})
                decoded = None
                if name in MODELLED:
                    decoder = factory.decoder_for(channel.message_encoding, schema)
                    decoded = plain(decoder(message.data))
                entry["messages"].append([message.log_time, message.data.hex(), decoded])
    return {"topics": topics}


def dump_sqlite(bag: Path) -> dict:
    """The same from the tables of the .db3 files, through Python's sqlite3."""
    import sqlite3

    files = sorted(bag.glob("*.db3")) if bag.is_dir() else [bag]
    if not files:
        raise ValueError("no .db3 file")
    topics: dict = {}
    store = get_typestore(Stores.ROS2_HUMBLE)
    for path in files:
        con = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
        names = {i: (n, t) for i, n, t in con.execute("SELECT id, name, type FROM topics")}
        for name, ty in names.values():
            topics.setdefault(name, {"type": ty, "messages": []})
        rows = con.execute("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id")
        for topic_id, stamp, data in rows:
            name, ty = names[topic_id]
            decoded = plain(store.deserialize_cdr(data, ty)) if ty in MODELLED else None
            topics[name]["messages"].append([stamp, bytes(data).hex(), decoded])
        con.close()
    return {"topics": topics}


def main() -> None:
    bag, out = Path(sys.argv[1]), Path(sys.argv[2])
    reader = sys.argv[3] if len(sys.argv) > 3 else "rosbags"
    try:
        readers = {"mcap": dump_mcap, "sqlite": dump_sqlite, "rosbags": dump}
        result = readers[reader](bag)
    except Exception as exc:  # rosbags cannot read it: say so, the test decides
        result = {"error": f"{type(exc).__name__}: {exc}"}
    out.write_text(json.dumps(result))


if __name__ == "__main__":
    main()
