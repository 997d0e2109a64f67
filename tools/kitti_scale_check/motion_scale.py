"""Check 2/3/5: scale of motion per consecutive pair with OpenCV-based pipeline.
 - stereo: GFTT+cornerSubPix corners in L_i, row-NCC + parabola disparities (also SGBM sampled)
 - temporal: LK L_i -> L_{i+1} with forward/backward check
 - PnP: solvePnPRansac (3D in frame i, 2D in frame i+1) + LM refine on inliers
 - 3D-3D: Arun/Umeyama (no scale) RANSAC, 3D in both frames
 - GT-consistency: offset o minimising disparity residual d_{i+1} vs prediction from d_i + GT motion
For disparity offsets o in a grid: d_true = d_meas + o.
Results saved to motion_scale.npz and printed."""
import numpy as np, cv2, sys
from common import *

fx, cx, cy, b = calib()
K = np.array([[fx, 0, cx], [0, fx, cy], [0, 0, 1.0]])
T = poses()
offs = np.round(np.arange(-1.0, 3.01, 0.1), 2)
DMIN = 3.0   # only points with measured disparity > 3 px (Z < ~129 m), same set for all offsets
rng = np.random.default_rng(0)
method = sys.argv[1] if len(sys.argv) > 1 else 'ncc'


def tri(p, d):
    Z = fx * b / d
    return np.c_[(p[:, 0] - cx) * Z / fx, (p[:, 1] - cy) * Z / fx, Z]


def umeyama(A, B):
    ma, mb = A.mean(0), B.mean(0)
    H = (A - ma).T @ (B - mb)
    U, S, Vt = np.linalg.svd(H)
    Dm = np.eye(3); Dm[2, 2] = np.sign(np.linalg.det(Vt.T @ U.T))
    R = Vt.T @ Dm @ U.T
    return R, mb - R @ ma


def proj(X):
    return np.c_[fx * X[:, 0] / X[:, 2] + cx, fx * X[:, 1] / X[:, 2] + cy, fx * b / X[:, 2]]


def wumeyama(A, B, w):
    w = w / w.sum()
    ma, mb = w @ A, w @ B
    H = ((A - ma) * w[:, None]).T @ (B - mb)
    U, S, Vt = np.linalg.svd(H)
    Dm = np.eye(3); Dm[2, 2] = np.sign(np.linalg.det(Vt.T @ U.T))
    R = Vt.T @ Dm @ U.T
    return R, mb - R @ ma


def ransac33(A, B, uvd_b, iters=1500, thr=1.5):
    """3-point RANSAC (Arun/Horn) scored by reprojection (u,v,d) in frame i+1; final fit = Umeyama
    without scale, weighted by inverse Z variance (w = 1/(Z0^4+Z1^4)), on inliers."""
    best = None; n = len(A)
    w = 1.0 / (A[:, 2] ** 4 + B[:, 2] ** 4)
    for _ in range(iters):
        s = rng.choice(n, 3, replace=False)
        R, t = umeyama(A[s], B[s])
        P = proj(A @ R.T + t)
        e = np.linalg.norm(P - uvd_b, axis=1)
        inl = e < thr
        if best is None or inl.sum() > best.sum():
            best = inl
    for _ in range(2):
        R, t = wumeyama(A[best], B[best], w[best])
        P = proj(A @ R.T + t); best = np.linalg.norm(P - uvd_b, axis=1) < thr
    R, t = wumeyama(A[best], B[best], w[best])
    return R, t, best


def stereo(L, R, p):
    if method == 'ncc':
        d, _ = ncc_row_match(L, R, p, dmin=-5)
    else:  # sgbm, bilinear-free nearest sampling
        S = sgbm(L, R)
        xi = np.clip(np.round(p[:, 0]).astype(int), 0, L.shape[1] - 1)
        yi = np.clip(np.round(p[:, 1]).astype(int), 0, L.shape[0] - 1)
        d = S[yi, xi]
    return d


lk = dict(winSize=(21, 21), maxLevel=4, criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 0.001))
npairs = N - 1
r_pnp = np.full((npairs, len(offs)), np.nan); r_33 = np.full((npairs, len(offs)), np.nan)
rot_pnp = np.full(npairs, np.nan); rot_33 = np.full(npairs, np.nan); gtstep = np.zeros(npairs)
ninl = np.zeros(npairs); o_gt = np.full(npairs, np.nan)
dir_err = np.full(npairs, np.nan)
for i in range(npairs):
    L0, R0, L1, R1 = img(0, i), img(1, i), img(0, i + 1), img(1, i + 1)
    p0 = corners(L0)
    d0 = stereo(L0, R0, p0)
    q, st, _ = cv2.calcOpticalFlowPyrLK(L0, L1, p0.reshape(-1, 1, 2), None, **lk)
    qb, st2, _ = cv2.calcOpticalFlowPyrLK(L1, L0, q, None, **lk)
    q = q.reshape(-1, 2)
    fb = np.linalg.norm(qb.reshape(-1, 2) - p0, axis=1)
    ok = (st.ravel() == 1) & (st2.ravel() == 1) & (fb < 0.2) & np.isfinite(d0) & (d0 > DMIN)
    ok &= (q[:, 0] > 10) & (q[:, 0] < L1.shape[1] - 10) & (q[:, 1] > 10) & (q[:, 1] < L1.shape[0] - 10)
    P0, D0, Q = p0[ok], d0[ok], q[ok]
    D1 = stereo(L1, R1, Q)
    M = gt_rel(T, i, i + 1)  # X_{i+1} = M X_i
    tg = np.linalg.norm(M[:3, 3]); gtstep[i] = tg
    # PnP with each offset (RANSAC inlier set from offset 0, then LM refine per offset)
    X = tri(P0, D0)
    okp, rv, tv, inl = cv2.solvePnPRansac(X, Q, K, None, iterationsCount=500, reprojectionError=1.0,
                                          confidence=0.999, flags=cv2.SOLVEPNP_ITERATIVE)
    inl = inl.ravel(); ninl[i] = len(inl)
    for k, o in enumerate(offs):
        Xo = tri(P0[inl], D0[inl] + o)
        rvk, tvk = cv2.solvePnPRefineLM(Xo, Q[inl], K, None, rv.copy(), tv.copy())
        r_pnp[i, k] = np.linalg.norm(tvk) / tg
        if abs(o) < 1e-9:
            Rk = cv2.Rodrigues(rvk)[0]
            rot_pnp[i] = rot_angle_deg(Rk.T @ M[:3, :3])
            dir_err[i] = np.degrees(np.arccos(np.clip(tvk.ravel() @ M[:3, 3] / (np.linalg.norm(tvk) * tg), -1, 1)))
    # 3D-3D (weighted Arun/Umeyama, no scale; RANSAC inliers from offset 0, refit per offset)
    g = np.isfinite(D1) & (D1 > DMIN)
    g33 = g & (D0 > 5) & (np.nan_to_num(D1) > 5)  # 3D-3D only with Z < ~77 m
    A0 = tri(P0[g33], D0[g33]); B0 = tri(Q[g33], D1[g33])
    _, _, in33 = ransac33(A0, B0, np.c_[Q[g33], D1[g33]])   # inlier set at offset 0
    for k, o in enumerate(offs):
        A = tri(P0[g33][in33], D0[g33][in33] + o); B = tri(Q[g33][in33], D1[g33][in33] + o)
        Rk, tk = wumeyama(A, B, 1.0 / (A[:, 2] ** 4 + B[:, 2] ** 4))
        r_33[i, k] = np.linalg.norm(tk) / tg
        if abs(o) < 1e-9:
            rot_33[i] = rot_angle_deg(Rk.T @ M[:3, :3])
    # GT-consistency offset: offset o for which the 3D points of frame i, moved by the GT motion,
    # reproject best onto the LK-tracked positions in L_{i+1} (median uv error over PnP inliers)
    best = (1e9, np.nan)
    for o in np.arange(-2, 4.001, 0.02):
        Xo = tri(P0[inl], D0[inl] + o)
        up = proj(Xo @ M[:3, :3].T + M[:3, 3])
        m = np.median(np.linalg.norm(up[:, :2] - Q[inl], axis=1))
        if m < best[0]:
            best = (m, o)
    o_gt[i] = best[1]
    k0 = int(np.where(offs == 0)[0][0])
    print(f'{i:2d} gt {tg:.3f} m  n={ok.sum()} inl={len(inl)}  PnP ratio {r_pnp[i,k0]:.4f} rotErr {rot_pnp[i]:.3f} deg dirErr {dir_err[i]:.2f} | '
          f'3D3D ratio {r_33[i,k0]:.4f} rotErr {rot_33[i]:.3f} | GT-fit offset {o_gt[i]:+.2f}', flush=True)

np.savez(f'motion_scale_{method}.npz', offs=offs, r_pnp=r_pnp, r_33=r_33, rot_pnp=rot_pnp, rot_33=rot_33,
         gtstep=gtstep, o_gt=o_gt, dir_err=dir_err)


def summary(name, r):
    med = np.nanmedian(r, 0)
    k0 = int(np.where(offs == 0)[0][0])
    x = r[:, k0]
    q25, q75 = np.nanpercentile(x, [25, 75])
    # offset where median ratio crosses 1 (linear interpolation)
    j = np.where(np.diff(np.sign(med - 1)) != 0)[0]
    oc = np.nan
    if len(j):
        j = j[0]; oc = offs[j] + (1 - med[j]) * (offs[j + 1] - offs[j]) / (med[j + 1] - med[j])
    print(f'{name}: ratio at offset 0: median {np.median(x):.4f}  IQR [{q25:.4f}, {q75:.4f}]  mean {x.mean():.4f} '
          f'| sum|t| ratio {np.sum(x*gtstep)/gtstep.sum():.4f} | median ratio = 1 at offset {oc:+.2f} px')
    for o in [-0.5, 0.5, 1.0, 1.5]:
        k = int(np.argmin(np.abs(offs - o)))
        print(f'    offset {o:+.1f}: median ratio {med[k]:.4f}')


print(f'--- method {method}, {npairs} pairs')
summary('PnP  ', r_pnp)
summary('3D-3D', r_33)
print(f'rotation err vs GT: PnP median {np.median(rot_pnp):.3f} max {rot_pnp.max():.3f} deg; 3D-3D median {np.median(rot_33):.3f} max {rot_33.max():.3f}')
print(f'translation direction err PnP median {np.median(dir_err):.2f} deg')
print(f'GT-consistency offset: median {np.median(o_gt):+.2f} px IQR {np.percentile(o_gt,[25,75]).round(2)}')
