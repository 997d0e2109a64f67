//! [`super::align_window`] against its definition with indices (before its sums ran over
//! zipped rows): bit for bit; [`super::ssd_fixed`] against [`super::ssd`].

use super::{PairWindow, align_window, ssd, ssd_fixed};
use crate::features::GrayView;
use crate::image::sample_patch;
use crate::test_noise::Lcg;

/// [`align_window`] with every sample found by its index.
fn by_definition(
    window: PairWindow<'_>,
    d0: f32,
    iterations: usize,
    disparity_free: bool,
) -> Option<(f32, f32)> {
    let PairWindow {
        left,
        right,
        xl,
        y,
        r,
    } = window;
    let (n, m) = (2 * r + 1, 2 * r + 3);
    if m > 13
        || y < r + 4
        || y + r + 4 >= left.height.min(right.height)
        || xl < r
        || xl + r >= left.width
    {
        return None;
    }
    let mut lw = [0f32; 169];
    for (j, yy) in (y - r..=y + r).enumerate() {
        for (i, xx) in (xl - r..=xl + r).enumerate() {
            lw[j * n + i] = f32::from(left.data[yy * left.width + xx]);
        }
    }
    let mut rw = [0f32; 169];
    let (mut d, mut dy) = (d0, 0f32);
    for _ in 0..iterations {
        let (x0, y0) = (
            xl as f32 - d - r as f32 - 1.0,
            y as f32 + dy - r as f32 - 1.0,
        );
        sample_patch(right, x0, y0, m, &mut rw)?;
        let (mut a, mut b, mut c, mut ex, mut ey) = (0f32, 0f32, 0f32, 0f32, 0f32);
        for j in 0..n {
            for i in 0..n {
                let k = (j + 1) * m + i + 1;
                let e = lw[j * n + i] - rw[k];
                let gy = -0.5 * (rw[k + m] - rw[k - m]);
                c += gy * gy;
                ey += gy * e;
                if disparity_free {
                    let gx = 0.5 * (rw[k + 1] - rw[k - 1]);
                    a += gx * gx;
                    b += gx * gy;
                    ex += gx * e;
                }
            }
        }
        let (sd, sy) = if disparity_free {
            let det = a * c - b * b;
            if !(det > 1e-6 * (a * c).max(1e-3) && a >= 1e-3) {
                return None;
            }
            (-(c * ex - b * ey) / det, -(a * ey - b * ex) / det)
        } else {
            if c < 1e-3 {
                return None;
            }
            (0.0, -ey / c)
        };
        d += sd;
        dy += sy;
        if (d - d0).abs() > 1.0 || dy.abs() > 2.0 {
            return None;
        }
        if sd.abs() < 1e-3 && sy.abs() < 1e-3 {
            break;
        }
    }
    Some((d, dy))
}

/// Textured pairs with noise, every window half side 1 to 6 (6 is refused), windows all
/// over the image and at its borders, disparities near the truth and off it: the same
/// `(d, dy)`, bit for bit, or the same refusal, for the disparity free and fixed.
#[test]
fn align_window_is_its_definition_bit_for_bit() {
    let (w, h) = (96usize, 40usize);
    let mut g = Lcg(34);
    let f = |x: f32, y: f32| {
        128.0 + 60.0 * ((x + y) * 0.5).sin() + 25.0 * (x * 0.31).cos() * (y * 0.23).sin()
    };
    let mut image = |dx: f32, dy: f32| -> Vec<u8> {
        (0..w * h)
            .map(|i| {
                let noise = (g.next_u32() >> 29) as f32;
                (f((i % w) as f32 + dx, (i / w) as f32 - dy) + noise).round() as u8
            })
            .collect()
    };
    let (left, right) = (image(0.0, 0.0), image(6.6, 0.4));
    let view = |data| GrayView {
        width: w,
        height: h,
        data,
    };
    let mut found = 0;
    for r in 1..=6 {
        for y in (0..h).step_by(3) {
            for xl in (0..w).step_by(5) {
                let window = PairWindow {
                    left: view(&left),
                    right: view(&right),
                    xl,
                    y,
                    r,
                };
                for d0 in [6.6f32, 6.0, 7.3, 0.2, 30.0] {
                    for free in [true, false] {
                        let got = align_window(window, d0, 8, free);
                        assert_eq!(
                            got.map(|(d, dy)| (d.to_bits(), dy.to_bits())),
                            by_definition(window, d0, 8, free)
                                .map(|(d, dy)| (d.to_bits(), dy.to_bits())),
                            "r {r}, ({xl}, {y}), d0 {d0}, free {free}"
                        );
                        found += usize::from(got.is_some());
                    }
                }
            }
        }
    }
    assert!(found > 2_000, "{found}");
}

/// [`align_window`] inlined into a dispatched kernel, over windows and starting disparities.
struct Windows<'a>(GrayView<'a>, GrayView<'a>, &'a [(usize, usize, usize, f32)]);

impl crate::simd::Kernel for Windows<'_> {
    type Output = Vec<Option<(u32, u32)>>;

    #[inline(always)]
    fn run(self) -> Self::Output {
        let mut out = Vec::new();
        for &(xl, y, r, d0) in self.2 {
            let window = PairWindow {
                left: self.0,
                right: self.1,
                xl,
                y,
                r,
            };
            for free in [true, false] {
                let got = align_window(window, d0, 8, free);
                out.push(got.map(|(d, dy)| (d.to_bits(), dy.to_bits())));
            }
        }
        out
    }
}

/// The dispatched compilation of [`align_window`] (vector blocks of products) gives its
/// baseline's `(d, dy)`, bit for bit, on noise images with random windows and disparities.
#[test]
fn align_window_is_the_same_dispatched() {
    let (w, h) = (80usize, 36usize);
    let (left, right) = (
        crate::test_noise::noise_bytes(w * h, 361),
        crate::test_noise::noise_bytes(w * h, 362),
    );
    let view = |data| GrayView {
        width: w,
        height: h,
        data,
    };
    let mut g = Lcg(36);
    let windows: Vec<(usize, usize, usize, f32)> = (0..4_000)
        .map(|_| {
            let r = 1 + g.next_u32() as usize % 5;
            let (xl, y) = (g.next_u32() as usize % w, g.next_u32() as usize % h);
            let d0 = (g.next_u32() >> 8) as f32 / (1u32 << 24) as f32 * 20.0;
            (xl, y, r, d0)
        })
        .collect();
    let run = || crate::simd::dispatch(Windows(view(&left), view(&right), &windows));
    let (got, base) = (run(), crate::simd::baseline(run));
    assert_eq!(got, base);
    let found = got.iter().filter(|p| p.is_some()).count();
    assert!(found > 500, "{found} alignments");
}

/// [`ssd_fixed`] as it was before it summed all 8 lanes: the lanes past the window masked
/// (the buffer's end is left to [`ssd`]).
fn masked_ssd_fixed<const N: usize>(window: PairWindow<'_>, xr: usize) -> u32 {
    const LANES: usize = 8;
    let (left, right, xl, y, r) = (window.left, window.right, window.xl, window.y, window.r);
    if (y + r) * left.width + xl - r + LANES > left.data.len()
        || (y + r) * right.width + xr - r + LANES > right.data.len()
    {
        return ssd(window, xr);
    }
    let mut sums = [0u32; LANES];
    for yy in y - r..=y + r {
        let lrow = &left.data[yy * left.width + xl - r..][..LANES];
        let rrow = &right.data[yy * right.width + xr - r..][..LANES];
        for k in 0..LANES {
            let d = i32::from(lrow[k]) - i32::from(rrow[k]);
            sums[k] += if k < N { (d * d) as u32 } else { 0 };
        }
    }
    sums.iter().sum()
}

/// [`ssd_fixed`] for the 7 x 7 window gives [`ssd`]'s sums, and its previous computation's
/// ([`masked_ssd_fixed`]), on noise images, all over the images up to their borders
/// (the last rows through [`ssd`]), including identical windows (sum 0) and the largest
/// differences (black against white).
#[test]
fn fixed_ssd_is_ssd() {
    let (w, h) = (60usize, 20usize);
    let left = crate::test_noise::noise_bytes(w * h, 363);
    let mut right = crate::test_noise::noise_bytes(w * h, 364);
    for (i, v) in right.iter_mut().enumerate() {
        match (i % w) / 15 {
            0 => *v = left[i],
            1 => *v = if left[i] < 128 { 255 } else { 0 },
            _ => {}
        }
    }
    let view = |data| GrayView {
        width: w,
        height: h,
        data,
    };
    let (mut zero, mut compared) = (0, 0);
    for y in 3..h - 3 {
        for xl in 3..w - 3 {
            let window = PairWindow {
                left: view(&left),
                right: view(&right),
                xl,
                y,
                r: 3,
            };
            for xr in 3..w - 3 {
                let s = ssd(window, xr);
                assert_eq!(ssd_fixed::<7>(window, xr), s, "({xl}, {y}) at {xr}");
                let masked = masked_ssd_fixed::<7>(window, xr);
                assert_eq!(masked, s, "({xl}, {y}) at {xr}");
                zero += usize::from(s == 0);
                compared += 1;
            }
        }
    }
    assert!(zero > 0 && compared > 30_000, "{zero} zero of {compared}");
}
