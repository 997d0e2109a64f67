"""swarmpose.Odometry.rgbd / track_rgbd: a textured wall seen by an RGB-D camera that
moves sideways, and the errors of giving a frame of the wrong kind."""

import numpy as np
import pytest

import swarmpose

FX, CX, CY, W, H = 525.0, 319.5, 239.5, 640, 480
DEPTH_M = 2.0


def texture(seed=3):
    """A random blob texture wide enough to slide the view over (uint8)."""
    rng = np.random.default_rng(seed)
    coarse = rng.uniform(0, 255, size=(H // 4 + 1, (W + 64) // 4 + 1))
    big = np.kron(coarse, np.ones((4, 4)))[:H, : W + 64]
    return big.astype(np.uint8)


def test_a_sideways_motion_of_a_wall():
    """The view slides by 8 px over a wall 2 m away: the camera moved 8 * 2 / fx m
    along x (the image content moves left when the camera moves right)."""
    wall = texture()
    depth = np.full((H, W), DEPTH_M, np.float32)
    odo = swarmpose.Odometry.rgbd(FX, FX, CX, CY, W, H)
    first = odo.track_rgbd(np.ascontiguousarray(wall[:, :W]), depth, 0.0)
    second = odo.track_rgbd(np.ascontiguousarray(wall[:, 8:W + 8]), depth, 0.1)
    assert first.status == "first"
    assert second.tracked, second.status
    t = second.pose[:3, 3]
    assert t[0] == pytest.approx(8 * DEPTH_M / FX, rel=0.05)
    assert abs(t[1]) < 2e-3 and abs(t[2]) < 1e-2


def test_frames_of_the_wrong_kind():
    rgbd = swarmpose.Odometry.rgbd(FX, FX, CX, CY, W, H)
    gray = np.zeros((H, W), np.uint8)
    with pytest.raises(ValueError) as e:
        rgbd.track(gray, gray, 0.0)
    assert str(e.value) == "camera: this engine takes RGB-D frames (track_rgbd), not stereo pairs"
    with pytest.raises(ValueError) as e:
        rgbd.track_rgbd(gray, np.zeros((H, W)), 0.0)
    assert str(e.value).startswith("depth image has shape (480, 640) and dtype float64")
    stereo = swarmpose.Odometry(FX, FX, CX, CY, 0.1, W, H)
    with pytest.raises(ValueError) as e:
        stereo.track_rgbd(gray, np.zeros((H, W), np.float32), 0.0)
    assert str(e.value) == "camera: this engine takes stereo pairs (track), not RGB-D frames"
