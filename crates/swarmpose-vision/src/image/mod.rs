//! Owned 8-bit grayscale images: PNG loading with errors naming the file (feature `png`,
//! on by default), bilinear sampling, a small separable blur, halving and doubling.

#[cfg(feature = "png")]
use std::path::Path;
use std::path::PathBuf;

use crate::features::GrayView;

pub mod depth;

pub use depth::{Depth, DepthSource};

/// Why an image could not be loaded. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The file could not be read (missing, permissions, ...).
    #[error("{}: cannot read image: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The bytes are not a decodable PNG.
    #[error("{}: not a readable PNG image: {message}", path.display())]
    Decode {
        /// The file.
        path: PathBuf,
        /// What the decoder said.
        message: String,
    },
}

/// An owned 8-bit grayscale image, row-major.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct GrayImage {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Pixels, row-major: pixel `(x, y)` is `data[y * width + x]`.
    pub data: Vec<u8>,
}

impl GrayImage {
    /// A black image of this size (pixels).
    #[must_use]
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            data: vec![0; width * height],
        }
    }

    /// Wraps row-major pixels; `None` when `data.len() != width * height`.
    #[must_use]
    pub fn from_raw(width: usize, height: usize, data: Vec<u8>) -> Option<Self> {
        (data.len() == width * height).then_some(Self {
            width,
            height,
            data,
        })
    }

    #[cfg(feature = "png")]
    /// Loads a PNG (any colour type; converted to 8-bit luma).
    ///
    /// # Errors
    /// [`ImageError`] naming `path` when it cannot be read or decoded.
    pub fn load_png(path: &Path) -> Result<Self, ImageError> {
        let bytes = std::fs::read(path).map_err(|source| ImageError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::decode_png(&bytes, path)
    }

    #[cfg(feature = "png")]
    /// Decodes the bytes of a PNG (any colour type; converted to 8-bit luma); messages
    /// name `path`.
    ///
    /// # Errors
    /// [`ImageError::Decode`] naming `path`.
    pub fn decode_png(bytes: &[u8], path: &Path) -> Result<Self, ImageError> {
        Self::decode_png_with_depth(bytes, path).map(|(img, _)| img)
    }

    #[cfg(feature = "png")]
    /// [`GrayImage::decode_png`], with the depth its data was read with: 16-bit images
    /// are scaled to 8 bits by the depth their data uses ([`depth`]: the `sBIT` chunk
    /// where present; 12 bits when every value fits and nothing says so; else 16), not
    /// by 16 bits regardless (which turns 12-bit data near-black).
    ///
    /// # Errors
    /// [`ImageError::Decode`] naming `path`.
    pub fn decode_png_with_depth(bytes: &[u8], path: &Path) -> Result<(Self, Depth), ImageError> {
        let decoded =
            image::load_from_memory_with_format(bytes, image::ImageFormat::Png).map_err(|e| {
                ImageError::Decode {
                    path: path.to_owned(),
                    message: e.to_string(),
                }
            })?;
        let (w, h) = (decoded.width() as usize, decoded.height() as usize);
        let sixteen = matches!(
            decoded.color(),
            image::ColorType::L16
                | image::ColorType::La16
                | image::ColorType::Rgb16
                | image::ColorType::Rgba16
        );
        if sixteen {
            let luma = decoded.into_luma16().into_raw();
            let d = depth::of_16bit(&luma, depth::sbit(bytes));
            let data = depth::to_8bit(&luma, d.bits);
            return Ok((
                Self {
                    width: w,
                    height: h,
                    data,
                },
                d,
            ));
        }
        let luma = decoded.into_luma8();
        Ok((
            Self {
                width: w,
                height: h,
                data: luma.into_raw(),
            },
            Depth {
                bits: 8,
                source: DepthSource::Eight,
            },
        ))
    }

    #[cfg(feature = "png")]
    /// Saves as an 8-bit grayscale PNG.
    ///
    /// # Errors
    /// The encoder's or the file system's message, naming `path`.
    pub fn save_png(&self, path: &Path) -> Result<(), String> {
        image::save_buffer(
            path,
            &self.data,
            self.width as u32,
            self.height as u32,
            image::ExtendedColorType::L8,
        )
        .map_err(|e| format!("{}: cannot write PNG: {e}", path.display()))
    }

    /// A borrowed view.
    #[must_use]
    pub fn view(&self) -> GrayView<'_> {
        GrayView {
            width: self.width,
            height: self.height,
            data: &self.data,
        }
    }

    /// Pixel `(x, y)`; the caller keeps it inside.
    #[inline]
    #[must_use]
    pub fn get(&self, x: usize, y: usize) -> u8 {
        self.data[y * self.width + x]
    }
}

/// Bilinear sample at `(x, y)` pixels (pixel centres at integers); `None` outside the
/// image (a sample needs all four neighbours).
#[inline]
#[must_use]
pub fn sample_bilinear(img: GrayView<'_>, x: f32, y: f32) -> Option<f32> {
    if !(x >= 0.0 && y >= 0.0) {
        return None;
    }
    // Through i64, whose conversions to and from f32 are cheaper than usize's: x, y ≥ 0
    // (a NaN is refused above), so below 2^63 these are the integers `x as usize` gives,
    // and non-negative; beyond, the position is outside any image (where `x as usize`
    // could overflow `x0 + 1`).
    let (tx, ty) = (x as i64, y as i64);
    let (x0, y0) = (tx as usize, ty as usize);
    if x0 + 1 >= img.width || y0 + 1 >= img.height {
        // Exactly on the last row/column is still inside.
        if x0 < img.width && y0 < img.height && x == tx as f32 && y == ty as f32 {
            return Some(f32::from(img.data[y0 * img.width + x0]));
        }
        return None;
    }
    Some(sample_bilinear_inside(img, x, y))
}

/// [`sample_bilinear`] at `(x, y)` pixels that the caller has checked inside, with the
/// four neighbours: `0 ≤ x < width − 1` and `0 ≤ y < height − 1`, where
/// [`sample_bilinear`] gives `Some` of this (outside, a wrong value or a panic).
#[inline(always)]
#[must_use]
pub(crate) fn sample_bilinear_inside(img: GrayView<'_>, x: f32, y: f32) -> f32 {
    // As in `sample_bilinear`: x, y ≥ 0, so the integers `x as usize` gives.
    let (tx, ty) = (x as i64, y as i64);
    let (x0, y0) = (tx as usize, ty as usize);
    let (fx, fy) = (x - tx as f32, y - ty as f32);
    let i = y0 * img.width + x0;
    let d = img.data;
    let top = f32::from(d[i]) * (1.0 - fx) + f32::from(d[i + 1]) * fx;
    let bot = f32::from(d[i + img.width]) * (1.0 - fx) + f32::from(d[i + img.width + 1]) * fx;
    top * (1.0 - fy) + bot * fy
}

#[must_use]
#[inline(always)]
/// Samples the `n × n` patch whose top-left sample is at `(x0, y0)` (pixels, sub-pixel)
/// into `out` (row-major): every sample shares the same fractional offset, so the
/// bilinear weights are computed once. `out` holds at least `n²` values. `None` when the
/// patch leaves the image.
pub fn sample_patch(img: GrayView<'_>, x0: f32, y0: f32, n: usize, out: &mut [f32]) -> Option<()> {
    if out.len() < n * n {
        return None;
    }
    if !(x0 >= 0.0 && y0 >= 0.0) {
        return None;
    }
    // For x0, y0 ≥ 0 the floor is the truncation, and i64's conversions are cheaper than
    // usize's (as in `sample_bilinear`): the same integers below 2^63.
    let (tx, ty) = (x0 as i64, y0 as i64);
    let (xi, yi) = (tx as usize, ty as usize);
    if xi + n >= img.width || yi + n >= img.height {
        return None;
    }
    let (fx, fy) = (x0 - tx as f32, y0 - ty as f32);
    let (w00, w10, w01, w11) = (
        (1.0 - fx) * (1.0 - fy),
        fx * (1.0 - fy),
        (1.0 - fx) * fy,
        fx * fy,
    );
    let w = img.width;
    for j in 0..n {
        let top = &img.data[(yi + j) * w + xi..][..n + 1];
        let bot = &img.data[(yi + j + 1) * w + xi..][..n + 1];
        let row = &mut out[j * n..][..n];
        patch_row(top, bot, [w00, w10, w01, w11], row);
    }
    Some(())
}

/// Lanes of [`patch_row`]'s blocks: the samples of a row computed together.
const PATCH_LANES: usize = 8;

/// One row of [`sample_patch`]: `row[i]` from the pixels `i`, `i + 1` of the rows `top`
/// and `bot` (`row.len() + 1` pixels each) with the weights `[w00, w10, w01, w11]`. Rows
/// of at least [`PATCH_LANES`] samples go by blocks of that many, of fixed size (the
/// compiler keeps each in vector registers, every lane doing the scalar operations in the
/// same order), the last block overlapping the previous one when the row is not a
/// multiple (its samples are written twice, with the same values).
#[inline(always)]
fn patch_row(top: &[u8], bot: &[u8], weights: [f32; 4], row: &mut [f32]) {
    let n = row.len();
    if n < PATCH_LANES {
        for (i, o) in row.iter_mut().enumerate() {
            *o = bilinear_weighted(top, bot, weights, i);
        }
        return;
    }
    let mut start = 0;
    while start + PATCH_LANES < n {
        patch_block(&top[start..], &bot[start..], weights, &mut row[start..]);
        start += PATCH_LANES;
    }
    let last = n - PATCH_LANES;
    patch_block(&top[last..], &bot[last..], weights, &mut row[last..]);
}

/// [`PATCH_LANES`] samples of [`patch_row`] from the start of `top`, `bot` and `row`.
#[inline(always)]
fn patch_block(top: &[u8], bot: &[u8], weights: [f32; 4], row: &mut [f32]) {
    let (t, b) = (&top[..=PATCH_LANES], &bot[..=PATCH_LANES]);
    for (i, o) in row[..PATCH_LANES].iter_mut().enumerate() {
        *o = bilinear_weighted(t, b, weights, i);
    }
}

/// The sample of [`sample_patch`] between pixels `i`, `i + 1` of the rows `t` and `b`, with
/// the weights `[w00, w10, w01, w11]`.
#[inline(always)]
fn bilinear_weighted(t: &[u8], b: &[u8], [w00, w10, w01, w11]: [f32; 4], i: usize) -> f32 {
    w00 * f32::from(t[i])
        + w10 * f32::from(t[i + 1])
        + w01 * f32::from(b[i])
        + w11 * f32::from(b[i + 1])
}

/// Halves `img`: each pixel of the result is the mean (rounded) of a 2x2 block, so the
/// result has `(width / 2, height / 2)` pixels (a last odd column or row is dropped).
/// With pixel centres at integer coordinates, a point at `x` in `img` is at
/// `(x − 0.5) / 2` in the result. `out` is resized to the result (reused between calls);
/// returns its width and height.
pub fn halve(img: GrayView<'_>, out: &mut Vec<u8>) -> (usize, usize) {
    let (w, h) = (img.width / 2, img.height / 2);
    out.clear();
    out.resize(w * h, 0);
    if w == 0 || h == 0 {
        return (w, h);
    }
    let stride = img.width;
    for (y, orow) in out.chunks_exact_mut(w).enumerate() {
        let top = &img.data[2 * y * stride..][..2 * w];
        let bottom = &img.data[(2 * y + 1) * stride..][..2 * w];
        for ((o, t), b) in orow
            .iter_mut()
            .zip(top.chunks_exact(2))
            .zip(bottom.chunks_exact(2))
        {
            let sum = u16::from(t[0]) + u16::from(t[1]) + u16::from(b[0]) + u16::from(b[1]);
            *o = ((sum + 2) / 4) as u8;
        }
    }
    (w, h)
}

/// Weights of the neighbours `k − 2 ..= k + 1` of the even output pixel `2k` in
/// [`double`] (in 256ths): the cubic convolution kernel with `a = −0.75` (OpenCV's
/// bicubic) at the distances 1.75, 0.75, 0.25 and 1.25; the odd pixel `2k + 1` takes
/// them mirrored on `k − 1 ..= k + 2`.
pub const DOUBLE_TAPS: [i32; 4] = [-9, 67, 225, -27];

/// Doubles `img` with a bicubic interpolation (separable, borders clamped; the weights
/// are [`DOUBLE_TAPS`]), into `out`: `(2 width, 2 height)` pixels. With pixel centres at
/// integer coordinates, a point at `x` in `img` is at `2 x + 0.5` in the result. `tmp` is
/// scratch space; both are reused between calls. Returns the result's width and height.
pub fn double(img: GrayView<'_>, tmp: &mut Vec<i32>, out: &mut Vec<u8>) -> (usize, usize) {
    let (w, h) = (img.width, img.height);
    let (w2, h2) = (2 * w, 2 * h);
    tmp.clear();
    tmp.resize(w2 * h, 0);
    out.clear();
    out.resize(w2 * h2, 0);
    if w == 0 || h == 0 {
        return (w2, h2);
    }
    let clamp = |i: isize, n: usize| i.clamp(0, n as isize - 1) as usize;
    // Horizontal pass: 256 times the interpolated values, row by row.
    for (row, trow) in img.data.chunks_exact(w).zip(tmp.chunks_exact_mut(w2)) {
        let at = |i: isize| i32::from(row[clamp(i, w)]);
        for k in 0..w {
            let k = k as isize;
            let [t0, t1, t2, t3] = DOUBLE_TAPS;
            trow[2 * k as usize] = t0 * at(k - 2) + t1 * at(k - 1) + t2 * at(k) + t3 * at(k + 1);
            trow[2 * k as usize + 1] =
                t3 * at(k - 1) + t2 * at(k) + t1 * at(k + 1) + t0 * at(k + 2);
        }
    }
    // Vertical pass, then back to 8 bits (65536 times the value), rounded and clamped.
    let to_u8 = |v: i64| ((v + 32768) >> 16).clamp(0, 255) as u8;
    for k in 0..h {
        let r = |i: isize| &tmp[clamp(i, h) * w2..][..w2];
        let k = k as isize;
        let (a, b, c, d, e) = (r(k - 2), r(k - 1), r(k), r(k + 1), r(k + 2));
        let [t0, t1, t2, t3] = DOUBLE_TAPS.map(i64::from);
        let (even, odd) = out[2 * k as usize * w2..][..2 * w2].split_at_mut(w2);
        for x in 0..w2 {
            let (a, b, c, d, e) = (
                i64::from(a[x]),
                i64::from(b[x]),
                i64::from(c[x]),
                i64::from(d[x]),
                i64::from(e[x]),
            );
            even[x] = to_u8(t0 * a + t1 * b + t2 * c + t3 * d);
            odd[x] = to_u8(t3 * b + t2 * c + t1 * d + t0 * e);
        }
    }
    (w2, h2)
}

/// Separable binomial blur `[1 4 6 4 1] / 16` (σ ≈ 1 pixel), borders clamped. `out` is
/// resized to the image; `tmp` is scratch space (reused between calls). Compiled for the
/// CPU's best instruction set ([`crate::simd`]).
pub fn blur5(img: GrayView<'_>, tmp: &mut Vec<u16>, out: &mut Vec<u8>) {
    crate::simd::dispatch(Blur5(img, tmp, out));
}

/// A call of [`blur5`] for [`crate::simd::dispatch`].
struct Blur5<'a>(GrayView<'a>, &'a mut Vec<u16>, &'a mut Vec<u8>);

impl crate::simd::Kernel for Blur5<'_> {
    type Output = ();

    #[inline(always)]
    fn run(self) {
        blur5_in(self.0, self.1, self.2);
    }
}

/// [`blur5`], inlined into each instruction set's compilation.
#[inline(always)]
fn blur5_in(img: GrayView<'_>, tmp: &mut Vec<u16>, out: &mut Vec<u8>) {
    let (w, h) = (img.width, img.height);
    let d = img.data;
    // Every element of `tmp` and `out` is written below when the image holds its `w h`
    // pixels: nothing to clear then (a short image leaves zeros, as before).
    if d.len() < w * h {
        tmp.clear();
        out.clear();
    }
    tmp.resize(w * h, 0);
    out.resize(w * h, 0);
    if w == 0 || h == 0 {
        return;
    }
    for (row, trow) in d.chunks_exact(w).zip(tmp.chunks_exact_mut(w)) {
        let at = |x: usize, dx: isize| -> u16 {
            let xx = (x as isize + dx).clamp(0, w as isize - 1) as usize;
            u16::from(row[xx])
        };
        let edge = |x: usize| at(x, -2) + 4 * at(x, -1) + 6 * at(x, 0) + 4 * at(x, 1) + at(x, 2);
        if w < 5 {
            for (x, t) in trow.iter_mut().enumerate() {
                *t = edge(x);
            }
            continue;
        }
        // Clamped at the two pixels of each end; the interior on shifted slices of one
        // length (no clamps, no bounds checks).
        for x in [0, 1, w - 2, w - 1] {
            trow[x] = edge(x);
        }
        let n = w - 4;
        let (r0, r1, r2, r3, r4) = (
            &row[..n],
            &row[1..][..n],
            &row[2..][..n],
            &row[3..][..n],
            &row[4..][..n],
        );
        let inner = &mut trow[2..][..n];
        for x in 0..n {
            inner[x] = u16::from(r0[x])
                + 4 * u16::from(r1[x])
                + 6 * u16::from(r2[x])
                + 4 * u16::from(r3[x])
                + u16::from(r4[x]);
        }
    }
    for (y, orow) in out.chunks_exact_mut(w).enumerate() {
        let r = |dy: isize| {
            let yy = (y as isize + dy).clamp(0, h as isize - 1) as usize;
            &tmp[yy * w..][..w]
        };
        let (a, b, c, e, f) = (r(-2), r(-1), r(0), r(1), r(2));
        for x in 0..w {
            let s = u32::from(a[x])
                + 4 * u32::from(b[x])
                + 6 * u32::from(c[x])
                + 4 * u32::from(e[x])
                + u32::from(f[x]);
            orow[x] = ((s + 128) >> 8) as u8;
        }
    }
}

#[cfg(test)]
mod sampling_bits;

#[cfg(test)]
mod tests {
    use super::*;

    /// [`blur5`] into buffers left by a larger image (not cleared) gives what it gives
    /// into new ones, also for an image shorter than its size says (zero rows).
    #[test]
    fn blur_into_used_buffers() {
        let (w, h) = (37, 23);
        let data = crate::test_noise::noise_bytes(w * h, 5);
        let (mut tmp, mut out) = (vec![7u16; 2 * w * h], vec![9u8; 2 * w * h]);
        for len in [w * h, w * h - 3 * w - 5, w * h] {
            let img = GrayView {
                width: w,
                height: h,
                data: &data[..len],
            };
            let (mut t, mut o) = (Vec::new(), Vec::new());
            blur5(img, &mut t, &mut o);
            blur5(img, &mut tmp, &mut out);
            assert_eq!(out, o, "{len} pixels");
            assert_eq!(tmp, t, "{len} pixels");
        }
    }

    #[test]
    fn bilinear_and_blur() {
        let img = GrayImage::from_raw(2, 2, vec![0, 100, 100, 200]).expect("size");
        assert_eq!(sample_bilinear(img.view(), 0.5, 0.5), Some(100.0));
        assert_eq!(sample_bilinear(img.view(), 1.0, 1.0), Some(200.0));
        assert_eq!(sample_bilinear(img.view(), 1.5, 0.0), None);
        let flat = GrayImage::from_raw(7, 5, vec![77; 35]).expect("size");
        let (mut t, mut o) = (Vec::new(), Vec::new());
        blur5(flat.view(), &mut t, &mut o);
        assert!(o.iter().all(|&v| v == 77));
    }

    #[test]
    fn halving_averages_each_block() {
        // 5x3: the last column and row are dropped; blocks rounded to nearest.
        let img = GrayImage::from_raw(
            5,
            3,
            vec![0, 2, 10, 11, 99, 1, 2, 12, 13, 99, 99, 99, 99, 99, 99],
        )
        .expect("size");
        let mut out = vec![7; 3];
        assert_eq!(halve(img.view(), &mut out), (2, 1));
        assert_eq!(out, vec![1, 12]);
        // A ramp in x keeps its slope halved per pixel and moves as (x - 0.5) / 2.
        let ramp: Vec<u8> = (0..8 * 4).map(|i| (i % 8 * 20) as u8).collect();
        let img = GrayImage::from_raw(8, 4, ramp).expect("size");
        halve(img.view(), &mut out);
        assert_eq!(out[..4], [10, 50, 90, 130]);
        // Too small to halve: empty.
        let one = GrayImage::from_raw(1, 1, vec![5]).expect("size");
        assert_eq!(halve(one.view(), &mut out), (0, 0));
        assert!(out.is_empty());
    }

    #[test]
    fn doubling_interpolates_bicubically() {
        let (mut tmp, mut out) = (Vec::new(), Vec::new());
        // A flat image stays flat; the taps sum to 256.
        assert_eq!(DOUBLE_TAPS.iter().sum::<i32>(), 256);
        let flat = GrayImage::from_raw(3, 2, vec![77; 6]).expect("size");
        assert_eq!(double(flat.view(), &mut tmp, &mut out), (6, 4));
        assert!(out.iter().all(|&v| v == 77));
        // A linear ramp 10 x + 40 (away from the clamped borders) is sampled at
        // x = (X − 0.5) / 2: the cubic kernel reproduces linear functions.
        let w = 12;
        let ramp: Vec<u8> = (0..w * 6).map(|i| (10 * (i % w) + 40) as u8).collect();
        let img = GrayImage::from_raw(w, 6, ramp).expect("size");
        let (w2, _) = double(img.view(), &mut tmp, &mut out);
        for xx in 4..w2 - 4 {
            let expected = 10.0 * (xx as f64 - 0.5) / 2.0 + 40.0;
            let got = f64::from(out[5 * w2 + xx]);
            assert!(
                (got - expected).abs() <= 0.5,
                "column {xx}: {got} vs {expected}"
            );
        }
        // Halving a doubled smooth image gives it back within a grey level.
        let smooth: Vec<u8> = (0..20 * 10)
            .map(|i| {
                let (x, y) = ((i % 20) as f64, (i / 20) as f64);
                (128.0 + 60.0 * (x / 3.0).sin() * (y / 4.0).cos()).round() as u8
            })
            .collect();
        let img = GrayImage::from_raw(20, 10, smooth.clone()).expect("size");
        let (w2, h2) = double(img.view(), &mut tmp, &mut out);
        let doubled = GrayImage::from_raw(w2, h2, out.clone()).expect("size");
        let mut back = Vec::new();
        assert_eq!(halve(doubled.view(), &mut back), (20, 10));
        for (i, (a, b)) in back.iter().zip(&smooth).enumerate() {
            let (x, y) = (i % 20, i / 20);
            if (2..18).contains(&x) && (2..8).contains(&y) {
                assert!(a.abs_diff(*b) <= 1, "({x}, {y}): {a} vs {b}");
            }
        }
    }

    #[test]
    fn blur_matches_the_clamped_definition() {
        for (w, h) in [(1, 1), (3, 2), (4, 7), (5, 5), (13, 9)] {
            let data = crate::test_noise::noise_bytes(w * h, 7);
            let at = |x: isize, y: isize| {
                let (x, y) = (x.clamp(0, w as isize - 1), y.clamp(0, h as isize - 1));
                u32::from(data[y as usize * w + x as usize])
            };
            let k = [1, 4, 6, 4, 1];
            let img = GrayImage::from_raw(w, h, data.clone()).expect("size");
            let (mut t, mut o) = (Vec::new(), Vec::new());
            blur5(img.view(), &mut t, &mut o);
            for y in 0..h as isize {
                for x in 0..w as isize {
                    let mut sum = 0;
                    for (j, kj) in k.iter().enumerate() {
                        for (i, ki) in k.iter().enumerate() {
                            sum += kj * ki * at(x + i as isize - 2, y + j as isize - 2);
                        }
                    }
                    assert_eq!(u32::from(o[y as usize * w + x as usize]), (sum + 128) >> 8);
                }
            }
        }
    }

    #[cfg(feature = "png")]
    #[test]
    fn load_errors_name_the_file() {
        let missing = Path::new("/nonexistent/dir/x.png");
        let e = GrayImage::load_png(missing).expect_err("missing");
        assert!(e.to_string().contains("/nonexistent/dir/x.png"));
        let dir = std::env::temp_dir().join(format!("swarmpose-vision-img-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("tmp");
        let bad = dir.join("bad.png");
        std::fs::write(&bad, b"not a png").expect("write");
        let e = GrayImage::load_png(&bad).expect_err("bad");
        assert!(e.to_string().contains("bad.png") && e.to_string().contains("PNG"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
