"""GT-FREE estimate of a disparity offset: for each pair, estimate the full stereo motion (R,t) by
minimising reprojection residuals of (u1, v1, d1) in frame i+1 (left image position + disparity),
with 3D points of frame i triangulated from d0+o; the measured d1 is compared as d1+o.
A wrong offset distorts the reconstructed structure projectively (not a similarity), so no rigid motion
fits uv AND d consistently; the summed robust cost over 50 pairs vs o shows which offset the images +
calibration support by themselves (no poses.txt). Also prints |t|/|t_GT| for each o."""
import numpy as np, cv2
from scipy.optimize import least_squares
from common import *
fx, cx, cy, b = calib(); T = poses()
A = np.load('gtc.npz')['A']
fr = A[:, 0].astype(int); p0 = A[:, 1:3]; d0 = A[:, 3]; q = A[:, 4:6]; d1 = A[:, 6]
offs = np.arange(-1.0, 3.01, 0.25)
SIG_D = 0.5  # weight of disparity residual relative to uv (d is ~as precise as uv; keep equal weight -> 1.0); see below

def run(wd):
    tot = np.zeros(len(offs)); ratios = np.zeros((N - 1, len(offs)))
    for i in range(N - 1):
        m = (fr == i) & (d0 > 3) & (d1 > 3)
        P, D0, Q, D1 = p0[m], d0[m], q[m], d1[m]
        M = gt_rel(T, i, i + 1); tg = np.linalg.norm(M[:3, 3])
        x = np.r_[np.zeros(3), 0, 0, -1.0]
        # inlier set fixed at o=0 with an initial robust fit
        def res(x, o, sel):
            Rr = cv2.Rodrigues(x[:3])[0]
            d = D0[sel] + o; Z = fx * b / d
            X = np.c_[(P[sel, 0] - cx) * Z / fx, (P[sel, 1] - cy) * Z / fx, Z]
            Y = X @ Rr.T + x[3:]
            u = fx * Y[:, 0] / Y[:, 2] + cx; v = fx * Y[:, 1] / Y[:, 2] + cy; dd = fx * b / Y[:, 2] - o
            return np.r_[u - Q[sel, 0], v - Q[sel, 1], wd * (dd - D1[sel])]
        allp = np.ones(len(D0), bool)
        r = least_squares(res, x, args=(0.0, allp), loss='soft_l1', f_scale=0.5)
        e = np.abs(r.fun.reshape(3, -1)).max(0)
        sel = e < 1.5
        x = r.x
        for k, o in enumerate(offs):
            r = least_squares(res, x, args=(o, sel), loss='soft_l1', f_scale=0.5)
            tot[k] += r.cost
            ratios[i, k] = np.linalg.norm(r.x[3:]) / tg
    return tot, ratios

for wd in [1.0, 2.0]:
    tot, ratios = run(wd)
    kbest = int(np.argmin(tot))
    # parabola refine
    if 0 < kbest < len(offs) - 1:
        a, bb, c = tot[kbest - 1:kbest + 2]
        ob = offs[kbest] + 0.5 * (a - c) / (a - 2 * bb + c) * (offs[1] - offs[0])
    else:
        ob = offs[kbest]
    print(f'disparity-residual weight {wd}: GT-free best offset {ob:+.2f} px')
    for k, o in enumerate(offs):
        print(f'   o={o:+.2f}  total robust cost {tot[k]:9.1f}   median |t|/|t_GT| {np.median(ratios[:,k]):.4f}')
