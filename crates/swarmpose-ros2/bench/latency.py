"""Latency of swarmpose-ros2, from a stereo pair published to its nav_msgs/Odometry
received, over Cyclone DDS on the loopback interface (not a timed test: a benchmark).

Usage: python latency.py [--pairs N] [--out RESULTS.md] [--no-sweep]

Runs the node (target/release/swarmpose-ros2, built by `cargo build --release -p
swarmpose-ros2`) with 1 and 2 threads, publishing KITTI's 1241x376 mono8 pairs
(SWARMPOSE_DATA/kitti_vo_seq2, back and forth so that the motion stays continuous) at
10 Hz and at the engine's full rate (the next pair as soon as the previous pair's
odometry is received). Per pair: the latency (publish -> Odometry received), the time in
the node (pair complete -> published, the status's `in_node_ms`), the engine's time
(`engine_ms`) and so the transport's share (latency - time in the node: Python's
serialisation, Cyclone DDS, RustDDS receiving and decoding the two images, and the
Odometry's way back).

Then the transport alone: the example `echo` (`cargo build --release -p swarmpose-ros2
--example echo`) takes each image through the node's RustDDS setup and sends its header
back; one image (466 kB) and back is timed at 10 Hz, with RustDDS's socket buffers at
their default (8 MiB) and at 1 MiB and 32 MiB (`SOCKET_BUFFER_BYTES`).

Last (unless --no-sweep), `transport.py`'s sweep: the round trip against the image's size
for RustDDS and Cyclone DDS echo peers. Rewrites the sections after `<!-- latency -->`
and `<!-- transport -->` in RESULTS.md."""

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests" / "py"))

from dds_peer import Kitti, Peer, stamp_ns  # noqa: E402
import transport  # noqa: E402

REPO = HERE.parents[2]
BASE_NS = 1_700_000_000 * 10**9


def order(n: int, count: int):
    """0, 1, ..., n-1, n-2, ..., 0, 1, ...: `count` frame indices back and forth."""
    cycle = list(range(n)) + list(range(n - 2, 0, -1))
    return [cycle[i % len(cycle)] for i in range(count)]


def status_values(peer):
    out = {}
    for a in peer.statuses:
        for s in a.status:
            v = {kv.key: kv.value for kv in s.values}
            if "frame" in v:
                out[s_stamp(a)] = v
    return out


def s_stamp(a):
    return stamp_ns(a.header.stamp)


def run(binary, kitti, threads, hz, pairs, domain):
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_LOCALHOST_ONLY="1")
    node = subprocess.Popen([str(binary), "--threads", str(threads)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        peer = Peer(domain)
        peer.wait_matched()
        sent, written = {}, {}
        idx = order(len(kitti), pairs + 5)
        next_t = time.perf_counter()
        for i, k in enumerate(idx):
            ns = BASE_NS + i * 100_000_000
            peer.infos(ns, kitti.p_left, kitti.p_right, kitti.width, kitti.height)
            sent[ns] = peer.pair(ns, kitti.left[k], kitti.right[k])
            written[ns] = time.perf_counter()
            if hz is None:
                peer.wait_odometry(ns, 10.0)
            else:
                next_t += 1.0 / hz
                while time.perf_counter() < next_t:
                    peer.poll()
                    time.sleep(0.0002)
        time.sleep(1.0)
        peer.poll()
    finally:
        node.send_signal(signal.SIGINT)
        out, err = node.communicate(timeout=30)
    values = status_values(peer)
    rows = []
    for t_recv, o in peer.received:
        ns = stamp_ns(o.header.stamp)
        if ns not in sent or ns == BASE_NS + 0 or ns not in values:
            continue
        lat = (t_recv - sent[ns]) * 1e3
        in_node = float(values[ns]["in_node_ms"])
        rows.append((lat, in_node, float(values[ns]["engine_ms"]), (written[ns] - sent[ns]) * 1e3))
    rows = np.array(rows[2:])  # the first pairs warm up
    dropped = max((int(v["dropped"]) for v in values.values()), default=0)
    return rows, dropped, len(sent), err


def echo(binary, kitti, domain, pairs, buffer_bytes=None):
    """Round trips of one image to the echo example and its header back, ms."""
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    import dds_peer as D
    import ros2_types as R

    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_LOCALHOST_ONLY="1")
    if buffer_bytes:
        env["SOCKET_BUFFER_BYTES"] = str(buffer_bytes)
    proc = subprocess.Popen([str(binary)], env=env, stderr=subprocess.PIPE, text=True)
    try:
        peer = Peer(domain)
        w = DataWriter(peer.dp, Topic(peer.dp, "rt/probe/image", R.Image), qos=D.SENSOR)
        r = DataReader(peer.dp, Topic(peer.dp, "rt/probe/echo", R.Header), qos=D.RELIABLE)
        end = time.monotonic() + 30
        while not (w.get_matched_subscriptions() and r.get_matched_publications()):
            if time.monotonic() > end:
                raise RuntimeError("echo not discovered")
            time.sleep(0.05)
        rtt = []
        for i in range(pairs + 5):
            ns = BASE_NS + i
            msg = D.image(ns, kitti.left[i % len(kitti)])
            t = time.perf_counter()
            w.write(msg)
            got = None
            while got is None and time.perf_counter() - t < 2.0:
                for h in r.take(N=10):
                    if hasattr(h, "stamp") and stamp_ns(h.stamp) == ns:
                        got = time.perf_counter()
                time.sleep(0.0002)
            if got is not None and i >= 5:
                rtt.append((got - t) * 1e3)
            time.sleep(max(0.0, 0.1 - (time.perf_counter() - t)))
        return np.array(rtt)
    finally:
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=30)


def pct(x, q):
    return float(np.percentile(x, q))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pairs", type=int, default=100)
    ap.add_argument("--out", type=Path, default=HERE.parent / "RESULTS.md")
    ap.add_argument("--profile", default="release", help="cargo profile folder of the binaries")
    ap.add_argument("--no-sweep", action="store_true", help="without transport.py's size sweep")
    args = ap.parse_args()
    data = Path(os.environ.get("SWARMPOSE_DATA", REPO.parent / "shared" / "data"))
    kitti = Kitti(data / "kitti_vo_seq2")
    binary = REPO / "target" / args.profile / "swarmpose-ros2"
    lines = []
    for threads in (1, 2):
        for hz in (10.0, None):
            rows, dropped, n, err = run(binary, kitti, threads, hz, args.pairs, 150 + threads * 2 + (hz is None))
            lat, node_ms, eng, write = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3]
            trans = lat - node_ms
            rate = "10 Hz" if hz else "full rate"
            lines.append(
                f"| {threads} | {rate} | {len(rows)} | {dropped} | {pct(lat, 50):.1f} | {pct(lat, 99):.1f} "
                f"| {pct(eng, 50):.1f} | {pct(node_ms, 50):.1f} | {pct(trans, 50):.1f} | {pct(trans, 99):.1f} "
                f"| {pct(write, 50):.1f} |"
            )
            print(lines[-1], flush=True)
    echo_bin = REPO / "target" / args.profile / "examples" / "echo"
    echo_lines = []
    for i, buf in enumerate([None, 1 << 20, 32 << 20]):
        rtt = echo(echo_bin, kitti, 170 + i, args.pairs, buf)
        name = "8 MiB (default)" if buf is None else f"{buf >> 20} MiB"
        echo_lines.append(f"| {name} | {len(rtt)} | {pct(rtt, 50):.2f} | {pct(rtt, 99):.2f} | {rtt.max():.2f} |")
        print(echo_lines[-1], flush=True)
    header = [
        "| threads | publishing | pairs timed | dropped | latency p50 ms | latency p99 ms | engine p50 ms "
        "| in node p50 ms | transport p50 ms | transport p99 ms | of which Python's writes p50 ms |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    echo_header = [
        "",
        "One 1241x376 mono8 image (466 kB) from Cyclone DDS to RustDDS and its header back, at 10 Hz:",
        "",
        "| RustDDS socket buffers | images | round trip p50 ms | p99 ms | max ms |",
        "|---|---|---|---|---|",
    ]
    note = [f"Binaries of the `{args.profile}` profile; {args.pairs} pairs a row; {transport.busy_note()}.", ""]
    text = "\n".join(note + header + lines + echo_header + echo_lines) + "\n"
    transport.write_section(args.out, "<!-- latency -->", text)
    if not args.no_sweep:
        transport.write_section(args.out, transport.MARKER, transport.sweep(args.pairs, args.profile))
    print(f"written to {args.out}")


if __name__ == "__main__":
    main()
