"""swarmpose.register against Open3D's registration_ransac_based_on_correspondence on
the same numpy arrays: matched 3D points with a known motion, Gaussian noise and a
growing share of wrong matches.

Prints, per outlier share, each method's rotation error (degrees), translation error
(metres), inliers found and time (milliseconds). Skipped (exit 0, with a message) when
Open3D is not installed: `pip install open3d`.

Usage: python examples/open3d_compare.py [-n 600] [--noise 0.01] [--seed 0]
"""

import argparse
import sys
import time

import numpy as np

import swarmpose


def rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def scene(n, outliers, noise, rng):
    """Points at 2-20 m in front of a camera, a known motion, wrong matches."""
    r = rotation(rng.normal(size=3), rng.uniform(0.05, 0.5))
    t = rng.uniform(-1, 1, size=3)
    src = rng.uniform([-8, -3, 2], [8, 3, 20], size=(n, 3))
    dst = src @ r.T + t + rng.normal(0, noise, size=(n, 3))
    bad = rng.choice(n, int(round(outliers * n)), replace=False)
    dst[bad] = rng.uniform([-8, -3, 2], [8, 3, 20], size=(len(bad), 3))
    return src, dst, r, t


def errors(transform, r, t):
    c = (np.trace(transform[:3, :3].T @ r) - 1) / 2
    return np.degrees(np.arccos(np.clip(c, -1, 1))), np.linalg.norm(transform[:3, 3] - t)


def open3d_register(o3d, src, dst, threshold, seed):
    reg = o3d.pipelines.registration
    o3d.utility.random.seed(seed)
    a = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(src))
    b = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(dst))
    pairs = np.stack([np.arange(len(src))] * 2, axis=1).astype(np.int32)
    result = reg.registration_ransac_based_on_correspondence(
        a, b, o3d.utility.Vector2iVector(pairs), threshold,
        reg.TransformationEstimationPointToPoint(False), 3, [],
        reg.RANSACConvergenceCriteria(100000, 0.999))
    return np.asarray(result.transformation), len(result.correspondence_set)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-n", type=int, default=600, help="correspondences")
    p.add_argument("--noise", type=float, default=0.01, help="noise sigma per axis, metres")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args()
    try:
        import open3d as o3d
    except ImportError as e:
        # Not installed, or installed without its system libraries (libusb, libGL, ...).
        print(f"skipped: open3d is not installed or cannot be loaded ({e}); pip install open3d")
        return 0
    threshold = 3 * args.noise * np.sqrt(3)  # metres, for Open3D and swarmpose alike
    print(f"swarmpose {swarmpose.__version__} vs open3d {o3d.__version__}: {args.n} "
          f"correspondences, noise {args.noise} m, inlier threshold {threshold:.3f} m, seed {args.seed}")
    print(f"{'outliers':>8} {'method':>9} {'rot err deg':>12} {'trans err m':>12} "
          f"{'inliers':>8} {'ms':>8}")
    rng = np.random.default_rng(args.seed)
    for share in (0.0, 0.5, 0.8, 0.9):
        src, dst, r, t = scene(args.n, share, args.noise, rng)
        runs = []
        start = time.perf_counter()
        e = swarmpose.register(src, dst, threshold=threshold, seed=args.seed)
        runs.append(("swarmpose", e.transform, len(e.inliers), time.perf_counter() - start))
        start = time.perf_counter()
        m, inliers = open3d_register(o3d, src, dst, threshold, args.seed)
        runs.append(("open3d", m, inliers, time.perf_counter() - start))
        for name, m, inliers, seconds in runs:
            dr, dt = errors(m, r, t)
            print(f"{share:8.0%} {name:>9} {dr:12.4f} {dt:12.4f} {inliers:8d} {seconds * 1e3:8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
