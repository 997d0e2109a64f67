//! The sums of [`super::align_window`]'s Gauss-Newton step over a window: the general
//! loop, and the one for a window side known to the compiler.

/// [`super::align_window`]'s sums `[Σ gx², Σ gx gy, Σ gy², Σ gx e, Σ gy e]` (the first,
/// second and fourth only when `disparity_free`) over the `n × n` left window `lw`
/// (row-major) against the `m × m` right one `rw` (`m = n + 2`, a ring around for the
/// gradients).
#[inline(always)]
pub(super) fn window_sums(lw: &[f32], rw: &[f32], n: usize, disparity_free: bool) -> [f32; 5] {
    let m = n + 2;
    // Pixel by pixel in rows, as `rw[k]`, `rw[k ± 1]`, `rw[k ± m]` with `k = (j + 1) m
    // + i + 1`: row `j` of the left window against the right one's rows `j`, `j + 1`
    // and `j + 2` (above, at and below the samples), zipped slices rather than indices
    // (no bounds check per pixel).
    let (mut a, mut b, mut c, mut ex, mut ey) = (0f32, 0f32, 0f32, 0f32, 0f32);
    for (j, l) in lw.chunks_exact(n).take(n).enumerate() {
        let above = &rw[j * m + 1..][..n];
        let at = &rw[(j + 1) * m..][..m];
        let below = &rw[(j + 2) * m + 1..][..n];
        for (((&l, w), &up), &down) in l.iter().zip(at.windows(3)).zip(above).zip(below) {
            let e = l - w[1];
            let gy = -0.5 * (down - up);
            c += gy * gy;
            ey += gy * e;
            if disparity_free {
                let gx = 0.5 * (w[2] - w[0]);
                a += gx * gx;
                b += gx * gy;
                ex += gx * e;
            }
        }
    }
    [a, b, c, ex, ey]
}

/// [`window_sums`] for a window side `N` known to the compiler, with the left window `lws`
/// laid out with the right one's stride `m = N + 2` (pixel `(i, j)` at `j m + i`): the
/// products at every pixel first, in one loop over the rows and the two columns between
/// them (the same operations on each, in vector registers; the columns between are not
/// summed), then the sums pixel by pixel in the same order, unrolled. `LEN = N (N + 2) −
/// 2` pixels from the first to the last of the window; `products` is scratch space
/// (`gx²`, `gx gy`, `gy²`, `gx e`, `gy e` at each, all written here).
#[inline(always)]
pub(super) fn window_sums_fixed<const N: usize, const LEN: usize>(
    lws: &[f32],
    rw: &[f32],
    products: &mut [[f32; LEN]; 5],
    disparity_free: bool,
) -> [f32; 5] {
    const { assert!(LEN == N * (N + 2) - 2) };
    let m = N + 2;
    // Pixel `(i, j)` at `k = j m + i`: `rw[k + m + 1]` and its neighbours.
    let (l, above, at, below) = (
        &lws[..LEN],
        &rw[1..][..LEN],
        &rw[m..][..LEN + 2],
        &rw[2 * m + 1..][..LEN],
    );
    let [pxx, pxy, pyy, pxe, pye] = products;
    for k in 0..LEN {
        let e = l[k] - at[k + 1];
        let gy = -0.5 * (below[k] - above[k]);
        let gx = 0.5 * (at[k + 2] - at[k]);
        pxx[k] = gx * gx;
        pxy[k] = gx * gy;
        pyy[k] = gy * gy;
        pxe[k] = gx * e;
        pye[k] = gy * e;
    }
    let (mut a, mut b, mut c, mut ex, mut ey) = (0f32, 0f32, 0f32, 0f32, 0f32);
    for j in 0..N {
        for k in j * m..j * m + N {
            c += pyy[k];
            ey += pye[k];
            if disparity_free {
                a += pxx[k];
                b += pxy[k];
                ex += pxe[k];
            }
        }
    }
    [a, b, c, ex, ey]
}
