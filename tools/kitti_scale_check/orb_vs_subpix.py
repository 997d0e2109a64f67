"""How do disparities from an ORB/FAST-style front end (keypoints at integer positions on pyramid levels,
scaled by 1.2^k; right keypoint matched by descriptor along the row) compare with sub-pixel NCC
disparities at the same left keypoints? A mean difference would be a front-end disparity bias."""
import numpy as np, cv2
from common import *
orb = cv2.ORB_create(nfeatures=4000, scaleFactor=1.2, nlevels=8, edgeThreshold=19, fastThreshold=12)
rows = []
for i in range(0, 51, 5):
    L, R = img(0, i), img(1, i)
    kl, dl = orb.detectAndCompute(L, None); kr, dr = orb.detectAndCompute(R, None)
    pl = np.array([k.pt for k in kl]); pr = np.array([k.pt for k in kr])
    ol = np.array([k.octave for k in kl]); orr = np.array([k.octave for k in kr])
    H = cv2.batchDistance(dl, dr, cv2.NORM_HAMMING, K=0)[0] if False else None
    bf = cv2.BFMatcher(cv2.NORM_HAMMING)
    # brute force with row + disparity constraints
    D = np.unpackbits((dl[:, None, :] ^ dr[None, :, :]), axis=2).sum(2).astype(float)
    dy = np.abs(pl[:, None, 1] - pr[None, :, 1]); dx = pl[:, None, 0] - pr[None, :, 0]
    D[(dy > 2.0) | (dx < 0) | (dx > 150)] = 1e9
    j = D.argmin(1); best = D[np.arange(len(j)), j]
    D2 = D.copy(); D2[np.arange(len(j)), j] = 1e9; second = D2.min(1)
    ok = (best < 50) & (best < 0.8 * second)
    idx = np.where(ok)[0]
    d_orb = pl[idx, 0] - pr[j[idx], 0]
    d_ncc, _ = ncc_row_match(L, R, pl[idx], dmin=-5)
    # NCC at the integer-rounded left position of the keypoint's OWN level, for reference
    for a, dd_o, dd_n in zip(idx, d_orb, d_ncc):
        rows.append([i, ol[a], orr[j[a]], dd_o, dd_n])
Rw = np.array(rows)
g = np.isfinite(Rw[:, 4]) & (np.abs(Rw[:, 3] - Rw[:, 4]) < 3)
diff = Rw[g, 3] - Rw[g, 4]
print(f'matches {len(Rw)}, with valid NCC and |diff|<3: {g.sum()}')
print(f'ALL: d_orb - d_ncc: mean {diff.mean():+.3f}  median {np.median(diff):+.3f}  std {diff.std():.3f}  (SE of mean {diff.std()/np.sqrt(len(diff)):.3f})')
for lev in range(0, 8):
    s = g & (Rw[:, 1] == lev)
    if s.sum() > 20:
        dd = Rw[s, 3] - Rw[s, 4]
        print(f'  left octave {lev} (scale {1.2**lev:.2f}): n={s.sum():4d}  mean {dd.mean():+.3f}  median {np.median(dd):+.3f}  std {dd.std():.3f}')
same = g & (Rw[:, 1] == Rw[:, 2]); diffoct = g & (Rw[:, 1] != Rw[:, 2])
for nm, s in [('same octave L/R', same), ('different octave L/R', diffoct)]:
    dd = Rw[s, 3] - Rw[s, 4]
    print(f'  {nm}: n={s.sum()} mean {dd.mean():+.3f} median {np.median(dd):+.3f}')
