"""swarmpose.Odometry, swarmpose.odometry, swarmpose.Sequence and swarmpose.evaluate:
the streaming engine from Python gives the trajectory of `swarmpose odometry`, and bad
input raises with the Rust messages."""

import shutil
import subprocess

import numpy as np
import pytest

import swarmpose

KITTI_CAMERA = dict(fx=718.856, fy=718.856, cx=607.1928, cy=185.2157, baseline=0.53717,
                    width=1241, height=376)


def read_kitti(path):
    rows = np.loadtxt(path).reshape(-1, 3, 4)
    poses = np.tile(np.eye(4), (len(rows), 1, 1))
    poses[:, :3, :] = rows
    return poses


def test_streaming_matches_the_cli(kitti_seq2, swarmpose_bin, tmp_path):
    """Frames given one at a time from numpy arrays give the CLI's trajectory (same
    engine, same defaults, frame i at 0.1 i s)."""
    out = tmp_path / "cli"
    subprocess.run([str(swarmpose_bin), "odometry", str(kitti_seq2), "--out", str(out),
                    "--quiet"], check=True, capture_output=True)
    cli = read_kitti(out / "trajectory.kitti.txt")

    seq = swarmpose.Sequence(kitti_seq2)
    odo = swarmpose.Odometry.from_sequence(kitti_seq2)
    frames = []
    for i in range(len(seq)):
        left, right = seq[i]
        frames.append(odo.track(left, right, 0.1 * i))
    poses = np.stack([f.pose for f in frames])
    assert poses.shape == cli.shape == (51, 4, 4)
    # The CLI prints the shortest decimal that reads back as the same double.
    assert np.max(np.abs(poses - cli)) < 1e-12
    assert frames[0].status == "first"
    assert sum(f.tracked for f in frames) >= 45
    assert all(f.covariance is None or f.covariance.shape == (6, 6) for f in frames)
    # The default window of 10 keyframes: each tracked frame is measured from the
    # window's oldest keyframe, with the covariance of that motion; driving at 10 Hz,
    # every frame moves enough to be a keyframe (the CLI's frames.csv says the same).
    rows = [line.rstrip().split(",") for line in (out / "frames.csv").read_text().splitlines()]
    assert rows[0][-2:] == ["keyframe", "ambiguous"]
    cli_keyframes = [row[-2] == "1" for row in rows[1:]]
    assert [f.keyframe for f in frames] == cli_keyframes == [True] * 51
    # A static scene: no frame saw two motions.
    assert [f.ambiguous for f in frames] == [row[-1] == "1" for row in rows[1:]] == [False] * 51
    for k, f in enumerate(frames[1:], start=1):
        assert f.reference == max(0, k - 9)
        assert f.measured_motion.shape == (4, 4)
        assert np.all(np.linalg.eigvalsh(f.covariance) > 0)

    run = swarmpose.odometry(kitti_seq2)
    assert np.array_equal(run.poses, poses)
    # The fixed-lag smoothed trajectory: the CLI's file, and each frame's last window
    # pose as the frames carry them.
    smoothed = run.smoothed_poses
    assert np.max(np.abs(smoothed - read_kitti(out / "trajectory.smoothed.kitti.txt"))) < 1e-12
    last = {}
    for f in frames:
        assert f.index == 0 or f.window_poses[-1][0] == f.index
        last.update({i: p for i, p in f.window_poses})
    assert all(np.array_equal(smoothed[i], p) for i, p in last.items())
    assert run.statuses == [f.status for f in frames]

    metrics = swarmpose.evaluate(run.poses, run.ground_truth)
    cli_metrics = subprocess.run(
        [str(swarmpose_bin), "evaluate", str(out / "trajectory.kitti.txt"),
         str(out / "groundtruth.kitti.txt"), "--json"],
        check=True, capture_output=True, text=True).stdout
    import json
    cli_metrics = json.loads(cli_metrics)
    for key in ("eq20_rms", "final_drift_m", "path_length_m"):
        assert metrics[key] == pytest.approx(cli_metrics[key], rel=1e-9, abs=1e-12), key
    files = swarmpose.evaluate(out / "trajectory.kitti.txt", out / "groundtruth.kitti.txt")
    assert files["eq20_rms"] == pytest.approx(metrics["eq20_rms"], rel=1e-9)


def test_sequence_reads_frames(kitti_seq2):
    seq = swarmpose.Sequence(str(kitti_seq2))
    assert len(seq) == 51 and seq.layout == "kitti"
    left, right = seq[-1]
    assert left.shape == right.shape == (376, 1241) and left.dtype == np.uint8
    assert seq.camera["fx"] == pytest.approx(718.856)
    assert seq.ground_truth.shape == (51, 4, 4)
    with pytest.raises(IndexError):
        seq[51]


def test_track_takes_non_contiguous_images(kitti_seq2):
    """A Fortran-ordered copy is read (copied) correctly: the same pose as C order."""
    seq = swarmpose.Sequence(kitti_seq2)
    a = swarmpose.Odometry.from_sequence(kitti_seq2)
    b = swarmpose.Odometry.from_sequence(kitti_seq2)
    for i in range(3):
        left, right = seq[i]
        ra = a.track(left, right, 0.1 * i)
        rb = b.track(np.asfortranarray(left), np.asfortranarray(right), 0.1 * i)
        assert np.array_equal(ra.pose, rb.pose)


def test_bad_camera():
    with pytest.raises(ValueError) as e:
        swarmpose.Odometry(**{**KITTI_CAMERA, "fx": -1.0})
    assert str(e.value) == "camera: fx is -1: it must be a finite positive number"
    with pytest.raises(ValueError) as e:
        swarmpose.Odometry(**KITTI_CAMERA, detector="sift")
    assert "sift" in str(e.value)
    with pytest.raises(ValueError) as e:
        swarmpose.Odometry(**KITTI_CAMERA, method="icp")
    assert str(e.value) == 'unknown method "icp": one of pso, pso-paper, svd, msac, wls'


def test_bad_frames_leave_the_engine_usable():
    odo = swarmpose.Odometry(**KITTI_CAMERA)
    small = np.zeros((10, 20), np.uint8)
    with pytest.raises(ValueError) as e:
        odo.track(small, small, 0.0)
    assert str(e.value) == "the left image is 20x10, but the camera's images are 1241x376"
    with pytest.raises(ValueError) as e:
        odo.track(np.zeros((376, 1241), np.float32), small, 0.0)
    assert str(e.value).startswith("left image has shape (376, 1241) and dtype float32")
    with pytest.raises(TypeError):
        odo.track([[0]], small, 0.0)
    frame = np.zeros((376, 1241), np.uint8)
    first = odo.track(frame, frame, 1.0)
    assert first.index == 0 and np.array_equal(first.pose, np.eye(4))
    with pytest.raises(ValueError) as e:
        odo.track(frame, frame, 1.0)
    assert str(e.value) == ("timestamp 1 s does not come after the previous frame's 1 s: "
                            "timestamps must increase")
    second = odo.track(frame, frame, 1.1)
    assert second.index == 1


def test_images_given_the_wrong_way_round(kitti_seq2):
    """A pair whose left and right images are exchanged raises, and the engine takes the
    pair the right way round next."""
    seq = swarmpose.Sequence(kitti_seq2)
    odo = swarmpose.Odometry.from_sequence(kitti_seq2)
    left, right = seq[0]
    with pytest.raises(ValueError) as e:
        odo.track(right, left, 0.0)
    assert str(e.value).startswith("the left and right images look exchanged: ")
    assert odo.track(left, right, 0.0).status == "first"


def copy_kitti(src, dst, n):
    """The first ``n`` frames of a KITTI sequence (images, calib.txt, poses) in ``dst``."""
    for side in ("image_0", "image_1"):
        (dst / side).mkdir(parents=True)
        for i in range(n):
            shutil.copy(src / side / f"{i:06}.png", dst / side / f"{i:06}.png")
    shutil.copy(src / "calib.txt", dst / "calib.txt")
    poses = (src / "poses.txt").read_text().splitlines()[:n]
    (dst / "poses.txt").write_text("\n".join(poses) + "\n")


def test_a_corrupt_frame_keeps_the_frames_before_it(kitti_seq2, tmp_path):
    """As on the command line: the run stops at the frame, says how many were done, and
    keeps them (the exception's ``run``); they used to be lost with the exception."""
    copy_kitti(kitti_seq2, tmp_path / "bad", 5)
    corrupt = tmp_path / "bad" / "image_0" / "000003.png"
    corrupt.write_bytes(b"\x89PNG\r\n\x1a\nnot really a png")
    with pytest.raises(ValueError) as e:
        swarmpose.odometry(tmp_path / "bad")
    message = str(e.value)
    assert message.startswith(f"frame 3: {corrupt}: not a readable PNG image"), message
    assert message.endswith("; stopped after 3 frame(s): the exception's `run` holds them")
    run = e.value.run
    assert len(run) == 3 and run.poses.shape == (3, 4, 4)
    copy_kitti(kitti_seq2, tmp_path / "good", 3)
    assert np.array_equal(run.poses, swarmpose.odometry(tmp_path / "good").poses)


def test_paths_that_do_not_exist(tmp_path):
    missing = tmp_path / "nowhere"
    with pytest.raises(FileNotFoundError) as e:
        swarmpose.Sequence(missing)
    assert str(e.value) == f"{missing}: missing (sequence directory)"
    with pytest.raises(FileNotFoundError):
        swarmpose.odometry(missing)
    with pytest.raises(FileNotFoundError):
        swarmpose.evaluate(missing, missing)
    with pytest.raises(ValueError) as e:
        swarmpose.Sequence(tmp_path)
    assert "unknown sequence layout" in str(e.value)


def test_evaluate_arrays():
    """A trajectory against itself: zero errors; against a shifted copy: the shift."""
    steps = np.tile(np.eye(4), (20, 1, 1))
    steps[:, 2, 3] = np.arange(20.0)
    m = swarmpose.evaluate(steps, steps)
    assert m["eq20_rms"] == 0.0 and m["final_drift_m"] == 0.0
    assert m["path_length_m"] == pytest.approx(19.0)
    moved = steps.copy()
    moved[:, 0, 3] += 0.5
    assert swarmpose.evaluate(moved, steps)["ate_raw"]["rmse"] == pytest.approx(0.5)
    with pytest.raises(ValueError) as e:
        swarmpose.evaluate(steps[:5], steps)
    assert str(e.value).startswith("estimate has 5 poses but ground_truth has 20")
    with pytest.raises(ValueError) as e:
        swarmpose.evaluate(steps[:, :3], steps)
    assert str(e.value) == "estimate has shape (20, 3, 4): (N, 4, 4) expected"


@pytest.mark.parametrize("block, message", [
    (np.diag([1.0, 1.0, -1.0]), "estimate[3]: the 3x3 part has determinant -1.000 (a reflection)"),
    (2 * np.eye(3), "estimate[3]: the 3x3 part is not a rotation (|R Rᵀ - I| = 5.196e0"),
    (np.zeros((3, 3)), "estimate[3]: the 3x3 part is not a rotation"),
])
def test_evaluate_refuses_what_is_not_a_pose(block, message):
    """As for trajectory files: a reflection, a scale or a zero block was projected to
    some rotation and evaluated without a word; a last row that is not 0 0 0 1 too."""
    steps = np.tile(np.eye(4), (20, 1, 1))
    steps[:, 2, 3] = np.arange(20.0)
    bad = steps.copy()
    bad[3, :3, :3] = block
    with pytest.raises(ValueError) as e:
        swarmpose.evaluate(bad, steps)
    assert str(e.value).startswith(message)
    bad = steps.copy()
    bad[3, 3] = [0.0, 0.0, 1.0, 1.0]
    with pytest.raises(ValueError) as e:
        swarmpose.evaluate(steps, bad)
    assert str(e.value) == "ground_truth[3] has the last row [0.0, 0.0, 1.0, 1.0]: [0, 0, 0, 1] expected"
    # Rounding as np.linalg.inv leaves it is accepted.
    inverted = np.linalg.inv(np.linalg.inv(steps))
    assert swarmpose.evaluate(inverted, steps)["eq20_rms"] < 1e-9


def test_window_matches_the_cli(kitti_seq2, swarmpose_bin, tmp_path):
    """``window=K`` is the command line's ``--window K``: the same trajectory (another
    one than the default window's), and a bad value is refused."""
    out = tmp_path / "cli"
    subprocess.run([str(swarmpose_bin), "odometry", str(kitti_seq2), "--out", str(out),
                    "--quiet", "--window", "5"], check=True, capture_output=True)
    cli = read_kitti(out / "trajectory.kitti.txt")
    run = swarmpose.odometry(kitti_seq2, window=5)
    assert np.max(np.abs(run.poses - cli)) < 1e-12
    default = swarmpose.odometry(kitti_seq2)
    assert np.max(np.abs(run.poses - default.poses)) > 1e-6
    frame_to_frame = swarmpose.odometry(kitti_seq2, window=0)
    assert all(f.reference == k for k, f in enumerate(frame_to_frame.frames[1:]))
    times = swarmpose.Odometry.from_sequence(kitti_seq2, window=5)
    seq = swarmpose.Sequence(kitti_seq2)
    for i in range(3):
        frame = times.track(*seq[i], 0.1 * i)
    assert "window" in frame.times_ms
    with pytest.raises(OverflowError):
        swarmpose.odometry(kitti_seq2, window=-1)


def test_marginalise_matches_the_cli(kitti_seq2, swarmpose_bin, tmp_path):
    """``marginalise=MODE`` is the command line's ``--marginalise MODE``: the same
    trajectory (another one than the default's, which is ``"off"``), and an unknown mode
    is refused with the modes named."""
    out = tmp_path / "cli"
    subprocess.run([str(swarmpose_bin), "odometry", str(kitti_seq2), "--out", str(out),
                    "--quiet", "--marginalise", "finished"], check=True, capture_output=True)
    cli = read_kitti(out / "trajectory.kitti.txt")
    run = swarmpose.odometry(kitti_seq2, marginalise="finished")
    assert np.max(np.abs(run.poses - cli)) < 1e-12
    off = swarmpose.odometry(kitti_seq2, marginalise="off")
    default = swarmpose.odometry(kitti_seq2)
    assert np.max(np.abs(off.poses - default.poses)) < 1e-12
    assert np.max(np.abs(run.poses - default.poses)) > 1e-6
    with pytest.raises(ValueError, match='marginalise "sometimes": expected one of off, finished, all'):
        swarmpose.Odometry(**KITTI_CAMERA, marginalise="sometimes")


def test_correction_per_frame_matches_the_cli(kitti_seq2, swarmpose_bin, tmp_path):
    """``correction_per_frame=True`` is the command line's ``--correction-per-frame``
    (issue 30): the same trajectory, another one than the default's."""
    out = tmp_path / "cli"
    subprocess.run([str(swarmpose_bin), "odometry", str(kitti_seq2), "--out", str(out),
                    "--quiet", "--correction-per-frame"], check=True, capture_output=True)
    cli = read_kitti(out / "trajectory.kitti.txt")
    config = swarmpose.OdometryConfig(correction_per_frame=True)
    assert config.correction_per_frame is True
    run = swarmpose.odometry(kitti_seq2, config=config)
    assert np.max(np.abs(run.poses - cli)) < 1e-12
    subprocess.run([str(swarmpose_bin), "odometry", str(kitti_seq2), "--out", str(tmp_path / "d"),
                    "--quiet"], check=True, capture_output=True)
    default = read_kitti(tmp_path / "d" / "trajectory.kitti.txt")
    assert np.max(np.abs(run.poses - default)) > 1e-6


def test_guided_radius_matches_the_cli(kitti_seq2, swarmpose_bin, tmp_path):
    """``guided_radius_px=20`` is the command line's ``--guided-radius 20`` (issue 34): the
    same trajectory, another one than the default's; a radius that is not above 0 is refused
    with the engine's message."""
    out = tmp_path / "cli"
    subprocess.run([str(swarmpose_bin), "odometry", str(kitti_seq2), "--out", str(out),
                    "--quiet", "--guided-radius", "20"], check=True, capture_output=True)
    cli = read_kitti(out / "trajectory.kitti.txt")
    config = swarmpose.OdometryConfig(guided_radius_px=20.0)
    assert config.guided_radius_px == 20.0
    run = swarmpose.odometry(kitti_seq2, config=config)
    assert np.max(np.abs(run.poses - cli)) < 1e-12
    default = swarmpose.odometry(kitti_seq2)
    assert np.max(np.abs(run.poses - default.poses)) > 1e-6
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="guided"):
            swarmpose.OdometryConfig(guided_radius_px=bad)


def test_fixed_correction_with_a_linear_term_matches_the_cli(kitti_seq2, swarmpose_bin, tmp_path):
    """``disparity_correction=(offset, quadratic, linear)`` is the command line's
    ``--disparity-offset --disparity-quadratic --disparity-linear``: the same trajectory,
    another one than without the linear term; the tuple reads back as given."""
    out = tmp_path / "cli"
    subprocess.run([str(swarmpose_bin), "odometry", str(kitti_seq2), "--out", str(out),
                    "--quiet", "--window", "0", "--disparity-offset", "0.6",
                    "--disparity-quadratic", "2.3", "--disparity-linear", "0.4"],
                   check=True, capture_output=True)
    cli = read_kitti(out / "trajectory.kitti.txt")
    config = swarmpose.OdometryConfig(window=0, disparity_correction=(0.6, 2.3, 0.4))
    assert config.disparity_correction == (0.6, 2.3, 0.4)
    run = swarmpose.odometry(kitti_seq2, config=config)
    assert np.max(np.abs(run.poses - cli)) < 1e-12
    two = swarmpose.odometry(kitti_seq2, window=0, disparity_correction=(0.6, 2.3))
    assert np.max(np.abs(run.poses - two.poses)) > 1e-6
    assert run.frames[5].correction["linear_x_px"] == 0.4
    with pytest.raises(ValueError, match="disparity_correction linear must be a finite number"):
        swarmpose.Odometry(**KITTI_CAMERA, disparity_correction=(0.0, 0.0, float("inf")))
    with pytest.raises(ValueError, match="disparity_correction must be"):
        swarmpose.Odometry(**KITTI_CAMERA, disparity_correction=(0.0,))


def test_large_images_are_halved(kitti_seq2):
    """A camera whose images have more than ``max_working_pixels`` pixels works on its
    images halved: each KITTI pixel repeated 2x2 (calibration to match) gives the
    recorded images' poses again."""
    seq = swarmpose.Sequence(kitti_seq2)
    big = dict(KITTI_CAMERA, fx=2 * 718.856, fy=2 * 718.856, cx=2 * 607.1928 + 0.5,
               cy=2 * 185.2157 + 0.5, width=2 * 1241, height=2 * 376)
    large = swarmpose.Odometry(**big, max_working_pixels=1241 * 376, min_working_pixels=0)
    small = swarmpose.Odometry(**KITTI_CAMERA, max_working_pixels=1241 * 376,
                               min_working_pixels=0)
    assert large.working_camera["width"] == 1241 and large.working_camera["height"] == 376
    assert abs(large.working_camera["cx"] - 607.1928) < 1e-9
    assert small.working_camera == small.camera
    for i in range(3):
        left, right = seq[i]
        a = small.track(left, right, 0.1 * i)
        twice = [np.repeat(np.repeat(im, 2, axis=0), 2, axis=1) for im in (left, right)]
        b = large.track(*twice, 0.1 * i)
        assert a.status == b.status
        assert np.max(np.abs(a.pose - b.pose)) < 1e-9
    with pytest.raises(OverflowError):
        swarmpose.Odometry(**KITTI_CAMERA, max_working_pixels=-1)
    with pytest.raises(ValueError, match="max_working_pixels 5: at least 10000 are needed"):
        swarmpose.Odometry(**KITTI_CAMERA, max_working_pixels=5)


def test_fixed_correction_out_of_range():
    """A fixed correction of 1e9 px (every point at the camera) is refused as on the
    command line, with the same message."""
    with pytest.raises(ValueError, match=r"disparity_correction offset 1e9 px is outside -100\.\.100 px"):
        swarmpose.Odometry(**KITTI_CAMERA, disparity_correction=(1e9, 0.0))
    with pytest.raises(ValueError, match="finite"):
        swarmpose.Odometry(**KITTI_CAMERA, disparity_correction=(0.0, float("nan")))


def test_a_run_configuration_reruns_the_run(kitti_seq2, swarmpose_bin, tmp_path):
    """The ``config.json`` a command-line run writes, given as ``config_file=``, gives
    that run's trajectory and the same configuration text; keywords given beside it
    replace its settings; a misspelt setting is refused, naming itself."""
    out = tmp_path / "cli"
    subprocess.run([str(swarmpose_bin), "odometry", str(kitti_seq2), "--out", str(out),
                    "--quiet", "--window", "3", "--seed", "4", "--method", "msac",
                    "--calibrate", "none"], check=True, capture_output=True)
    cli = read_kitti(out / "trajectory.kitti.txt")
    run = swarmpose.odometry(kitti_seq2, config_file=out / "config.json")
    assert np.max(np.abs(run.poses - cli)) < 1e-12
    assert run.config_json == (out / "config.json").read_text(encoding="utf-8")
    saved = tmp_path / "python.json"
    saved.write_text(run.config_json, encoding="utf-8")
    again = swarmpose.odometry(kitti_seq2, config_file=saved, seed=5)
    assert '"seed": 5' in again.config_json and '"method": "msac"' in again.config_json
    assert np.max(np.abs(again.poses - run.poses)) > 0
    bad = tmp_path / "bad.json"
    bad.write_text('{"odometry": {"windw": 3}}', encoding="utf-8")
    with pytest.raises(ValueError, match="unknown field `windw`"):
        swarmpose.odometry(kitti_seq2, config_file=bad)


def test_the_split_check_per_frame(kitti_seq2):
    """``split_check=True`` gives each tracked frame its split-feature check: the motion
    difference of the two halves, its covariance (symmetric), and the NEES that is that
    difference normalised by it, at most the model's alone (``model_nees``: the
    systematic floor only widens); without it, ``Frame.split`` is ``None``."""
    seq = swarmpose.Sequence(kitti_seq2)
    checked = swarmpose.Odometry.from_sequence(kitti_seq2, split_check=True, window=0)
    plain = swarmpose.Odometry.from_sequence(kitti_seq2, window=0)
    splits = []
    for i in range(6):
        left, right = seq[i]
        frame = checked.track(left, right, 0.1 * i)
        assert plain.track(left, right, 0.1 * i).split is None
        if frame.split is not None:
            splits.append(frame.split)
    assert len(splits) >= 4
    for s in splits:
        d, c = s["difference"], s["covariance"]
        assert d.shape == (6,) and c.shape == (6, 6) and np.allclose(c, c.T)
        assert s["nees"] == pytest.approx(d @ np.linalg.solve(c, d), rel=1e-6)
        # The floor only widens the model's covariance.
        assert s["nees"] <= s["model_nees"] * (1 + 1e-9)
        assert min(s["inliers"]) > 0
