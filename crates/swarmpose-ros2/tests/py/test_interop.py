"""swarmpose-ros2 against Eclipse Cyclone DDS (a DDS nobody here wrote): KITTI stereo
published as ROS 2 sensor_msgs/Image + CameraInfo on the loopback interface, the node's
nav_msgs/Odometry read back and compared with the offline `swarmpose odometry` run."""

import signal
import time

import numpy as np
import pytest

from conftest import domain_id
from dds_peer import stamp_ns

BASE_NS = 1_700_000_000 * 10**9  # a wall-clock-like first stamp
PERIOD_NS = 100_000_000  # KITTI's 10 Hz


def position(o):
    p = o.pose.pose.position
    return np.array([p.x, p.y, p.z])


def status_values(statuses):
    """The values of the last tracking status that has them, as a dict."""
    for a in reversed(statuses):
        for s in a.status:
            v = {kv.key: kv.value for kv in s.values}
            if "frame" in v:
                return v
    return {}


def lockstep(peer, kitti, frames, timeout_s=60.0):
    """Publishes each pair and waits for its odometry before the next (no drop);
    republishes a pair whose images were lost (best effort)."""
    for k in frames:
        ns = BASE_NS + k * PERIOD_NS
        for _ in range(3):
            peer.infos(ns, kitti.p_left, kitti.p_right, kitti.width, kitti.height)
            peer.pair(ns, kitti.left[k], kitti.right[k])
            if peer.wait_odometry(ns, timeout_s / 3):
                break
        else:
            raise AssertionError(f"no odometry for frame {k} within {timeout_s} s")


def test_poses_and_covariances_equal_the_offline_run(node_factory, peer_factory, kitti, offline, tmp_path):
    domain = domain_id()
    node = node_factory(domain, tmp_path / "out")
    peer = peer_factory(domain)
    peer.wait_matched()
    lockstep(peer, kitti, range(len(kitti)))
    code, _ = node.stop(signal.SIGINT)
    assert code == 0, node.stderr
    got = {stamp_ns(m.header.stamp): m for _, m in peer.received}
    assert len(got) == len(kitti) == len(offline)
    worst = 0.0
    for k, ref in enumerate(offline):
        o = got[BASE_NS + k * PERIOD_NS]
        worst = max(worst, float(np.linalg.norm(position(o) - position(ref))))
        q, qr = o.pose.pose.orientation, ref.pose.pose.orientation
        assert abs(abs(q.x * qr.x + q.y * qr.y + q.z * qr.z + q.w * qr.w) - 1) < 1e-12, k
        np.testing.assert_allclose(o.pose.covariance, ref.pose.covariance, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(o.twist.covariance, ref.twist.covariance, rtol=1e-9, atol=1e-15)
        assert o.header.frame_id == "odom" and o.child_frame_id == "camera_optical"
    assert worst <= 1e-9, f"largest position difference {worst} m"
    values = status_values(peer.statuses)
    assert values["dropped"] == "0", values
    # --out kept what `swarmpose odometry` writes, a line per frame.
    lines = (tmp_path / "out" / "trajectory.kitti.txt").read_text().splitlines()
    assert len(lines) == len(kitti)
    assert "dropped" in node.stdout and "0 dropped" in node.stdout, node.stdout


def engine_period_s(peer):
    """The engine's mean time a frame, from the statuses (`engine_ms`)."""
    ms = [
        float(kv.value)
        for a in peer.statuses
        for s in a.status
        for kv in s.values
        if kv.key == "engine_ms"
    ]
    return float(np.mean(ms)) * 1e-3


def test_twice_the_engine_rate_drops_and_stays_on_the_path(node_factory, peer_factory, kitti, offline):
    domain = domain_id()
    node = node_factory(domain)
    peer = peer_factory(domain)
    peer.wait_matched()
    # The engine's own rate, measured on the first pairs.
    lockstep(peer, kitti, range(4))
    period_s = engine_period_s(peer) / 2
    t = time.perf_counter()
    for k in range(4, len(kitti)):
        ns = BASE_NS + k * PERIOD_NS
        peer.infos(ns, kitti.p_left, kitti.p_right, kitti.width, kitti.height)
        peer.pair(ns, kitti.left[k], kitti.right[k])
        t += period_s
        while time.perf_counter() < t:
            peer.poll()
            time.sleep(0.0005)
    last = BASE_NS + (len(kitti) - 1) * PERIOD_NS
    peer.wait_odometry(last, 10.0)
    time.sleep(0.5)
    peer.poll()
    code, _ = node.stop(signal.SIGINT)
    assert code == 0, node.stderr
    got = {stamp_ns(m.header.stamp): m for _, m in peer.received}
    dropped = int(status_values(peer.statuses)["dropped"])
    print(f"published {len(kitti)} pairs, {len(got)} poses, {dropped} dropped, "
          f"publishing period {period_s * 1e3:.1f} ms")
    assert dropped > 0
    assert len(got) + dropped <= len(kitti)
    ref = [position(o) for o in offline]
    path_m = float(sum(np.linalg.norm(b - a) for a, b in zip(ref, ref[1:])))
    worst = max(
        float(np.linalg.norm(position(o) - ref[(s - BASE_NS) // PERIOD_NS])) for s, o in got.items()
    )
    print(f"largest position difference {worst:.3f} m over a {path_m:.1f} m path")
    assert worst <= 0.01 * path_m


def test_sigterm_stops_within_a_frame_and_keeps_whole_lines(node_factory, peer_factory, kitti, tmp_path):
    domain = domain_id()
    out = tmp_path / "out"
    node = node_factory(domain, out)
    peer = peer_factory(domain)
    peer.wait_matched()
    lockstep(peer, kitti, range(3))
    frame_s = engine_period_s(peer)
    # Mid-stream: pairs keep coming at the engine's rate while SIGTERM arrives.
    for k in range(3, 8):
        ns = BASE_NS + k * PERIOD_NS
        peer.infos(ns, kitti.p_left, kitti.p_right, kitti.width, kitti.height)
        peer.pair(ns, kitti.left[k], kitti.right[k])
        time.sleep(frame_s)
    code, took_s = node.stop(signal.SIGTERM)
    print(f"exit {code} {took_s * 1e3:.0f} ms after SIGTERM; a frame takes {frame_s * 1e3:.0f} ms")
    assert code == 0, node.stderr
    assert "stopped by SIGTERM" in node.stdout, node.stdout
    # One frame in work, then the DDS participant leaves (its threads are joined).
    assert took_s <= frame_s + 1.0
    for name in ["trajectory.kitti.txt", "trajectory.tum.txt", "frames.csv", "motion_covariance.csv"]:
        text = (out / name).read_text()
        assert text.endswith("\n"), name
    n = len((out / "trajectory.kitti.txt").read_text().splitlines())
    assert n >= 3
    assert len((out / "frames.csv").read_text().splitlines()) == n + 1
    assert all(len(l.split()) == 12 for l in (out / "trajectory.kitti.txt").read_text().splitlines())
