"""Check 4: are there reliable NEGATIVE disparities (objects 'beyond infinity')?
SGBM with minDisparity=-16 plus NCC/LK agreement at corners with d<0.5."""
import numpy as np, cv2
from common import *
fx, cx, cy, b = calib()
for i in range(0, 51, 5):
    L, R = img(0, i), img(1, i)
    bs = 5
    m = cv2.StereoSGBM_create(minDisparity=-16, numDisparities=144, blockSize=bs, P1=8*bs*bs, P2=32*bs*bs,
                              disp12MaxDiff=1, uniquenessRatio=15, speckleWindowSize=100, speckleRange=2,
                              mode=cv2.STEREO_SGBM_MODE_HH)
    S = m.compute(L, R).astype(np.float32) / 16.0
    valid = S > -16
    top = valid.copy(); top[200:] = False; top[:, :150] = False  # exclude left band (no overlap)
    s = S[top]
    p = corners(L)
    dn, sc = ncc_row_match(L, R, p, dmin=-8)
    dl, dy = lk_stereo(L, R, p, dinit=np.nan_to_num(dn, nan=20.0))
    neg = np.isfinite(dn) & np.isfinite(dl) & (dn < 0.5) & (np.abs(dn - dl) < 0.3)
    print(f'frame {i:2d}: SGBM valid top-band px {top.sum()}, frac d<0: {np.mean(s<0):.4f}, d<-0.5: {np.mean(s<-0.5):.4f}; '
          f'pctl 0.1/1/5: {np.percentile(s,[0.1,1,5]).round(2)} | corners NCC&LK agree with d<0.5: {neg.sum()} '
          f'values {np.sort(dn[neg])[:8].round(2)}')
    if i == 0:
        np.save('sgbm_neg_f0.npy', S)
