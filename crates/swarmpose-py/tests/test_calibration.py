"""Calibrations checked as the command line checks them (issue 29): projection rows read
in full (both rows' offsets give the baseline; a skew is refused) by Sequence and
Odometry.from_sequence."""

import shutil

import pytest

import swarmpose

FX, CX, CY = 718.856, 607.1928, 185.2157


def row(name, t, skew=0.0):
    """A calib.txt row of K [I | t], t in metres."""
    tx, ty, tz = t
    return (f"{name}: {FX} {skew} {CX} {FX * tx + CX * tz!r} 0 {FX} {CY} "
            f"{FX * ty + CY * tz!r} 0 0 1 {tz!r}\n")


@pytest.fixture
def clip(kitti_seq2, tmp_path):
    """The first two frames of kitti_vo_seq2 without ground truth; returns its calib.txt."""
    seq = tmp_path / "k"
    for side in ("image_0", "image_1"):
        (seq / side).mkdir(parents=True)
        for i in range(2):
            shutil.copy(kitti_seq2 / side / f"{i:06}.png", seq / side)
    return seq / "calib.txt"


def test_both_rows_offsets_give_the_baseline(clip):
    left = (0.059939, -0.001131, 0.00378)
    clip.write_text(row("P0", left) + row("P1", (left[0] - 0.53717, left[1], left[2])))
    camera = swarmpose.Sequence(clip.parent).camera
    # Before: the right row's Tx alone, 0.477 m.
    assert camera["baseline"] == pytest.approx(0.53717, abs=1e-9)
    assert swarmpose.Odometry.from_sequence(clip.parent).camera["baseline"] == \
        pytest.approx(0.53717, abs=1e-9)


def test_a_skew_is_refused(clip):
    clip.write_text(row("P0", (0, 0, 0)) + row("P1", (-0.537, 0, 0), skew=2.5))
    with pytest.raises(ValueError) as e:
        swarmpose.Sequence(clip.parent)
    assert str(e.value) == (f"{clip}:2: P1[0][1] = 2.5 is a skew: the rectified model has "
                            "none (a rectified camera matrix has 0 there)")
