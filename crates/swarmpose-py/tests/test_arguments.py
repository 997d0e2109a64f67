"""Issue 29, item 11 in Python: errors that name the argument, an engine shared by
threads, a mirror image refused, and a run that tracks nothing raising as the command
line's exit status 3 does."""

import struct
import threading
import zlib

import numpy as np
import pytest

import swarmpose
from test_odometry import KITTI_CAMERA, copy_kitti


def cloud(n=10):
    k = np.arange(n, dtype=float)
    return np.stack([k * 0.7 - 2.0, np.sin(k * 1.3) * 3.0, 4.0 + np.cos(k * 0.9)], axis=1)


def test_a_negative_seed_names_the_argument():
    src = cloud()
    for call in (lambda: swarmpose.register(src, src + 1.0, seed=-1),
                 lambda: swarmpose.OdometryConfig(seed=-1),
                 lambda: swarmpose.OdometryConfig(seed=2**64)):
        with pytest.raises(ValueError) as e:
            call()
        assert "seed must be an integer from 0 to 2**64 - 1" in str(e.value)
    with pytest.raises(TypeError) as e:
        swarmpose.register(src, src, seed="1")
    assert "seed must be an int" in str(e.value)


@pytest.mark.parametrize("terms", [(1.0,), (1.0, 2.0, 3.0, 4.0), ()])
def test_a_disparity_correction_of_the_wrong_length(terms):
    with pytest.raises(ValueError) as e:
        swarmpose.OdometryConfig(disparity_correction=terms)
    assert str(e.value) == ("disparity_correction must be (offset, quadratic) or (offset, "
                            f"quadratic, linear), numbers of pixels: got {len(terms)} number(s)")
    assert swarmpose.OdometryConfig(disparity_correction=[0.5, 0.0]).disparity_correction \
        == (0.5, 0.0)


def test_a_mirror_image_is_refused():
    src = cloud()
    with pytest.raises(ValueError) as e:
        swarmpose.register(src, -src, method="svd")
    assert "mirror image" in str(e.value)


def test_threads_may_share_an_engine():
    """One thread tracks while another reads the engine: pyo3 raised "Already borrowed"."""
    odo = swarmpose.Odometry(**KITTI_CAMERA)
    frame = np.zeros((KITTI_CAMERA["height"], KITTI_CAMERA["width"]), np.uint8)
    errors = []
    done = threading.Event()

    def track():
        try:
            for i in range(6):
                odo.track(frame, frame, 0.1 * i)
        except Exception as e:  # noqa: BLE001 - the test reports any
            errors.append(e)
        finally:
            done.set()

    def read():
        try:
            while not done.is_set():
                odo.state_bytes, odo.calibration, repr(odo)
        except Exception as e:  # noqa: BLE001
            errors.append(e)

    threads = [threading.Thread(target=track), threading.Thread(target=read)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []


def blank_png(path, width, height):
    """A gray PNG of one value (no image library needed)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(
            ">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    rows = b"".join(b"\0" + bytes([90]) * width for _ in range(height))
    path.write_bytes(b"\x89PNG\r\n\x1a\n"
                     + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def test_a_run_that_tracks_nothing_raises(kitti_seq2, tmp_path):
    copy_kitti(kitti_seq2, tmp_path, 4)
    for image in tmp_path.glob("image_*/*.png"):
        blank_png(image, KITTI_CAMERA["width"], KITTI_CAMERA["height"])
    with pytest.raises(swarmpose.NotUsableError) as e:
        swarmpose.odometry(tmp_path)
    assert str(e.value).startswith("not usable: 0 motions of 3 were tracked")
    assert isinstance(e.value, swarmpose.EstimationError)
    assert len(e.value.run.poses) == 4
