//! Drawing matches between two frames side by side (the paper's figure 9): frame I on
//! the left, frame J on the right, a line per match; once an estimator has run, inliers
//! in green and outliers in red (yellow when no classification is given). And one
//! frame's inliers on its own image ([`draw_tracks`]): a line from where each feature was
//! in the frame it was matched to, a marker where it is now.

use crate::features::GrayView;

/// Colour of a match without classification.
pub const UNCLASSIFIED: [u8; 3] = [255, 220, 0];
/// Colour of an inlier.
pub const INLIER: [u8; 3] = [0, 230, 0];
/// Colour of an outlier.
pub const OUTLIER: [u8; 3] = [255, 40, 40];

/// An RGB canvas, row-major, 3 bytes per pixel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Canvas {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Pixels, `3 * (y * width + x)` is the red byte of `(x, y)`.
    pub rgb: Vec<u8>,
}

impl Canvas {
    /// A black canvas.
    #[must_use]
    pub fn black(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            rgb: vec![0; 3 * width * height],
        }
    }

    /// Copies the gray image `img` in, its left column at column `x_off`; what does not
    /// fit is cut.
    pub fn paste(&mut self, img: GrayView<'_>, x_off: usize) {
        let w = img.width.min(self.width.saturating_sub(x_off));
        for y in 0..img.height.min(self.height) {
            for x in 0..w {
                let g = img.data[y * img.width + x];
                let i = 3 * (y * self.width + x + x_off);
                self.rgb[i..i + 3].copy_from_slice(&[g, g, g]);
            }
        }
    }

    /// Sets one pixel; outside is ignored.
    pub fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let i = 3 * (y as usize * self.width + x as usize);
            self.rgb[i..i + 3].copy_from_slice(&c);
        }
    }

    /// A straight line (Bresenham) between two pixels.
    pub fn line(&mut self, a: (f32, f32), b: (f32, f32), c: [u8; 3]) {
        let (mut x0, mut y0) = (a.0.round() as i64, a.1.round() as i64);
        let (x1, y1) = (b.0.round() as i64, b.1.round() as i64);
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
        let mut err = dx + dy;
        loop {
            self.put(x0, y0, c);
            if x0 == x1 && y0 == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x0 += sx;
            }
            if e2 <= dx {
                err += dx;
                y0 += sy;
            }
        }
    }

    /// A small square marker of half-size 2 pixels.
    pub fn marker(&mut self, p: (f32, f32), c: [u8; 3]) {
        let (x, y) = (p.0.round() as i64, p.1.round() as i64);
        for d in -2..=2 {
            self.put(x + d, y - 2, c);
            self.put(x + d, y + 2, c);
            self.put(x - 2, y + d, c);
            self.put(x + 2, y + d, c);
        }
    }

    #[cfg(feature = "png")]
    /// The canvas as the bytes of an RGB PNG file (the caller writes them where it
    /// chooses).
    ///
    /// # Errors
    /// The encoder's message.
    pub fn png(&self) -> Result<Vec<u8>, String> {
        use image::ImageEncoder;
        let mut out = Vec::new();
        image::codecs::png::PngEncoder::new(&mut out)
            .write_image(
                &self.rgb,
                self.width as u32,
                self.height as u32,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(|e| format!("cannot encode PNG: {e}"))?;
        Ok(out)
    }
}

/// Frame I (`dst_img`) and frame J (`src_img`) side by side with a line from each
/// `dst_pixels[k]` to `src_pixels[k]`; `inlier[k]` picks the colour when given.
#[must_use]
pub fn draw_matches(
    dst_img: GrayView<'_>,
    src_img: GrayView<'_>,
    dst_pixels: &[(f32, f32)],
    src_pixels: &[(f32, f32)],
    inlier: Option<&[bool]>,
) -> Canvas {
    let width = dst_img.width + src_img.width;
    let height = dst_img.height.max(src_img.height);
    let mut canvas = Canvas::black(width, height);
    canvas.paste(dst_img, 0);
    canvas.paste(src_img, dst_img.width);
    let off = dst_img.width as f32;
    // Outliers first so inliers stay visible on top.
    let colour = |k: usize| match inlier {
        None => UNCLASSIFIED,
        Some(v) if v.get(k).copied().unwrap_or(false) => INLIER,
        Some(_) => OUTLIER,
    };
    let mut order: Vec<usize> = (0..dst_pixels.len().min(src_pixels.len())).collect();
    order.sort_by_key(|&k| colour(k) == INLIER);
    for k in order {
        let c = colour(k);
        let a = dst_pixels[k];
        let b = (src_pixels[k].0 + off, src_pixels[k].1);
        canvas.line(a, b, c);
        canvas.marker(a, c);
        canvas.marker(b, c);
    }
    canvas
}

/// The image `img` with its tracked features: for each `k`, a line from
/// `reference_pixels[k]` (where the feature was in the frame it was matched to) to
/// `pixels[k]` and a marker at `pixels[k]`, in the inlier colour.
#[must_use]
pub fn draw_tracks(
    img: GrayView<'_>,
    pixels: &[(f32, f32)],
    reference_pixels: &[(f32, f32)],
) -> Canvas {
    let mut canvas = Canvas::black(img.width, img.height);
    canvas.paste(img, 0);
    for (&b, &a) in pixels.iter().zip(reference_pixels) {
        canvas.line(a, b, INLIER);
        canvas.marker(b, INLIER);
    }
    canvas
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_side_by_side_with_colours() {
        let a = vec![10u8; 20 * 10];
        let b = vec![200u8; 20 * 10];
        fn view(d: &[u8]) -> GrayView<'_> {
            GrayView {
                width: 20,
                height: 10,
                data: d,
            }
        }
        let c = draw_matches(
            view(&a),
            view(&b),
            &[(5.0, 5.0), (2.0, 2.0)],
            &[(5.0, 5.0), (2.0, 8.0)],
            Some(&[true, false]),
        );
        assert_eq!((c.width, c.height), (40, 10));
        let px = |x: usize, y: usize| &c.rgb[3 * (y * 40 + x)..3 * (y * 40 + x) + 3];
        // The inlier's line is green along row 5 between the halves.
        assert_eq!(px(15, 5), &INLIER);
        // Untouched pixels keep the gray levels of each frame.
        assert_eq!(px(10, 0), &[10, 10, 10]);
        assert_eq!(px(35, 0), &[200, 200, 200]);
        assert!(c.rgb.chunks(3).any(|p| p == OUTLIER));
    }

    #[test]
    fn draws_tracks_on_the_image() {
        let a: Vec<u8> = (0..200).map(|i| i as u8).collect();
        let img = GrayView {
            width: 20,
            height: 10,
            data: &a,
        };
        let c = draw_tracks(img, &[(15.0, 5.0)], &[(5.0, 5.0)]);
        assert_eq!((c.width, c.height), (20, 10));
        let px = |x: usize, y: usize| &c.rgb[3 * (y * 20 + x)..3 * (y * 20 + x) + 3];
        // The track along row 5 and the marker's corner at (13, 3).
        assert_eq!(px(10, 5), &INLIER);
        assert_eq!(px(13, 3), &INLIER);
        // Elsewhere the image's gray level.
        assert_eq!(px(1, 0), &[1, 1, 1]);
        assert_eq!(px(19, 9), &[199, 199, 199]);
    }
}
