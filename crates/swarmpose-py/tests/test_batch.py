"""swarmpose.batch: the items of a manifest run in a process pool, or on a local Ray
runtime, give the same merged table, byte for byte, as a serial batch; a rerun skips
what is done."""

import os
from pathlib import Path

import pytest

import swarmpose.batch
from conftest import data_root, require

FRAMES = 10


def kitti_slice(src: Path, dst: Path, start: int) -> Path:
    """Frames start..start+FRAMES of a KITTI clip (images linked, poses cut)."""
    for cam in ("image_0", "image_1"):
        (dst / cam).mkdir(parents=True)
        for i, f in enumerate(sorted(os.listdir(src / cam))[start:start + FRAMES]):
            os.symlink(src / cam / f, dst / cam / f"{i:06d}.png")
    os.symlink(src / "calib.txt", dst / "calib.txt")
    poses = (src / "poses.txt").read_text().splitlines()[start:start + FRAMES]
    (dst / "poses.txt").write_text("\n".join(poses) + "\n")
    return dst


@pytest.fixture
def manifest(tmp_path: Path) -> Path:
    src = data_root() / "kitti_vo_seq2"
    require(f"data set {src}", src.is_dir(), "set SWARMPOSE_DATA to the data root")
    items = [kitti_slice(src, tmp_path / f"seq{k}", k * 20) for k in range(3)]
    text = 'args = ["--seed", "0"]\n'
    for k, d in enumerate(items):
        text += f'\n[[item]]\nname = "part{k}"\ninput = "{d}"\n'
    path = tmp_path / "fleet.toml"
    path.write_text(text)
    return path


def table(out: Path) -> str:
    status, message = swarmpose.batch.merge(out)
    assert status == 0, message
    return (out / "batch.csv").read_text() + (out / "batch.md").read_text()


def test_a_process_pool_gives_the_serial_table_and_a_rerun_skips(manifest: Path, tmp_path: Path):
    serial = swarmpose.batch.run(manifest, tmp_path / "serial", executor="serial")
    assert [s["status"] for s in serial] == ["ok"] * 3, serial
    assert all(s["frames"] == FRAMES and s["metrics"] for s in serial)
    pooled = swarmpose.batch.run(manifest, tmp_path / "pool", jobs=2)
    assert table(tmp_path / "pool") == table(tmp_path / "serial")
    again = swarmpose.batch.run(manifest, tmp_path / "pool", jobs=2)
    assert [s["skipped"] for s in again] == [True] * 3
    assert [s["input_hash"] for s in again] == [s["input_hash"] for s in pooled]


def test_a_bad_manifest_raises_before_anything_runs(tmp_path: Path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[[item]]\ninput = "x"\nargs = ["--no-such-option"]\n')
    with pytest.raises(ValueError, match="item x"):
        swarmpose.batch.run(bad, tmp_path / "out")
    assert not (tmp_path / "out" / "x").exists()


def test_ray_gives_the_serial_table(manifest: Path, tmp_path: Path):
    ray = pytest.importorskip(
        "ray", reason="ray is not installed (pip install 'swarmpose[ray]')"
    )
    swarmpose.batch.run(manifest, tmp_path / "serial", executor="serial")
    ray.init(num_cpus=2, include_dashboard=False)
    try:
        summaries = swarmpose.batch.run(manifest, tmp_path / "ray", executor="ray")
    finally:
        ray.shutdown()
    assert [s["status"] for s in summaries] == ["ok"] * 3, summaries
    assert table(tmp_path / "ray") == table(tmp_path / "serial")
