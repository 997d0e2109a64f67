"""Fixtures of the ROS 2 node's interoperability tests: the node and the CLI built by
cargo, the KITTI sequence, the offline run to compare with, and a node process in a DDS
domain of its own on the loopback interface."""

import itertools
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

REPO = Path(__file__).resolve().parents[4]
TARGET = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "debug"

_domains = itertools.count()


def data_dir() -> Path | None:
    d = os.environ.get("SWARMPOSE_DATA")
    return Path(d) if d else None


@pytest.fixture(scope="session")
def kitti_dir():
    d = data_dir()
    path = d / "kitti_vo_seq2" if d else None
    if path is None or not (path / "calib.txt").exists():
        if os.environ.get("CI") == "true":
            pytest.fail("SWARMPOSE_DATA/kitti_vo_seq2 is missing under CI=true")
        pytest.skip("SWARMPOSE_DATA/kitti_vo_seq2 not found (set SWARMPOSE_DATA)")
    return path


_built = []


def built(package: str, binary: str) -> Path:
    """`binary` of `package`. With SWARMPOSE_BIN_DIR set (.ci/run sets it to the folder
    of `cargo test --workspace`'s binaries, which the node's command-line test makes cargo
    build), the binary there, which must exist; otherwise the node and the CLI built
    (incrementally) by cargo, both in one invocation (one feature set: no rebuild between
    them)."""
    bin_dir = os.environ.get("SWARMPOSE_BIN_DIR")
    if bin_dir:
        path = Path(bin_dir) / binary
        if not path.is_file():
            pytest.fail(f"SWARMPOSE_BIN_DIR={bin_dir}: no {binary} there (run cargo test --workspace first)")
        return path
    if not _built:
        subprocess.run(
            ["cargo", "build", "--quiet", "-p", "swarmpose-ros2", "-p", "swarmpose-cli", "--bins"],
            cwd=REPO,
            check=True,
        )
        _built.append(True)
    return TARGET / binary


@pytest.fixture(scope="session")
def node_binary():
    return built("swarmpose-ros2", "swarmpose-ros2")


@pytest.fixture(scope="session")
def kitti(kitti_dir):
    from dds_peer import Kitti

    return Kitti(kitti_dir)


@pytest.fixture(scope="session")
def offline(kitti_dir, tmp_path_factory):
    """The offline run `swarmpose odometry` of the sequence: its Odometry messages (in
    odometry.mcap), frame by frame."""
    from mcap_ros2.reader import read_ros2_messages

    out = tmp_path_factory.mktemp("offline")
    subprocess.run(
        [str(built("swarmpose-cli", "swarmpose")), "odometry", str(kitti_dir), "--out", str(out), "--quiet"],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    msgs = [m.ros_msg for m in read_ros2_messages(str(out / "odometry.mcap"), topics=["/swarmpose/odometry"])]
    return msgs


def domain_id() -> int:
    """A DDS domain of this test alone (from the process id and a counter: no two tests
    of concurrent runs share one)."""
    return 1 + (os.getpid() * 13 + next(_domains) * 7) % 200


class Node:
    """A swarmpose-ros2 process."""

    def __init__(self, binary: Path, domain: int, out: Path | None, *args: str):
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_LOCALHOST_ONLY="1")
        cmd = [str(binary), *args] + (["--out", str(out)] if out else [])
        self.proc = subprocess.Popen(
            cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        self.stdout = self.stderr = ""

    def stop(self, sig=signal.SIGINT, timeout_s=30.0):
        """Sends `sig`; returns (exit status, seconds to exit)."""
        t = time.monotonic()
        self.proc.send_signal(sig)
        self.stdout, self.stderr = self.proc.communicate(timeout=timeout_s)
        return self.proc.returncode, time.monotonic() - t

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.stdout, self.stderr = self.proc.communicate()


@pytest.fixture
def node_factory(node_binary):
    started = []

    def start(domain, out=None, *args):
        n = Node(node_binary, domain, out, *args)
        started.append(n)
        return n

    yield start
    for n in started:
        n.kill()


@pytest.fixture
def peer_factory():
    from dds_peer import Peer

    made = []

    def make(domain):
        p = Peer(domain)
        made.append(p)
        return p

    yield make
    for p in made:
        p.close()


def pytest_configure(config):
    if shutil.which("cargo") is None:
        pytest.exit("cargo is needed to build the node", returncode=1)
