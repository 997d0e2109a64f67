"""Calibrations checked as the command line checks them (issue 29): projection rows read
in full (both rows' offsets give the baseline; a skew is refused) and intrinsics that are
no camera for the images refused, by Sequence, Odometry.from_sequence and Odometry."""

import shutil

import pytest

import swarmpose

FX, CX, CY = 718.856, 607.1928, 185.2157
KITTI_CAMERA = dict(fx=FX, fy=FX, cx=CX, cy=CY, baseline=0.53717, width=1241, height=376)


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


def test_a_skew_and_a_principal_point_off_the_image_are_refused(clip):
    clip.write_text(row("P0", (0, 0, 0)) + row("P1", (-0.537, 0, 0), skew=2.5))
    with pytest.raises(ValueError) as e:
        swarmpose.Sequence(clip.parent)
    assert str(e.value) == (f"{clip}:2: P1[0][1] = 2.5 is a skew: the rectified model has "
                            "none (a rectified camera matrix has 0 there)")
    clip.write_text((row("P0", (0, 0, 0)) + row("P1", (-0.537, 0, 0)))
                    .replace(f" {CX} ", " 6071.928 "))
    with pytest.raises(ValueError) as e:
        swarmpose.Odometry.from_sequence(clip.parent)
    assert str(e.value).startswith(f"{clip}: cx = 6071.928 px is outside the 1241x376 image")


@pytest.mark.parametrize("change, message", [
    ({"cx": 6071.928}, "camera: cx = 6071.928 px is outside the 1241x376 image"),
    ({"fy": 71.8856}, "camera: fx / fy = 10.000"),
    ({"fx": 7.18856, "fy": 7.18856}, "camera: fx = 7.18856 px is not a focal length"),
])
def test_the_engine_refuses_what_is_no_camera_for_its_images(change, message):
    with pytest.raises(ValueError) as e:
        swarmpose.Odometry(**{**KITTI_CAMERA, **change})
    assert str(e.value).startswith(message)
