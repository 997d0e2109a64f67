#!/usr/bin/env python3
"""The KITTI odometry devkit's segment errors, written again with numpy alone: the
independent check of `swarmpose evaluate --kitti-segments` (and of
`swarmpose.kitti_segments`).

A line-by-line reading of the devkit's `evaluate_odometry.cpp` (KITTI odometry benchmark):

* `trajectoryDistances`: `dist[0] = 0`, `dist[i] = dist[i-1] + |t_i - t_(i-1)|` over the
  ground-truth positions.
* `lastFrameFromSegmentLength(dist, first, len)`: the first `i >= first` with
  `dist[i] > dist[first] + len`, or none.
* `calcSequenceErrors`: for `first` = 0, 10, 20, ... (`step_size = 10`) and each length
  100, 200, ..., 800 m with a last frame: `pose_error = inv(inv(P_first) P_last) *
  (inv(Q_first) Q_last)` (P the estimate, Q the ground truth, 4x4), the rotation error
  `acos(max(min(0.5 (trace(R) - 1), 1), -1)) / len` (rad/m) and translation error
  `|t(pose_error)| / len` (a ratio).
* The figures: the mean over the segments of each length (`saveErrorPlots`) and over all
  segments (`saveStats`); the published table reports the translation ratio x 100 (%)
  and the rotation in deg/m x 100 (deg/100 m).

By default each 3x3 block is first replaced by its nearest rotation (SVD), as
swarmpose's readers do; `--raw` uses the blocks as read, as the devkit does, and
`--float32` accumulates the distances in single precision, as the devkit does (its
`dist` is a `vector<float>`). README.md says how far those choices move the figures.

    python3 kitti_segments.py ESTIMATE GROUND_TRUTH [--scale F] [--raw] [--float32] [--json]
"""

import argparse
import json
import sys

import numpy as np

LENGTHS_M = (100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0)
STEP_FRAMES = 10


def read_kitti(path):
    """(N, 4, 4) poses of a KITTI trajectory file (12 numbers a line, row-major [R|t])."""
    rows = np.loadtxt(path, ndmin=2)
    if rows.shape[1] != 12:
        raise ValueError(f"{path}: {rows.shape[1]} numbers a line, 12 expected")
    poses = np.tile(np.eye(4), (len(rows), 1, 1))
    poses[:, :3, :] = rows.reshape(-1, 3, 4)
    return poses


def nearest_rotations(poses):
    """The poses with each 3x3 block replaced by the nearest rotation (Frobenius norm)."""
    out = poses.copy()
    u, _, vt = np.linalg.svd(poses[:, :3, :3])
    d = np.sign(np.linalg.det(u @ vt))
    u[:, :, 2] *= d[:, None]
    out[:, :3, :3] = u @ vt
    return out


def trajectory_distances(poses, float32=False):
    """Distance along the positions from the first, per frame (metres)."""
    if not float32:
        dist = [0.0]
        for i in range(1, len(poses)):
            d = poses[i - 1, :3, 3] - poses[i, :3, 3]
            dist.append(dist[-1] + float(np.sqrt(d @ d)))
        return np.array(dist)
    dist = [np.float32(0.0)]
    for i in range(1, len(poses)):
        dx, dy, dz = (poses[i - 1, :3, 3] - poses[i, :3, 3]).astype(np.float32)
        dist.append(np.float32(dist[-1] + np.sqrt(dx * dx + dy * dy + dz * dz)))
    return np.array(dist, dtype=np.float32)


def last_frame_from_segment_length(dist, first, length):
    """The first frame i >= first with dist[i] > dist[first] + length, or -1."""
    beyond = np.nonzero(dist[first:] > dist[first] + length)[0]
    return first + int(beyond[0]) if len(beyond) else -1


def rotation_error(pose_error):
    a, b, c = pose_error[0, 0], pose_error[1, 1], pose_error[2, 2]
    d = 0.5 * (a + b + c - 1.0)
    return float(np.arccos(max(min(d, 1.0), -1.0)))


def translation_error(pose_error):
    return float(np.linalg.norm(pose_error[:3, 3]))


def sequence_errors(gt, est, scale=1.0, float32=False):
    """Every segment: (first, last, length_m, translation ratio, rotation rad/m)."""
    dist = trajectory_distances(gt, float32)
    errors = []
    for first in range(0, len(gt), STEP_FRAMES):
        for length in LENGTHS_M:
            length = length * scale
            last = last_frame_from_segment_length(dist, first, length)
            if last == -1:
                continue
            delta_gt = np.linalg.inv(gt[first]) @ gt[last]
            delta_est = np.linalg.inv(est[first]) @ est[last]
            pose_error = np.linalg.inv(delta_est) @ delta_gt
            errors.append((first, last, length, translation_error(pose_error) / length,
                           rotation_error(pose_error) / length))
    return errors


def summary(errors, scale=1.0):
    """Per length and over all segments, in the published units (%, deg/100 m)."""
    def figures(errs):
        t = np.mean([e[3] for e in errs])
        r = np.mean([e[4] for e in errs])
        return 100.0 * t, 100.0 * np.degrees(r)

    per_length = []
    for length in LENGTHS_M:
        length = length * scale
        errs = [e for e in errors if e[2] == length]
        if errs:
            t, r = figures(errs)
            per_length.append({"length_m": length, "n": len(errs), "translation_percent": t,
                               "rotation_deg_per_100m": r})
    t, r = figures(errors) if errors else (None, None)
    return {"scale": scale, "translation_percent": t, "rotation_deg_per_100m": r,
            "per_length": per_length,
            "segments": [{"first_frame": f, "last_frame": l, "length_m": ln,
                          "translation_percent": 100.0 * te,
                          "rotation_deg_per_100m": 100.0 * np.degrees(re)}
                         for f, l, ln, te, re in sorted(errors, key=lambda e: (e[2], e[0]))]}


def evaluate(estimate_path, ground_truth_path, scale=1.0, raw=False, float32=False):
    """The summary of ESTIMATE against GROUND_TRUTH (KITTI files, paired by line)."""
    est, gt = read_kitti(estimate_path), read_kitti(ground_truth_path)
    if len(est) != len(gt):
        raise ValueError(f"{len(est)} estimated poses, {len(gt)} ground-truth poses")
    if not raw:
        est, gt = nearest_rotations(est), nearest_rotations(gt)
    return summary(sequence_errors(gt, est, scale, float32), scale)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("estimate")
    p.add_argument("ground_truth")
    p.add_argument("--scale", type=float, default=1.0, help="factor of the lengths, in (0, 1]")
    p.add_argument("--raw", action="store_true", help="the 3x3 blocks as read (the devkit)")
    p.add_argument("--float32", action="store_true", help="distances in single precision (the devkit)")
    p.add_argument("--json", action="store_true")
    a = p.parse_args()
    if not (0.0 < a.scale <= 1.0):
        sys.exit(f"--scale {a.scale}: a factor in (0, 1] expected")
    s = evaluate(a.estimate, a.ground_truth, a.scale, a.raw, a.float32)
    if a.json:
        print(json.dumps(s))
        return
    if a.scale != 1.0:
        print(f"NOTE: lengths x {a.scale}: not the KITTI benchmark's figures")
    print(f"{'length m':>10} {'segments':>9} {'translation %':>16} {'rotation deg/100 m':>20}")
    for row in s["per_length"]:
        print(f"{row['length_m']:>10.1f} {row['n']:>9} {row['translation_percent']:>16.6f} "
              f"{row['rotation_deg_per_100m']:>20.6f}")
    if s["translation_percent"] is not None:
        print(f"{'all':>10} {len(s['segments']):>9} {s['translation_percent']:>16.6f} "
              f"{s['rotation_deg_per_100m']:>20.6f}")


if __name__ == "__main__":
    main()
