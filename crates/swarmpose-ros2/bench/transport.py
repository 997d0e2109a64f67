"""Where the transport's time goes: the round trip of one sensor_msgs/Image from Eclipse
Cyclone DDS (Python) to an echo peer and its std_msgs/Header back, on the loopback
interface, against the image's size (not a timed test: a benchmark).

Usage: python transport.py [--images N] [--out RESULTS.md]

Echo peers (each in a process of its own, in a DDS domain of its own):
- `echo` example, RustDDS with the node's participant setup and its mio 1 wait (the node's);
- the same with RustDDS's mio 0.6 wait (`ECHO_EVENTS=mio06`, the node's before), whose
  readiness RustDDS 0.15.1 never re-arms: each wait ends on its 20 ms timeout;
- the same with the images reliable on both sides instead of best effort;
- Cyclone DDS (Python, this script with `--serve`) as the peer figure: what a DDS does
  here at all, with the same QoS and the same client;
- Cyclone DDS peer and client with 60 kB fragments in 64 kB datagrams instead of
  Cyclone's defaults (1344 B fragments, 14 720 B datagrams), to see whether the
  sender's fragmenting is what costs.

The client (this script with `--client`, a process of its own so that each gets its own
Cyclone configuration) writes an image every 100 ms (payload sizes 1 kB to 466 kB, the
largest a 1241x376 mono8 KITTI frame; seeded random pixels) and polls for its header.
It rewrites the table after `<!-- transport -->` in `crates/swarmpose-ros2/RESULTS.md`."""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests" / "py"))

import dds_peer as D  # noqa: E402  (sets CYCLONEDDS_URI: loopback only)

REPO = HERE.parents[2]
BASE_NS = 1_700_000_000 * 10**9
# (width, height) of the mono8 images: 1 kB, 10 kB, 60 kB, 200 kB and a KITTI frame.
SHAPES = [(32, 32), (100, 100), (250, 240), (500, 400), (1241, 376)]
LARGE_FRAGMENTS = (
    "<General><FragmentSize>61440B</FragmentSize><MaxMessageSize>65000B</MaxMessageSize></General>"
)
MARKER = "<!-- transport -->"
# The 1-minute load average before the benchmark started (its own processes load the
# machine while it runs).
LOAD_BEFORE = os.getloadavg()[0]


def cyclone_uri(large_fragments: bool) -> str:
    """dds_peer's loopback configuration, with 60 kB fragments when asked."""
    if not large_fragments:
        return D.LOOPBACK_XML
    return D.LOOPBACK_XML.replace("<General>", LARGE_FRAGMENTS.replace("</General>", ""), 1)


def qos(reliable: bool):
    from cyclonedds.core import Policy, Qos
    from cyclonedds.util import duration

    if not reliable:
        return D.SENSOR
    return Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(5), D.XCDR1)


def topics(dp, reliable: bool):
    from cyclonedds.topic import Topic

    import ros2_types as R

    return Topic(dp, "rt/probe/image", R.Image), Topic(dp, "rt/probe/echo", R.Header), qos(reliable)


def serve(domain: int, reliable: bool):
    """The Cyclone DDS echo peer: each image's header back, until 10 s without one."""
    from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.util import duration

    dp = DomainParticipant(domain)
    image_topic, echo_topic, image_qos = topics(dp, reliable)
    reader = DataReader(dp, image_topic, qos=image_qos)
    writer = DataWriter(dp, echo_topic, qos=D.RELIABLE)
    waitset = WaitSet(dp)
    waitset.attach(ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Any))
    idle = time.monotonic()
    while time.monotonic() - idle < 10.0:
        waitset.wait(duration(milliseconds=20))
        for m in reader.take(N=10):
            if hasattr(m, "header"):
                writer.write(m.header)
                idle = time.monotonic()


def client(domain: int, reliable: bool, images: int) -> dict:
    """Round trips (ms) of `images` images of each size, after 5 of warm-up each."""
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader

    dp = DomainParticipant(domain)
    image_topic, echo_topic, image_qos = topics(dp, reliable)
    writer = DataWriter(dp, image_topic, qos=image_qos)
    reader = DataReader(dp, echo_topic, qos=D.RELIABLE)
    end = time.monotonic() + 30
    while not (writer.get_matched_subscriptions() and reader.get_matched_publications()):
        if time.monotonic() > end:
            raise RuntimeError("the echo peer was not discovered within 30 s")
        time.sleep(0.05)
    rng = np.random.default_rng(28)
    out, n = {}, 0
    for w, h in SHAPES:
        pixels = rng.integers(0, 256, size=(h, w), dtype=np.uint8)
        rtt, lost = [], 0
        for i in range(images + 5):
            n += 1
            ns = BASE_NS + n
            msg = D.image(ns, pixels)
            t = time.perf_counter()
            writer.write(msg)
            got = None
            while got is None and time.perf_counter() - t < 1.0:
                for m in reader.take(N=10):
                    if hasattr(m, "stamp") and D.stamp_ns(m.stamp) == ns:
                        got = time.perf_counter()
                if got is None:
                    time.sleep(0.0002)
            if i >= 5:
                if got is None:
                    lost += 1
                else:
                    rtt.append((got - t) * 1e3)
            time.sleep(max(0.0, 0.1 - (time.perf_counter() - t)))
        out[str(w * h)] = {"rtt": rtt, "lost": lost}
    return out


def peer_process(kind: str, domain: int, reliable: bool, large: bool, profile: str):
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_LOCALHOST_ONLY="1")
    env["CYCLONEDDS_URI"] = cyclone_uri(large)
    if kind == "cyclone":
        cmd = [sys.executable, __file__, "--serve", str(domain)] + (["--reliable"] if reliable else [])
    else:
        cmd = [str(REPO / "target" / profile / "examples" / "echo")]
        if kind == "rustdds-mio06":
            env["ECHO_EVENTS"] = "mio06"
        if reliable:
            env["ECHO_IMAGE_QOS"] = "reliable"
    return subprocess.Popen(cmd, env=env, stderr=subprocess.PIPE, text=True)


def cell(kind, domain, reliable, large, images, profile):
    peer = peer_process(kind, domain, reliable, large, profile)
    try:
        cmd = [sys.executable, __file__, "--client", str(domain), "--images", str(images)]
        env = dict(os.environ, CYCLONEDDS_URI=cyclone_uri(large))
        res = subprocess.run(cmd + (["--reliable"] if reliable else []), env=env,
                             capture_output=True, text=True, check=True)
        return json.loads(res.stdout.splitlines()[-1])
    finally:
        peer.terminate()
        peer.communicate(timeout=30)


# (label, peer, images reliable, Cyclone 60 kB fragments)
CONFIGS = [
    ("RustDDS echo, mio 1 wait (the node's)", "rustdds", False, False),
    ("RustDDS echo, mio 0.6 wait (the node's before)", "rustdds-mio06", False, False),
    ("RustDDS echo, mio 1 wait, images reliable", "rustdds", True, False),
    ("RustDDS echo, mio 1 wait, Cyclone sender 60 kB fragments", "rustdds", False, True),
    ("Cyclone DDS echo (peer figure)", "cyclone", False, False),
    ("Cyclone DDS echo, images reliable", "cyclone", True, False),
    ("Cyclone DDS echo, 60 kB fragments", "cyclone", False, True),
]


def busy_note() -> str:
    """Whether the machine was busy: the load average before the benchmark started."""
    cores = os.cpu_count() or 1
    state = "busy: other work ran, the figures are a shared machine's" if LOAD_BEFORE > 0.5 else "quiet"
    return f"1-minute load average {LOAD_BEFORE:.1f} on {cores} cores before the run ({state})"


def table(rows, images, profile) -> str:
    head = "| echo peer | " + " | ".join(f"{w * h / 1000:g} kB p50 / p99 ms" for w, h in SHAPES) + " | lost |"
    lines = [
        f"Round trip of one mono8 `sensor_msgs/Image` (payload sizes below) from Cyclone DDS "
        f"(Python) to the echo peer and its header back, loopback, {images} images a size "
        f"every 100 ms; binaries of the `{profile}` profile; {busy_note()}.",
        "",
        head,
        "|---|" + "---|" * (len(SHAPES) + 1),
    ]
    for label, res in rows:
        cells, lost = [], 0
        for w, h in SHAPES:
            r = res[str(w * h)]
            lost += r["lost"]
            x = np.array(r["rtt"])
            cells.append(f"{np.percentile(x, 50):.2f} / {np.percentile(x, 99):.2f}" if len(x) else "-")
        lines.append(f"| {label} | " + " | ".join(cells) + f" | {lost} |")
    return "\n".join(lines) + "\n"


def write_section(path: Path, marker: str, text: str):
    """Replaces what follows `marker` up to the next `<!-- ` marker (or the end)."""
    old = path.read_text() if path.exists() else ""
    if marker not in old:
        path.write_text(old.rstrip("\n") + f"\n\n{marker}\n{text}")
        return
    before, after = old.split(marker, 1)
    rest = after[after.index("<!-- "):] if "<!-- " in after else ""
    path.write_text(before + marker + "\n" + text + ("\n" + rest if rest else ""))


def sweep(images: int, profile: str) -> str:
    """Every echo peer of CONFIGS at every size: the table."""
    rows = []
    for i, (label, kind, reliable, large) in enumerate(CONFIGS):
        rows.append((label, cell(kind, 180 + i, reliable, large, images, profile)))
        print(table(rows[-1:], images, profile).splitlines()[-1], flush=True)
    return table(rows, images, profile)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--images", type=int, default=100, help="images timed a size")
    ap.add_argument("--out", type=Path, default=HERE.parent / "RESULTS.md")
    ap.add_argument("--profile", default="release", help="cargo profile folder of the echo example")
    ap.add_argument("--serve", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--client", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--reliable", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.serve is not None:
        return serve(args.serve, args.reliable)
    if args.client is not None:
        print(json.dumps(client(args.client, args.reliable, args.images)))
        return None
    write_section(args.out, MARKER, sweep(args.images, args.profile))
    print(f"written to {args.out}")
    return None


if __name__ == "__main__":
    main()
