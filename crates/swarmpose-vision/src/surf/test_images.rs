//! Synthetic images for the unit tests.

/// A Gaussian blob of standard deviation `sigma` at the image centre: bright (≈ 220) on a
/// dark (≈ 40) background, or the reverse.
pub(crate) fn gaussian_blob(w: usize, h: usize, sigma: f32, bright: bool) -> Vec<u8> {
    let (cx, cy) = ((w / 2) as f32, (h / 2) as f32);
    (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32 - cx, (k / w) as f32 - cy);
            let g = (-(x * x + y * y) / (2.0 * sigma * sigma)).exp();
            let v = if bright {
                40.0 + 180.0 * g
            } else {
                220.0 - 180.0 * g
            };
            v.round() as u8
        })
        .collect()
}

/// A smooth deterministic texture: 60 anisotropic Gaussian blobs of random size,
/// elongation, orientation and sign on a mid-grey background.
pub(crate) fn texture(w: usize, h: usize, seed: u64) -> Vec<u8> {
    let mut state = seed ^ 0x9E37_79B9_7F4A_7C15;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    };
    let blobs: Vec<[f32; 6]> = (0..60)
        .map(|_| {
            let sx = 1.5 + 5.0 * next();
            let sy = sx * (0.4 + 0.6 * next());
            [
                next() * w as f32,
                next() * h as f32,
                sx,
                sy,
                next() * std::f32::consts::PI,
                (next() - 0.5) * 240.0,
            ]
        })
        .collect();
    let mut img = vec![128.0f32; w * h];
    for &[bx, by, sx, sy, phi, amp] in &blobs {
        let (s, c) = phi.sin_cos();
        let reach = 3.5 * sx;
        let (x0, x1) = (
            (bx - reach).max(0.0) as usize,
            ((bx + reach) as usize).min(w),
        );
        let (y0, y1) = (
            (by - reach).max(0.0) as usize,
            ((by + reach) as usize).min(h),
        );
        for y in y0..y1 {
            for x in x0..x1 {
                let (dx, dy) = (x as f32 - bx, y as f32 - by);
                let (u, v) = (c * dx + s * dy, -s * dx + c * dy);
                img[y * w + x] +=
                    amp * (-(u * u / (2.0 * sx * sx) + v * v / (2.0 * sy * sy))).exp();
            }
        }
    }
    img.into_iter()
        .map(|v| v.round().clamp(0.0, 255.0) as u8)
        .collect()
}
