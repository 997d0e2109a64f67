"""Offset vs scale discrimination using the GT motion directly (no pose estimation).
For every tracked point (L_i -> L_{i+1}, fb-checked) with NCC disparities d0 (frame i) and d1 (frame i+1):
 model 'offset o':   X0 = tri(u0, d0+o);  X1 = M X0;  predicted d1 = f b / Z1 - o
 model 'scale s':    X0 = tri(u0, d0);    X1 = R X0 + s t;  predicted d1 = f b / Z1
Residuals pooled over all pairs. Also PnP ratio per disparity band (near vs far points).
Saves per-point arrays to gtc.npz."""
import numpy as np, cv2
from common import *

fx, cx, cy, b = calib()
K = np.array([[fx, 0, cx], [0, fx, cy], [0, 0, 1.0]])
T = poses()
lk = dict(winSize=(21, 21), maxLevel=4, criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 0.001))


def tri(p, d):
    Z = fx * b / d
    return np.c_[(p[:, 0] - cx) * Z / fx, (p[:, 1] - cy) * Z / fx, Z]


rows = []
bands = [(3, 8), (8, 15), (15, 30), (30, 200)]
band_ratio = {bd: [] for bd in bands}
for i in range(N - 1):
    L0, R0, L1, R1 = img(0, i), img(1, i), img(0, i + 1), img(1, i + 1)
    p0 = corners(L0)
    d0, _ = ncc_row_match(L0, R0, p0, dmin=-5)
    q, st, _ = cv2.calcOpticalFlowPyrLK(L0, L1, p0.reshape(-1, 1, 2), None, **lk)
    qb, st2, _ = cv2.calcOpticalFlowPyrLK(L1, L0, q, None, **lk)
    q = q.reshape(-1, 2)
    fb = np.linalg.norm(qb.reshape(-1, 2) - p0, axis=1)
    ok = (st.ravel() == 1) & (st2.ravel() == 1) & (fb < 0.2) & np.isfinite(d0) & (d0 > 2)
    ok &= (q[:, 0] > 10) & (q[:, 0] < L1.shape[1] - 10) & (q[:, 1] > 10) & (q[:, 1] < L1.shape[0] - 10)
    P0, D0, Q = p0[ok], d0[ok], q[ok]
    D1, _ = ncc_row_match(L1, R1, Q, dmin=-5)
    M = gt_rel(T, i, i + 1)
    g = np.isfinite(D1)
    for a, bb, c, e in zip(P0[g], D0[g], Q[g], D1[g]):
        rows.append([i, a[0], a[1], bb, c[0], c[1], e])
    # PnP per disparity band (using all-band RANSAC inliers)
    X = tri(P0, D0)
    _, rv, tv, inl = cv2.solvePnPRansac(X, Q, K, None, iterationsCount=500, reprojectionError=1.0, confidence=0.999)
    inl = inl.ravel()
    tg = np.linalg.norm(M[:3, 3])
    for bd in bands:
        s = inl[(D0[inl] >= bd[0]) & (D0[inl] < bd[1])]
        if len(s) >= 15:
            rvk, tvk = cv2.solvePnPRefineLM(X[s], Q[s], K, None, rv.copy(), tv.copy())
            band_ratio[bd].append(np.linalg.norm(tvk) / tg)
    print(i, len(P0), g.sum(), flush=True)

A = np.array(rows)
np.savez('gtc.npz', A=A)
print('PnP translation ratio by disparity band of the 3D points (median, IQR, n pairs):')
for bd in bands:
    r = np.array(band_ratio[bd])
    if len(r):
        print(f'  d in [{bd[0]},{bd[1]}) px  (Z {fx*b/bd[1]:.0f}-{fx*b/bd[0]:.0f} m): median {np.median(r):.4f} IQR {np.percentile(r,[25,75]).round(4)} n={len(r)}')
