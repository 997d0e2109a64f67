"""Is the discrepancy better explained by wrong intrinsics (images from another calibration) than by a
disparity offset? Fit, against the GT motion (pooled per-point data gtc.npz), models with a free focal
length f' (used for triangulation AND projection), free cx', free baseline b', and disparity offset o."""
import numpy as np
from scipy.optimize import least_squares
from common import *
fx, cx, cy, b = calib(); T = poses()
A = np.load('gtc.npz')['A']
fr = A[:, 0].astype(int); p0 = A[:, 1:3]; d0 = A[:, 3]; q = A[:, 4:6]
Ms = [gt_rel(T, i, i + 1) for i in range(N - 1)]
Rm = np.stack([Ms[i][:3, :3] for i in fr]); tm = np.stack([Ms[i][:3, 3] for i in fr])
m = d0 > 3

def resid(par, names):
    P = dict(f=fx, cx=cx, cy=cy, b=b, o=0.0, k=1.0)
    P.update(dict(zip(names, par)))
    f, c, cyy = P['f'], P['cx'], P['cy']
    d = d0[m] + P['o']
    Z = f * P['b'] / d
    X = np.c_[(p0[m, 0] - c) * Z / f, (p0[m, 1] - cyy) * Z / f, Z]
    Y = np.einsum('nij,nj->ni', Rm[m], X) + P['k'] * tm[m]
    u = f * Y[:, 0] / Y[:, 2] + c; v = f * Y[:, 1] / Y[:, 2] + cyy
    return np.r_[u - q[m, 0], v - q[m, 1]]

init = dict(f=fx, cx=cx, cy=cy, b=b, o=0.0, k=1.0)
for names in [[], ['o'], ['b'], ['f'], ['f', 'o'], ['f', 'cx', 'cy'], ['f', 'cx', 'cy', 'o'], ['f', 'cx', 'cy', 'b'], ['f', 'cx', 'cy', 'o', 'k']]:
    if names:
        r = least_squares(resid, [init[n] for n in names], args=(names,), loss='soft_l1', f_scale=1.0, x_scale='jac')
        x, fun, cost = r.x, r.fun, r.cost
    else:
        fun = resid([], []); x = []
        cost = (2 * (np.sqrt(1 + fun ** 2) - 1)).sum() / 2
    e = np.hypot(*fun.reshape(2, -1))
    print(f'free {",".join(names) or "(none)":16s}: {dict(zip(names, np.round(x, 4)))}  robust cost {cost:.0f}  median err {np.median(e):.3f}px')
