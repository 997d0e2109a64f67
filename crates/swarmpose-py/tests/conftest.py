"""Shared helpers of the pytest suite: the data root (as the Rust tests find it) and
the `swarmpose` command-line binary."""

import os
import shutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


def data_root() -> Path:
    """SWARMPOSE_DATA, else ../shared/data beside the repository (as the Rust tests)."""
    env = os.environ.get("SWARMPOSE_DATA")
    return Path(env) if env else REPO.parent / "shared" / "data"


def require(what: str, found: bool, reason: str) -> None:
    """Skips with `reason` when `what` is missing; under CI=true, fails instead."""
    if found:
        return
    message = f"{what} not found: {reason}"
    if os.environ.get("CI") == "true":
        pytest.fail(f"CI=true: {message}")
    pytest.skip(message)


@pytest.fixture
def kitti_seq2() -> Path:
    d = data_root() / "kitti_vo_seq2"
    require(f"data set {d}", d.is_dir(), "set SWARMPOSE_DATA to the data root")
    return d


@pytest.fixture
def swarmpose_bin() -> Path:
    """The CLI: SWARMPOSE_BIN, else the newest of target/{release,debug}/swarmpose,
    else `swarmpose` on PATH (CI builds target/debug/swarmpose in `cargo test`)."""
    env = os.environ.get("SWARMPOSE_BIN")
    candidates = [Path(env)] if env else []
    built = [REPO / "target" / p / "swarmpose" for p in ("release", "debug")]
    candidates += sorted((b for b in built if b.is_file()), key=lambda b: -b.stat().st_mtime)
    on_path = shutil.which("swarmpose")
    if on_path:
        candidates.append(Path(on_path))
    found = next((c for c in candidates if c.is_file()), None)
    require("the swarmpose binary", found is not None,
            "build it with `cargo build -p swarmpose-cli` or set SWARMPOSE_BIN")
    return found
