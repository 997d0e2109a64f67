"""A ROS 2 peer that nobody here wrote: Eclipse Cyclone DDS (the `cyclonedds` package),
publishing stereo images and camera_info as a ROS 2 camera driver does and reading what
swarmpose-ros2 publishes. Loopback only (CYCLONEDDS_URI below; the node gets
ROS_LOCALHOST_ONLY=1)."""

import os
import time
from pathlib import Path

import numpy as np

# Cyclone DDS reads its configuration when a domain is first joined: loopback only, no
# multicast, peers found by unicast on 127.0.0.1.
LOOPBACK_XML = (
    "<CycloneDDS><Domain Id='any'><General><Interfaces>"
    "<NetworkInterface address='127.0.0.1'/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
    "<MaxAutoParticipantIndex>40</MaxAutoParticipantIndex>"
    "<Peers><Peer address='127.0.0.1'/></Peers></Discovery></Domain></CycloneDDS>"
)
os.environ["CYCLONEDDS_URI"] = LOOPBACK_XML

from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402

import ros2_types as R  # noqa: E402

XCDR1 = Policy.DataRepresentation(use_cdrv0_representation=True)
# rclcpp's sensor data profile (best effort, keep last 5) and its default (reliable, 10).
SENSOR = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(5), XCDR1)
RELIABLE = Qos(
    Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(1000), XCDR1
)

LEFT, RIGHT = "/stereo/left/image_rect", "/stereo/right/image_rect"
LEFT_INFO, RIGHT_INFO = "/stereo/left/camera_info", "/stereo/right/camera_info"
ODOMETRY, STATUS, PATH = "/swarmpose/odometry", "/swarmpose/status", "/swarmpose/path"


def stamp(ns: int) -> R.Time:
    return R.Time(sec=ns // 10**9, nanosec=ns % 10**9)


def stamp_ns(t: R.Time) -> int:
    return t.sec * 10**9 + t.nanosec


class Kitti:
    """The rectified gray stereo pairs and projections of a KITTI odometry folder."""

    def __init__(self, folder: Path):
        from PIL import Image as PilImage

        rows = {}
        for line in (folder / "calib.txt").read_text().splitlines():
            if ":" in line:
                key, nums = line.split(":", 1)
                rows[key.strip()] = [float(x) for x in nums.split()]
        self.p_left, self.p_right = rows["P0"], rows["P1"]
        names = sorted(p.name for p in (folder / "image_0").glob("*.png"))
        self.left = [np.asarray(PilImage.open(folder / "image_0" / n)) for n in names]
        self.right = [np.asarray(PilImage.open(folder / "image_1" / n)) for n in names]
        self.height, self.width = self.left[0].shape

    def __len__(self):
        return len(self.left)


def camera_info(ns: int, p, width: int, height: int, frame="camera_optical") -> R.CameraInfo:
    k = [p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]]
    return R.CameraInfo(
        header=R.Header(stamp=stamp(ns), frame_id=frame),
        height=height,
        width=width,
        distortion_model="plumb_bob",
        d=[0.0] * 5,
        k=k,
        r=[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
        p=list(p),
        binning_x=0,
        binning_y=0,
        roi=R.RegionOfInterest(0, 0, 0, 0, False),
    )


def image(ns: int, pixels: np.ndarray, encoding="mono8", frame="camera_optical") -> R.Image:
    h, w = pixels.shape[:2]
    channels = 1 if pixels.ndim == 2 else pixels.shape[2]
    return R.Image(
        header=R.Header(stamp=stamp(ns), frame_id=frame),
        height=h,
        width=w,
        encoding=encoding,
        is_bigendian=0,
        step=w * channels * pixels.itemsize,
        data=np.ascontiguousarray(pixels).tobytes(),
    )


class Peer:
    """A Cyclone DDS participant in `domain`: the camera's writers and the readers of the
    node's outputs."""

    def __init__(self, domain: int):
        self.dp = DomainParticipant(domain)

        def writer(topic, cls):
            return DataWriter(self.dp, Topic(self.dp, R.dds_topic(topic), cls), qos=SENSOR)

        def reader(topic, cls):
            return DataReader(self.dp, Topic(self.dp, R.dds_topic(topic), cls), qos=RELIABLE)

        self.left = writer(LEFT, R.Image)
        self.right = writer(RIGHT, R.Image)
        self.left_info = writer(LEFT_INFO, R.CameraInfo)
        self.right_info = writer(RIGHT_INFO, R.CameraInfo)
        self.odometry = reader(ODOMETRY, R.Odometry)
        self.status = reader(STATUS, R.DiagnosticArray)
        self.path = reader(PATH, R.Path)
        self.received = []  # (receive time, Odometry)
        self.statuses = []  # DiagnosticArray
        self.paths = []

    def wait_matched(self, timeout_s=30.0):
        """Waits until the node's readers and writers are discovered."""
        end = time.monotonic() + timeout_s
        ends = [self.left, self.right, self.left_info, self.right_info]
        while time.monotonic() < end:
            if all(len(w.get_matched_subscriptions()) > 0 for w in ends) and all(
                len(r.get_matched_publications()) > 0 for r in [self.odometry, self.status]
            ):
                return
            time.sleep(0.05)
        raise AssertionError(f"the node was not discovered within {timeout_s} s")

    def infos(self, ns, p_left, p_right, width, height):
        self.left_info.write(camera_info(ns, p_left, width, height))
        self.right_info.write(camera_info(ns, p_right, width, height))

    def pair(self, ns, left: np.ndarray, right: np.ndarray, encoding="mono8"):
        """Publishes a pair; returns the time it was published (time.perf_counter())."""
        li, ri = image(ns, left, encoding), image(ns, right, encoding)
        t = time.perf_counter()
        self.left.write(li)
        self.right.write(ri)
        return t

    def poll(self):
        """Takes what the node published."""
        now = time.perf_counter()
        # Cyclone hands "invalid samples" (a writer gone) among the data: skipped.
        for m in self.odometry.take(N=100):
            if hasattr(m, "header"):
                self.received.append((now, m))
        self.statuses.extend(m for m in self.status.take(N=100) if hasattr(m, "status"))
        self.paths.extend(m for m in self.path.take(N=10) if hasattr(m, "poses"))

    def wait_odometry(self, ns: int, timeout_s: float) -> bool:
        """Waits for the odometry stamped `ns`."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            self.poll()
            if any(stamp_ns(m.header.stamp) == ns for _, m in self.received):
                return True
            time.sleep(0.0005)
        return False

    def wait_status(self, contains: str, timeout_s: float):
        """Waits for a status whose message contains `contains`; returns it."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            self.poll()
            for a in self.statuses:
                for s in a.status:
                    if contains in s.message:
                        return s
            time.sleep(0.01)
        seen = sorted({s.message for a in self.statuses for s in a.status})
        raise AssertionError(f"no status with '{contains}' within {timeout_s} s; seen: {seen}")

    def close(self):
        # Drop the entities (Cyclone deletes them with the participant).
        self.dp = None
