"""Camera height above the road from stereo (offset-independent):
on a planar road, d = b/h * ((v-cy) cos(pitch) + ...) + const; the slope dd/dv = b*cos(pitch)/h does not
depend on a constant disparity offset (an offset only moves the intercept). KITTI's setup page gives the
camera height as 1.65 m. Robust plane fit d = a*u + c*v + e on SGBM disparities in a road window."""
import numpy as np, cv2
from common import *
fx, cx, cy, b = calib()
hs = []
for i in range(0, 51, 2):
    L, R = img(0, i), img(1, i)
    S = sgbm(L, R)
    v, u = np.mgrid[0:S.shape[0], 0:S.shape[1]]
    win = (v > 260) & (v < 370) & (np.abs(u - cx) < 120 + (v - 260) * 2.0)
    m = win & np.isfinite(S)
    A = np.c_[u[m], v[m], np.ones(m.sum())].astype(float); y = S[m]
    keep = np.ones(len(y), bool)
    for it in range(5):
        coef, *_ = np.linalg.lstsq(A[keep], y[keep], rcond=None)
        r = y - A @ coef
        s = 1.4826 * np.median(np.abs(r[keep]))
        keep = np.abs(r) < max(2.5 * s, 0.3)
    a, c, e = coef
    h = b / c
    v_h = -(e + a * cx) / c  # row where road disparity (at u=cx) would be 0
    hs.append(h)
    print(f'frame {i:2d}: n={keep.sum():6d} resid MAD {s:.3f}px  slope dd/dv={c:.4f}  -> h = b/slope = {h:.3f} m   zero-disparity row {v_h:.1f} (cy={cy:.1f})')
hs = np.array(hs)
print(f'median camera height {np.median(hs):.3f} m, IQR {np.percentile(hs,[25,75]).round(3)}')
