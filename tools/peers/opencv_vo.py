#!/usr/bin/env python3
"""A plain OpenCV stereo visual odometry: the peer swarmpose's odometry is compared with.

One configuration for every sequence, one thread: 3000 ORB features per image, the
strongest of each cell of a 4 x 12 grid, row stereo matching (Hamming distance,
candidates within 1.5 rows and 250 px of disparity, ratio test and left-right check),
triangulation with the calibration as given (no disparity correction; ORB's keypoint
positions, no sub-pixel refinement: a parabola fit on SSD made the drift worse here),
frame-to-frame matching of the previous frame's 3D points nearer than 30 m with every
current left keypoint (ratio test, one to one), cv2.solvePnPRansac (EPnP, 2 px) then
cv2.solvePnPRefineLM on the inliers; constant velocity when a pair fails. These are the
settings of ../shared/peers/opencv_pnp_vo.py (its "pnp" pipeline), written independently.

Reads the three shared layouts (KITTI odometry, Karlsruhe, EuRoC MAV: raw images
undistorted and rectified with cv2.stereoRectify). Writes the trajectory (the pose of the
left camera of frame i in the left camera frame of frame 0; x right, y down, z forward;
metres) in KITTI and TUM formats and prints one JSON line with the timing.

    python3 opencv_vo.py SEQUENCE_DIR OUT_DIR
"""

import glob
import json
import os
import sys
import time

import cv2
import numpy as np

cv2.setNumThreads(1)
# solvePnPRansac draws its samples from OpenCV's global generator: seeded, so that every
# run gives the same trajectory.
cv2.setRNGSeed(0)

# The one configuration: that of a competent OpenCV stereo PnP pipeline (the settings of
# ../shared/peers/opencv_pnp_vo.py, written here independently): 3000 ORB features per
# image spread over a 4 x 12 grid, PnP only on points nearer than 30 m (depth noise grows
# as Z^2, far points bias the scale), a 2 px RANSAC threshold, then Levenberg-Marquardt.
N_FEATURES = 3000          # ORB features kept per image after bucketing
GRID = (4, 12)             # bucketing cells down and across the image
ROW_TOLERANCE_PX = 1.5     # stereo candidates within this many rows
MAX_DISPARITY_PX = 250.0   # largest disparity
RATIO = 0.8                # Lowe's ratio test (stereo and temporal)
MAX_HAMMING = 64           # largest descriptor distance of a match
MAX_DEPTH_M = 30.0         # PnP uses the previous frame's points nearer than this
PNP_REPROJECTION_PX = 2.0  # RANSAC inlier threshold
PNP_ITERATIONS = 300
MIN_INLIERS = 6


def read_kitti(seq):
    calib = {}
    for line in open(os.path.join(seq, "calib.txt")):
        if ":" in line:
            k, v = line.split(":", 1)
            calib[k.strip()] = np.array([float(x) for x in v.split()]).reshape(3, 4)
    p0, p1 = calib["P0"], calib["P1"]
    K = p0[:, :3]
    baseline = -p1[0, 3] / p1[0, 0]
    left = sorted(glob.glob(os.path.join(seq, "image_0", "*.png")))
    right = sorted(glob.glob(os.path.join(seq, "image_1", "*.png")))
    frames = [(lambda a=a, b=b: (cv2.imread(a, 0), cv2.imread(b, 0))) for a, b in zip(left, right)]
    return K, baseline, frames


def read_karlsruhe(seq):
    calib = {}
    for line in open(os.path.join(seq, "calib.txt")):
        k, _, v = line.partition(":")
        if k.strip() in ("P1_roi", "P2_roi"):
            calib[k.strip()] = [float(x) for x in v.split()]
    p1 = np.array(calib["P1_roi"]).reshape(3, 4)
    p2 = np.array(calib["P2_roi"]).reshape(3, 4)
    K = p1[:, :3]
    baseline = -p2[0, 3] / p2[0, 0]
    img = glob.glob(os.path.join(seq, "*_Images"))[0]
    left = sorted(glob.glob(os.path.join(img, "I1_*.png")))
    right = sorted(glob.glob(os.path.join(img, "I2_*.png")))
    frames = [(lambda a=a, b=b: (cv2.imread(a, 0), cv2.imread(b, 0))) for a, b in zip(left, right)]
    return K, baseline, frames


def _yaml_cam(path):
    text = open(path).read()

    def numbers(key):
        i = text.index(key)
        j = text.index("[", i)
        k = text.index("]", j)
        return [float(x) for x in text[j + 1:k].replace("\n", " ").split(",")]

    T = np.array(numbers("data:")).reshape(4, 4)
    fu, fv, cu, cv = numbers("intrinsics:")
    dist = np.array(numbers("distortion_coefficients:"))
    w, h = [int(x) for x in numbers("resolution:")]
    return T, np.array([[fu, 0, cu], [0, fv, cv], [0, 0, 1]]), dist, (w, h)


def read_euroc(seq):
    cams = [os.path.join(seq, "mav0", c) for c in ("cam0", "cam1")]
    (T0, K0, d0, size), (T1, K1, d1, _) = [_yaml_cam(os.path.join(c, "sensor.yaml")) for c in cams]
    T01 = np.linalg.inv(T1) @ T0  # cam0 -> cam1
    R1, R2, P1, P2, _, _, _ = cv2.stereoRectify(K0, d0, K1, d1, size, T01[:3, :3].copy(), T01[:3, 3].reshape(3, 1).copy(), alpha=0)
    m0 = cv2.initUndistortRectifyMap(K0, d0, R1, P1, size, cv2.CV_32FC1)
    m1 = cv2.initUndistortRectifyMap(K1, d1, R2, P2, size, cv2.CV_32FC1)
    K = P1[:, :3]
    baseline = -P2[0, 3] / P2[0, 0]
    names = sorted(os.listdir(os.path.join(cams[0], "data")))

    def load(n):
        a = cv2.imread(os.path.join(cams[0], "data", n), 0)
        b = cv2.imread(os.path.join(cams[1], "data", n), 0)
        return (cv2.remap(a, *m0, cv2.INTER_LINEAR), cv2.remap(b, *m1, cv2.INTER_LINEAR))

    frames = [(lambda n=n: load(n)) for n in names]
    return K, baseline, frames


def read_sequence(seq):
    if os.path.isdir(os.path.join(seq, "image_0")):
        return read_kitti(seq)
    if os.path.isdir(os.path.join(seq, "mav0")):
        return read_euroc(seq)
    if glob.glob(os.path.join(seq, "*_Images")):
        return read_karlsruhe(seq)
    raise SystemExit(f"{seq}: not a KITTI, Karlsruhe or EuRoC sequence")


class Frontend:
    def __init__(self, size):
        w, h = size
        self.size = size
        # Detect twice the features, keep the strongest per grid cell.
        self.orb = cv2.ORB_create(nfeatures=2 * N_FEATURES, scaleFactor=1.2, nlevels=8,
                                  edgeThreshold=31, fastThreshold=12)
        self.per_cell = int(np.ceil(N_FEATURES / (GRID[0] * GRID[1])))
        self.matcher = cv2.BFMatcher(cv2.NORM_HAMMING)

    def features(self, img):
        """Bucketed ORB keypoints (pixels) and descriptors of one image."""
        w, h = self.size
        kps = self.orb.detect(img, None)
        cells = {}
        for i, k in enumerate(kps):
            c = (min(int(k.pt[1] * GRID[0] / h), GRID[0] - 1), min(int(k.pt[0] * GRID[1] / w), GRID[1] - 1))
            cells.setdefault(c, []).append(i)
        keep = []
        for idx in cells.values():
            idx.sort(key=lambda i: -kps[i].response)
            keep.extend(idx[:self.per_cell])
        kps, des = self.orb.compute(img, [kps[i] for i in sorted(keep)])
        if des is None or not kps:
            return np.zeros((0, 2)), np.zeros((0, 32), np.uint8)
        return np.array([k.pt for k in kps]), des

    def stereo(self, left, right):
        """Every left keypoint (pixels) and descriptor, and the stereo matches among them
        (left index, disparity in pixels): the best row candidate by Hamming distance,
        ratio test, left-right check, so one to one."""
        pl, dl = self.features(left)
        pr, dr = self.features(right)
        empty = (pl, dl, np.zeros(0, int), np.zeros(0))
        if len(pl) == 0 or len(pr) == 0:
            return empty
        dy = np.abs(pl[:, 1][:, None] - pr[:, 1][None, :])
        disp = pl[:, 0][:, None] - pr[:, 0][None, :]
        mask = ((dy <= ROW_TOLERANCE_PX) & (disp > 0.0) & (disp <= MAX_DISPARITY_PX)).astype(np.uint8)
        fwd = self.matcher.knnMatch(dl, dr, k=2, mask=mask)
        back = self.matcher.knnMatch(dr, dl, k=1, mask=mask.T.copy())
        back_best = {m[0].queryIdx: m[0].trainIdx for m in back if m}
        keep = []
        for m in fwd:
            if not m:
                continue
            best = m[0]
            if best.distance > MAX_HAMMING:
                continue
            if len(m) > 1 and best.distance >= RATIO * m[1].distance:
                continue
            if back_best.get(best.trainIdx) != best.queryIdx:
                continue
            keep.append((best.queryIdx, best.trainIdx))
        if not keep:
            return empty
        li = np.array([a for a, _ in keep])
        ri = np.array([b for _, b in keep])
        return pl, dl, li, pl[li, 0] - pr[ri, 0]


def triangulate(K, baseline, pl, disparity):
    d = disparity
    z = K[0, 0] * baseline / d
    x = (pl[:, 0] - K[0, 2]) * z / K[0, 0]
    y = (pl[:, 1] - K[1, 2]) * z / K[1, 1]
    return np.stack([x, y, z], axis=1)


def run(seq, out):
    K, baseline, frames = read_sequence(seq)
    os.makedirs(out, exist_ok=True)
    poses = [np.eye(4)]
    velocity = np.eye(4)
    times, fallbacks = [], 0
    prev = None
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING)
    frontend = None
    t_all = time.perf_counter()
    for i, load in enumerate(frames):
        t0 = time.perf_counter()
        left, right = load()
        t1 = time.perf_counter()
        if frontend is None:
            frontend = Frontend((left.shape[1], left.shape[0]))
        pl, desc, li, disparity = frontend.stereo(left, right)
        points = triangulate(K, baseline, pl[li], disparity) if len(li) else np.zeros((0, 3))
        near = points[:, 2] < MAX_DEPTH_M
        if prev is not None:
            ok = False
            p_points, p_desc = prev
            if len(p_desc) >= MIN_INLIERS and len(desc) >= MIN_INLIERS:
                # The previous frame's near 3D points against every current left keypoint:
                # ratio test, then one to one (the closest previous point per keypoint).
                m = matcher.knnMatch(p_desc, desc, k=2)
                good = [a for a in (x for x in m if len(x) == 2)
                        if a[0].distance <= MAX_HAMMING and a[0].distance < RATIO * a[1].distance]
                best = {}
                for g in good:
                    j = g[0].trainIdx
                    if j not in best or g[0].distance < best[j][0].distance:
                        best[j] = g
                good = sorted(best.values(), key=lambda g: g[0].queryIdx)
                if len(good) >= MIN_INLIERS:
                    obj = np.array([p_points[g[0].queryIdx] for g in good], dtype=np.float64)
                    img = np.array([pl[g[0].trainIdx] for g in good], dtype=np.float64)
                    found, rvec, tvec, inl = cv2.solvePnPRansac(
                        obj, img, K, None, iterationsCount=PNP_ITERATIONS,
                        reprojectionError=PNP_REPROJECTION_PX, confidence=0.999,
                        flags=cv2.SOLVEPNP_EPNP)
                    if found and inl is not None and len(inl) >= MIN_INLIERS:
                        inl = inl[:, 0]
                        rvec, tvec = cv2.solvePnPRefineLM(obj[inl], img[inl], K, None, rvec, tvec)
                        R, _ = cv2.Rodrigues(rvec)
                        T = np.eye(4)
                        T[:3, :3], T[:3, 3] = R, tvec[:, 0]
                        velocity = np.linalg.inv(T)  # pose of camera i in camera i-1
                        ok = True
            if not ok:
                fallbacks += 1
            poses.append(poses[-1] @ velocity)
        prev = (points[near], desc[li][near] if len(li) else desc[:0])
        t2 = time.perf_counter()
        times.append((t1 - t0, t2 - t1))
    wall = time.perf_counter() - t_all
    with open(os.path.join(out, "trajectory.kitti.txt"), "w") as f:
        for P in poses:
            f.write(" ".join(f"{v:.12e}" for v in P[:3, :].reshape(-1)) + "\n")
    n = len(times)
    load = sum(t[0] for t in times)
    work = sum(t[1] for t in times)
    print(json.dumps({
        "sequence": seq, "frames": n, "fallbacks": fallbacks,
        "frames_per_s": n / wall, "frames_per_s_without_loading": n / work,
        "load_ms": 1e3 * load / n, "pipeline_ms": 1e3 * work / n,
    }))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    run(sys.argv[1], sys.argv[2])
