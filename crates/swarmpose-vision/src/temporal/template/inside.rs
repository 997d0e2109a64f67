//! [`super::PatchTemplate::align_affine`]'s samples of a patch inside the image: the values of
//! [`sample_bilinear_inside`] at each position, from the same operations, a patch at a
//! time.

use super::N;
use crate::features::GrayView;
#[cfg(doc)]
use crate::image::sample_bilinear_inside;

/// 2^23: added to a non-negative `f32` below 2^22, it leaves the nearest integer in the
/// sum's low mantissa bits.
const TWO_23: f32 = 8_388_608.0;

/// The whole part of `u`, `0 <= u < 2^22`, as `u as i32` and as `f32` (the same integer),
/// without the saturating conversion: the nearest integer (from `u + 2^23`), less one when
/// above `u`.
#[inline(always)]
pub(super) fn whole_part(u: f32) -> (i32, f32) {
    let s = u + TWO_23;
    let (near, r) = ((s.to_bits() & 0x007f_ffff) as i32, s - TWO_23);
    let above = r > u;
    (near - i32::from(above), if above { r - 1.0 } else { r })
}

/// [`sample_bilinear_inside`] at each of the positions `(us, vs)` (pixels, all inside it, in
/// an image at most 2^22 pixels wide and high) into `out`: the same values, each from the
/// same operations, in three loops of which the first and last are vectorised: the
/// positions' whole parts ([`whole_part`]) and fractions, the four neighbours of each, the
/// weighted sums.
#[inline(always)]
pub(super) fn sample_inside(
    image: GrayView<'_>,
    (us, vs): (&[f32; N * N], &[f32; N * N]),
    out: &mut [f32; N * N],
) {
    let (mut cx, mut cy) = ([0i32; N * N], [0i32; N * N]);
    let (mut fx, mut fy) = ([0f32; N * N], [0f32; N * N]);
    for (((&u, cx), fx), (&v, (cy, fy))) in us
        .iter()
        .zip(&mut cx)
        .zip(&mut fx)
        .zip(vs.iter().zip(cy.iter_mut().zip(&mut fy)))
    {
        let ((tx, wx), (ty, wy)) = (whole_part(u), whole_part(v));
        (*cx, *cy) = (tx, ty);
        (*fx, *fy) = (u - wx, v - wy);
    }
    // The width is at most 2^22 (the caller's condition; `min` tells the compiler, so that
    // one bounds check per sample covers its four neighbours).
    let (w, d) = (image.width.min(1 << 22), image.data);
    // The four neighbours of each sample, as two pairs of bytes (little-endian: the left
    // one low): the top and the bottom ones.
    let (mut tops, mut bots) = ([0u16; N * N], [0u16; N * N]);
    let pair = |a: u8, b: u8| u16::from(a) | (u16::from(b) << 8);
    for ((top, bot), (&tx, &ty)) in tops.iter_mut().zip(&mut bots).zip(cx.iter().zip(&cy)) {
        // Inside: 0 <= tx, ty (whole parts of non-negative positions).
        let i = ty as usize * w + tx as usize;
        let q = &d[i..i + w + 2];
        (*top, *bot) = (pair(q[0], q[1]), pair(q[w], q[w + 1]));
    }
    let byte = |p: u16, high: bool| f32::from((if high { p >> 8 } else { p & 0xff }) as u8);
    for ((o, (&tp, &bp)), (&fx, &fy)) in out
        .iter_mut()
        .zip(tops.iter().zip(&bots))
        .zip(fx.iter().zip(&fy))
    {
        let top = byte(tp, false) * (1.0 - fx) + byte(tp, true) * fx;
        let bot = byte(bp, false) * (1.0 - fx) + byte(bp, true) * fx;
        *o = top * (1.0 - fy) + bot * fy;
    }
}
