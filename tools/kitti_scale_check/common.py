"""Shared helpers for the KITTI scale investigation (independent of swarmpose)."""
import numpy as np, cv2

import os
D = os.path.join(os.environ.get('SWARMPOSE_DATA') or os.path.join(os.path.dirname(os.path.abspath(__file__)), '../../../shared/data'), 'kitti_vo_seq2')
N = 51


def calib():
    P = {}
    for line in open(f'{D}/calib.txt'):
        k, v = line.split(':')
        P[k] = np.array([float(x) for x in v.split()]).reshape(3, 4)
    P0, P1 = P['P0'], P['P1']
    fx, cx, cy = P0[0, 0], P0[0, 2], P0[1, 2]
    b = -P1[0, 3] / P1[0, 0]
    return fx, cx, cy, b


def poses():
    T = []
    for line in open(f'{D}/poses.txt'):
        m = np.eye(4)
        m[:3, :] = np.array([float(x) for x in line.split()]).reshape(3, 4)
        T.append(m)
    return T


def img(side, i):
    return cv2.imread(f'{D}/image_{side}/{i:06d}.png', cv2.IMREAD_GRAYSCALE)


def gt_rel(T, i, j):
    """Transform mapping points in camera-i coords to camera-j coords: X_j = M X_i."""
    return np.linalg.inv(T[j]) @ T[i]


def rot_angle_deg(R):
    return np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)))


def ncc_row_match(L, R, pts, win=5, dmin=0, dmax=160):
    """For each left point (x,y) (float), find the right-image match on the same
    row by ZNCC over disparities [dmin,dmax] at integer steps, then parabola
    sub-pixel refinement. Patches are sampled with bilinear interpolation at the
    exact sub-pixel left position, and at x-d (same y) in the right image.
    Returns disparity (nan if rejected) and peak score."""
    Lf = L.astype(np.float32); Rf = R.astype(np.float32)
    H, W = L.shape
    out = np.full(len(pts), np.nan); score = np.zeros(len(pts))
    offs = np.arange(-win, win + 1, dtype=np.float32)
    for k, (x, y) in enumerate(pts):
        if y - win < 1 or y + win > H - 2 or x - win < 1 or x + win > W - 2:
            continue
        pl = cv2.getRectSubPix(Lf, (2 * win + 1, 2 * win + 1), (float(x), float(y)))
        pl = pl - pl.mean(); nl = np.sqrt((pl * pl).sum())
        if nl < 1e-3 * (2 * win + 1) ** 2:
            continue
        ds = np.arange(dmin, min(dmax, int(x - win - 2)) + 1)
        if ds.max() - dmin < 3: continue
        if len(ds) < 3:
            continue
        # strip of right image rows around y, sub-pixel in y handled by getRectSubPix
        xr0 = x - ds.max() - win
        wstrip = int(ds.max() - ds.min() + 2 * win + 1)
        strip = cv2.getRectSubPix(Rf, (wstrip, 2 * win + 1), (float(xr0 + (wstrip - 1) / 2), float(y)))
        sc = np.empty(len(ds))
        for j, d in enumerate(ds):
            c0 = int(ds.max() - d)
            pr = strip[:, c0:c0 + 2 * win + 1]
            pr = pr - pr.mean(); nr = np.sqrt((pr * pr).sum())
            sc[j] = (pl * pr).sum() / (nl * nr + 1e-9)
        j = int(np.argmax(sc))
        if j == 0 or j == len(ds) - 1 or sc[j] < 0.9:
            continue
        # uniqueness: second best peak away from the best
        mask = np.abs(np.arange(len(ds)) - j) > 2
        if mask.any() and sc[mask].max() > sc[j] - 0.02:
            continue
        a, b_, c = sc[j - 1], sc[j], sc[j + 1]
        den = a - 2 * b_ + c
        delta = 0.5 * (a - c) / den if den < 0 else 0.0
        out[k] = ds[j] + delta
        score[k] = sc[j]
    return out, score


def lk_stereo(L, R, pts, dinit=None):
    """LK (pyramidal, 2D) from left to right, with backward check; returns
    disparity and vertical difference (yL - yR)."""
    p0 = pts.reshape(-1, 1, 2).astype(np.float32)
    p1i = p0.copy()
    if dinit is not None:
        p1i[:, 0, 0] -= dinit
        flags = cv2.OPTFLOW_USE_INITIAL_FLOW
    else:
        flags = 0
    lk = dict(winSize=(21, 21), maxLevel=4, criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 0.001))
    p1, st, _ = cv2.calcOpticalFlowPyrLK(L, R, p0, p1i, flags=flags, **lk)
    pb, st2, _ = cv2.calcOpticalFlowPyrLK(R, L, p1, p0.copy(), flags=cv2.OPTFLOW_USE_INITIAL_FLOW, **lk)
    fb = np.linalg.norm((pb - p0).reshape(-1, 2), axis=1)
    ok = (st.ravel() == 1) & (st2.ravel() == 1) & (fb < 0.1)
    d = (p0 - p1).reshape(-1, 2)
    disp = np.where(ok, d[:, 0], np.nan)
    dy = np.where(ok, d[:, 1], np.nan)
    return disp, dy


def sgbm(L, R, ndisp=128, bs=5):
    m = cv2.StereoSGBM_create(minDisparity=0, numDisparities=ndisp, blockSize=bs,
                              P1=8 * bs * bs, P2=32 * bs * bs, disp12MaxDiff=1,
                              uniquenessRatio=10, speckleWindowSize=100, speckleRange=2,
                              mode=cv2.STEREO_SGBM_MODE_HH)
    d = m.compute(L, R).astype(np.float32) / 16.0
    d[d <= 0] = np.nan
    return d


def corners(L, n=3000, q=0.005, md=7):
    p = cv2.goodFeaturesToTrack(L, n, q, md, blockSize=5)
    p = cv2.cornerSubPix(L, p, (5, 5), (-1, -1), (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 40, 0.001))
    return p.reshape(-1, 2)
