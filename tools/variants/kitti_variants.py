#!/usr/bin/env python3
"""Writes variants of a KITTI-layout stereo sequence that are still exact stereo sequences
with exact ground truth, so that the odometry can be checked on motions and scenes the
defaults were never looked at on:

* ``reversed``: the frames in reverse order (the car drives backwards through the same
  street, turning the other way).
* ``mirrored``: every image flipped left to right and the two cameras swapped (the new left
  camera is the old right one seen in a mirror): a world mirrored in x, so a right turn
  becomes a left turn. The principal point moves to ``width - 1 - cx``; a disparity
  ``u_left - u_right`` is unchanged, so a disparity error of the rig stays the same.
* ``mirrored-reversed``: both.
* ``first-half`` / ``second-half``: frames 0..n/2 and n/2..n-1, each from its own start.
* ``every-2nd``: every other frame (half the frame rate).

Images are symbolic links (or flipped copies for the mirrored variants); the ground truth is
``poses.txt`` (the pose of the left camera of frame i in the left camera frame of frame 0,
row-major 3x4). The calibration is ``calib.txt`` with ``P0:`` and ``P1:``.

    python3 tools/variants/kitti_variants.py SRC DST_DIR [--only NAME ...]
"""

import argparse
import os
import sys

import numpy as np

VARIANTS = ["reversed", "mirrored", "mirrored-reversed", "first-half", "second-half", "every-2nd"]


def read_calib(path):
    rows = {}
    for line in open(path):
        parts = line.split()
        if not parts:
            continue
        key = parts[0].rstrip(":") if parts[0].endswith(":") else f"P{len(rows)}"
        nums = [float(v) for v in (parts[1:] if parts[0].endswith(":") else parts)]
        rows[key] = np.array(nums).reshape(3, 4)
    return rows["P0"], rows["P1"]


def read_poses(path):
    out = []
    for line in open(path):
        v = [float(x) for x in line.split()]
        if len(v) == 12:
            t = np.eye(4)
            t[:3, :] = np.array(v).reshape(3, 4)
            out.append(t)
    return out


def write_poses(path, poses):
    with open(path, "w") as f:
        for t in poses:
            f.write(" ".join(f"{x:.12e}" for x in t[:3, :].reshape(-1)) + "\n")


def rebase(poses):
    inv0 = np.linalg.inv(poses[0])
    return [inv0 @ p for p in poses]


def frames_of(src):
    return sorted(f for f in os.listdir(os.path.join(src, "image_0")) if f.endswith(".png"))


def write_sequence(dst, calib_lines, items):
    """items: (left source, right source, flip) per frame, in order. OpenCV is needed
    only for flipped (mirrored) frames; the other variants are links."""
    if any(flip for _, _, flip in items):
        import cv2

    for cam in ("image_0", "image_1"):
        os.makedirs(os.path.join(dst, cam), exist_ok=True)
    for i, (left, right, flip) in enumerate(items):
        name = f"{i:06d}.png"
        for cam, src in (("image_0", left), ("image_1", right)):
            out = os.path.join(dst, cam, name)
            if os.path.lexists(out):
                os.remove(out)
            if flip:
                img = cv2.imread(src, cv2.IMREAD_UNCHANGED)
                if img is None:
                    sys.exit(f"cannot read {src}")
                cv2.imwrite(out, cv2.flip(img, 1))
            else:
                os.symlink(os.path.abspath(src), out)
    with open(os.path.join(dst, "calib.txt"), "w") as f:
        f.write(calib_lines)


def calib_text(p0, p1):
    return "".join(f"{k}: " + " ".join(f"{x:.12e}" for x in p.reshape(-1)) + "\n"
                   for k, p in (("P0", p0), ("P1", p1)))


def make(src, dst, name):
    p0, p1 = read_calib(os.path.join(src, "calib.txt"))
    poses = read_poses(os.path.join(src, "poses.txt"))
    frames = frames_of(src)
    n = len(frames)
    if len(poses) != n:
        sys.exit(f"{src}: {n} frames but {len(poses)} poses")
    left = [os.path.join(src, "image_0", f) for f in frames]
    right = [os.path.join(src, "image_1", f) for f in frames]
    order = list(range(n))
    mirror = name.startswith("mirrored")
    if "reversed" in name:
        order = order[::-1]
    elif name == "first-half":
        order = order[: n // 2 + 1]
    elif name == "second-half":
        order = order[n // 2:]
    elif name == "every-2nd":
        order = order[::2]
    if mirror:
        import cv2

        width = cv2.imread(left[0], cv2.IMREAD_UNCHANGED).shape[1]
        fx = p0[0, 0]
        baseline = -p1[0, 3] / fx
        q0 = p0.copy()
        q0[0, 2] = width - 1 - p0[0, 2]
        q1 = q0.copy()
        q1[0, 3] = -fx * baseline
        # The new left camera is the old right camera (at +baseline in x of the old
        # left), mirrored: M B^-1 P B M with M = diag(-1, 1, 1, 1).
        b = np.eye(4)
        b[0, 3] = baseline
        m = np.diag([-1.0, 1.0, 1.0, 1.0])
        poses = [m @ np.linalg.inv(b) @ p @ b @ m for p in poses]
        items = [(right[i], left[i], True) for i in order]
        calib = calib_text(q0, q1)
    else:
        items = [(left[i], right[i], False) for i in order]
        calib = calib_text(p0, p1)
    write_sequence(dst, calib, items)
    write_poses(os.path.join(dst, "poses.txt"), rebase([poses[i] for i in order]))
    return len(order)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("src")
    ap.add_argument("dst_dir")
    ap.add_argument("--only", nargs="*", choices=VARIANTS)
    a = ap.parse_args()
    for name in a.only or VARIANTS:
        dst = os.path.join(a.dst_dir, name)
        k = make(a.src, dst, name)
        print(f"{dst}: {k} frames")


if __name__ == "__main__":
    main()
