"""Check 1 + 4: disparities of the same points by three independent methods
(row-NCC + parabola, pyramidal LK 2D, StereoSGBM dense), vertical offsets,
and far-point / minimum-disparity statistics."""
import numpy as np, cv2
from common import *

frames = [0, 10, 20, 30, 40, 50]
allr = []
for i in frames:
    L, R = img(0, i), img(1, i)
    p = corners(L)
    dn, sc = ncc_row_match(L, R, p, dmin=-10)
    dl, dy = lk_stereo(L, R, p, dinit=np.nan_to_num(dn, nan=20.0))
    S = sgbm(L, R)
    xi, yi = np.clip(np.round(p[:, 0]).astype(int), 0, L.shape[1]-1), np.clip(np.round(p[:, 1]).astype(int), 0, L.shape[0]-1)
    ds = S[yi, xi]
    ok = np.isfinite(dn) & np.isfinite(dl) & np.isfinite(ds)
    a = dl[ok] - dn[ok]; b = ds[ok] - dn[ok]
    print(f'frame {i:2d}: pts {len(p)} ncc ok {np.isfinite(dn).sum()} lk ok {np.isfinite(dl).sum()} all3 {ok.sum()}')
    print(f'   LK-NCC  median {np.median(a):+.3f} px  (MAD {np.median(np.abs(a-np.median(a))):.3f})')
    print(f'   SGBM-NCC median {np.median(b):+.3f} px  (MAD {np.median(np.abs(b-np.median(b))):.3f})')
    print(f'   vertical dy (yL-yR) by LK: median {np.nanmedian(dy):+.3f} px, MAD {np.nanmedian(np.abs(dy-np.nanmedian(dy))):.3f}')
    dd = dn[np.isfinite(dn)]
    print(f'   NCC disparity percentiles 0.5/1/5/50: {np.percentile(dd,[0.5,1,5,50]).round(2)}  min {dd.min():.2f}')
    sd = S[np.isfinite(S)]
    print(f'   SGBM dense disparity percentiles 0.1/1/5: {np.percentile(sd,[0.1,1,5]).round(2)}')
    # top image band (sky/far structures): rows < 150
    top = p[:, 1] < 150
    t = dn[top & np.isfinite(dn)]
    if len(t):
        print(f'   NCC disparity at rows<150: n={len(t)} percentiles 1/5/25: {np.percentile(t,[1,5,25]).round(2)}')
