//! Acceptance test: "SURF detects repeatably: on a real image rotated and scaled by a
//! known homography, at least 60 % of the keypoints are found again within 2 px."
//!
//! The image is the first left KITTI frame, `$SWARMPOSE_DATA/kitti_vo_seq2/image_0/000000.png`
//! (default data root `../../../shared/data` from this crate). Without it the test is
//! skipped with a message, unless `CI=true`, where it fails.
//!
//! The image `A` is warped by a similarity `H` about its centre `c`,
//! `p = c + σ R(θ) (q − c)`, with a bilinear warp `B(p) = A(H⁻¹ p)`. Every keypoint `q`
//! of `A` whose image `H q` falls in the part of `B` that is filled from `A`, at least
//! `MARGIN` pixels from both images' borders, counts; it is repeated when `B` has a
//! detection within 2 px of `H q`. The repeatability is repeated / counted.
//!
//! Beside it the tests print the keypoint counts of `A` and `B` and the symmetric form
//! repeated / min(counted, `B`'s keypoints in the same overlap), so that a detector
//! cannot look repeatable by flooding `B` with detections (the symmetric form counts
//! keypoints of `A`, several of which may share one of `B`, so it can exceed 100 % when
//! `B` has far fewer keypoints).

use std::time::Instant;

use swarmpose_vision::features::{Descriptor, FeatureExtractor, GrayView, Keypoint};
use swarmpose_vision::surf::{Surf, SurfConfig};

/// Distance from both images' borders, pixels (in the warped image), for a keypoint to
/// count.
const MARGIN: f32 = 24.0;

/// Localisation tolerance, pixels.
const TOLERANCE: f32 = 2.0;

/// An owned 8-bit grayscale image.
struct Frame {
    w: usize,
    h: usize,
    pixels: Vec<u8>,
}

impl Frame {
    fn view(&self) -> GrayView<'_> {
        GrayView {
            width: self.w,
            height: self.h,
            data: &self.pixels,
        }
    }
}

/// The KITTI frame, or `None` (skip) when it is absent outside CI.
fn load_kitti() -> Option<Frame> {
    let path = swarmpose_testdata::dataset_for_test("kitti_vo_seq2")?.join("image_0/000000.png");
    let img = match image::open(&path) {
        Ok(img) => img.to_luma8(),
        Err(e) => panic!("cannot read {}: {e}", path.display()),
    };
    let (w, h) = (img.width() as usize, img.height() as usize);
    Some(Frame {
        w,
        h,
        pixels: img.into_raw(),
    })
}

/// A similarity about the point `(cx, cy)`: `p = c + scale · R(angle) · (q − c)`.
#[derive(Clone, Copy)]
struct Similarity {
    cx: f32,
    cy: f32,
    scale: f32,
    angle: f32,
}

impl Similarity {
    fn apply(&self, x: f32, y: f32) -> (f32, f32) {
        let (s, c) = self.angle.sin_cos();
        let (dx, dy) = (x - self.cx, y - self.cy);
        (
            self.cx + self.scale * (c * dx - s * dy),
            self.cy + self.scale * (s * dx + c * dy),
        )
    }

    fn inverse(&self) -> Self {
        Self {
            scale: 1.0 / self.scale,
            angle: -self.angle,
            ..*self
        }
    }
}

/// `B(p) = A(H⁻¹ p)` with bilinear interpolation, same size as `A`, 0 outside `A`.
fn warp(w: usize, h: usize, src: &[u8], warp: Similarity) -> Vec<u8> {
    let inv = warp.inverse();
    let mut out = vec![0u8; w * h];
    let at = |x: usize, y: usize| f32::from(src[y * w + x]);
    for y in 0..h {
        for x in 0..w {
            let (sx, sy) = inv.apply(x as f32, y as f32);
            if sx < 0.0 || sy < 0.0 || sx > (w - 1) as f32 || sy > (h - 1) as f32 {
                continue;
            }
            let (x0, y0) = (sx.floor() as usize, sy.floor() as usize);
            let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
            let (fx, fy) = (sx - x0 as f32, sy - y0 as f32);
            let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
            let bottom = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
            out[y * w + x] = (top * (1.0 - fy) + bottom * fy).round() as u8;
        }
    }
    out
}

/// Distance of `(x, y)` to the border of a `w × h` image (negative outside).
fn inside_by(x: f32, y: f32, w: usize, h: usize) -> f32 {
    x.min(y).min((w - 1) as f32 - x).min((h - 1) as f32 - y)
}

/// Counts of [`repeatability`].
#[derive(Debug, Clone, Copy)]
struct Counts {
    /// Keypoints of `A` whose image lies in the overlap (the denominator).
    counted: usize,
    /// Those with a keypoint of `B` within `TOLERANCE`.
    repeated: usize,
    /// Keypoints of `B` in the same overlap (for the symmetric form only).
    b_counted: usize,
    /// All keypoints of `B`.
    b_total: usize,
}

impl Counts {
    /// repeated / counted.
    fn rate(&self) -> f32 {
        self.repeated as f32 / self.counted.max(1) as f32
    }

    /// repeated / min(counted, b_counted).
    fn symmetric_rate(&self) -> f32 {
        self.repeated as f32 / self.counted.min(self.b_counted).max(1) as f32
    }
}

/// The keypoints of `a` found again in `b` under `warp`.
fn repeatability(a: &[Keypoint], b: &[Keypoint], w: usize, h: usize, warp: Similarity) -> Counts {
    let inv = warp.inverse();
    let b_counted = b
        .iter()
        .filter(|q| {
            let (x, y) = inv.apply(q.x, q.y);
            inside_by(q.x, q.y, w, h) >= MARGIN && inside_by(x, y, w, h) >= MARGIN / warp.scale
        })
        .count();
    let (mut counted, mut repeated) = (0, 0);
    for k in a {
        let (px, py) = warp.apply(k.x, k.y);
        // The disc of radius MARGIN around p in B comes from the disc of radius
        // MARGIN / scale around k in A.
        if inside_by(px, py, w, h) < MARGIN || inside_by(k.x, k.y, w, h) < MARGIN / warp.scale {
            continue;
        }
        counted += 1;
        let hit = b.iter().any(|q| {
            let (dx, dy) = (q.x - px, q.y - py);
            dx * dx + dy * dy <= TOLERANCE * TOLERANCE
        });
        repeated += usize::from(hit);
    }
    Counts {
        counted,
        repeated,
        b_counted,
        b_total: b.len(),
    }
}

/// The detector, the KITTI frame and its keypoints.
struct Setup {
    surf: Surf,
    frame: Frame,
    keypoints: Vec<Keypoint>,
}

impl Setup {
    /// Detections of the default configuration on the KITTI frame (positions do not
    /// depend on the orientation, so the faster upright variant is used); `None` to skip.
    fn kitti() -> Option<Self> {
        let frame = load_kitti()?;
        let surf = Surf::new(SurfConfig::upright());
        let start = Instant::now();
        let keypoints = surf.detect(frame.view());
        println!(
            "{} keypoints in the {}x{} KITTI frame (detection {:.1} ms at this build's opt-level)",
            keypoints.len(),
            frame.w,
            frame.h,
            start.elapsed().as_secs_f64() * 1e3
        );
        assert!(keypoints.len() >= 200, "only {} keypoints", keypoints.len());
        Some(Self {
            surf,
            frame,
            keypoints,
        })
    }

    /// Warps the frame by `warp_h`, detects in it and counts the repeated keypoints.
    fn repeatability_under(&self, warp_h: Similarity) -> Counts {
        let Frame { w, h, .. } = self.frame;
        let warped = Frame {
            w,
            h,
            pixels: warp(w, h, &self.frame.pixels, warp_h),
        };
        let b = self.surf.detect(warped.view());
        repeatability(&self.keypoints, &b, w, h, warp_h)
    }

    /// Repeatability under the similarity of `scale` and `degrees` about the image
    /// centre, printed with `label`.
    fn run(&self, label: &str, scale: f32, degrees: f32) -> f32 {
        let warp_h = Similarity {
            cx: (self.frame.w - 1) as f32 / 2.0,
            cy: (self.frame.h - 1) as f32 / 2.0,
            scale,
            angle: degrees.to_radians(),
        };
        let counts = self.repeatability_under(warp_h);
        let Counts {
            counted,
            repeated,
            b_counted,
            b_total,
        } = counts;
        println!(
            "{label:<20} scale {scale:.2} rotation {degrees:>4.1}°: {repeated} / {counted} keypoints repeated within {TOLERANCE} px = {:.1} %; \
             keypoints A {} B {b_total} (in the overlap {counted} and {b_counted}), symmetric {repeated} / {} = {:.1} %",
            100.0 * counts.rate(),
            self.keypoints.len(),
            counted.min(b_counted),
            100.0 * counts.symmetric_rate(),
        );
        assert!(
            counted >= 100,
            "{label}: only {counted} keypoints in the overlap"
        );
        counts.rate()
    }
}

/// The acceptance criterion: >= 60 % under rotation 30° and scale 0.8.
///
/// Measured with the default configuration: 562 / 871 = 64.5 % (1249 keypoints in `A`,
/// 1131 in `B`; symmetric form 562 / 744 = 75.5 %). The paper's algorithm as first
/// written repeated 43 % (1163 keypoints); the gain comes from the finest-layer maxima,
/// the smoothed octaves and keeping the maxima whose interpolation does not settle (see
/// the `surf` module documentation for what each contributes).
#[test]
fn surf_detects_repeatably_under_a_known_similarity() {
    let Some(setup) = Setup::kitti() else {
        return;
    };
    let both = setup.run("rotation and scale", 0.8, 30.0);
    assert!(
        both >= 0.6,
        "repeatability under rotation 30° and scale 0.8 is {:.1} % < 60 %",
        100.0 * both
    );
}

/// Each part of the similarity alone (scale 0.8 without rotation, rotation 30° without
/// scaling) under the bar of 60 % (a detector that repeats under both together
/// must repeat under each alone: each is the combined warp with one distortion taken
/// away), and an exact 90° rotation (about a pixel, so no resampling) as a correctness
/// check. Measured when written: 64.6 % (scale only), 70.4 % (rotation only).
#[test]
fn surf_repeats_under_each_part_and_an_exact_rotation() {
    let Some(setup) = Setup::kitti() else {
        return;
    };
    let scale_only = setup.run("scale only", 0.8, 0.0);
    let rotation_only = setup.run("rotation only", 1.0, 30.0);
    assert!(scale_only >= 0.6, "scale only: {:.1} %", 100.0 * scale_only);
    assert!(
        rotation_only >= 0.6,
        "rotation only: {:.1} %",
        100.0 * rotation_only
    );

    // 90° about the pixel (620, 188) maps pixels onto pixels: the box filters see the
    // same sums, so nearly every keypoint must come back.
    let exact = Similarity {
        cx: 620.0,
        cy: 188.0,
        scale: 1.0,
        angle: std::f32::consts::FRAC_PI_2,
    };
    let counts = setup.repeatability_under(exact);
    let (counted, repeated) = (counts.counted, counts.repeated);
    let rate = counts.rate();
    // Measured 340 / 341 = 99.7 %.
    println!(
        "exact 90° rotation: {repeated} / {counted} keypoints repeated = {:.1} %; symmetric {:.1} %",
        100.0 * rate,
        100.0 * counts.symmetric_rate()
    );
    assert!(
        counted >= 100 && rate >= 0.97,
        "exact 90°: {:.1} %",
        100.0 * rate
    );
}

#[test]
fn surf_extracts_oriented_features_on_kitti() {
    let Some(frame) = load_kitti() else {
        return;
    };
    for surf in [Surf::default(), Surf::upright()] {
        let start = Instant::now();
        let f = surf.extract(frame.view());
        println!(
            "{}: {} features in {:.1} ms at this build's opt-level",
            surf.name(),
            f.len(),
            start.elapsed().as_secs_f64() * 1e3
        );
        assert!(f.len() >= 200);
        assert_eq!(f.descriptors.len(), f.len());
        assert!(
            f.keypoints.iter().all(|k| {
                k.x >= 0.0 && k.y >= 0.0 && k.x < frame.w as f32 && k.y < frame.h as f32
            })
        );
    }
}

/// Descriptor matching under the rotation-and-scale warp: nearest neighbours with the
/// same Laplacian sign and Lowe's ratio test; a match is correct when the matched
/// keypoint lies within 3 px of the mapped one. Returns (matches, correct).
fn match_under(surf: &Surf, frame: &Frame, warp_h: Similarity) -> (usize, usize) {
    let warped = Frame {
        w: frame.w,
        h: frame.h,
        pixels: warp(frame.w, frame.h, &frame.pixels, warp_h),
    };
    let a = surf.extract_with_laplacian(frame.view());
    let b = surf.extract_with_laplacian(warped.view());
    let (mut matches, mut correct) = (0, 0);
    for (i, (ka, da)) in a
        .features
        .keypoints
        .iter()
        .zip(&a.features.descriptors)
        .enumerate()
    {
        let (px, py) = warp_h.apply(ka.x, ka.y);
        if inside_by(px, py, frame.w, frame.h) < MARGIN
            || inside_by(ka.x, ka.y, frame.w, frame.h) < MARGIN / warp_h.scale
        {
            continue;
        }
        let (mut best, mut second, mut best_j) = (f32::MAX, f32::MAX, 0);
        for (j, db) in b.features.descriptors.iter().enumerate() {
            if !a.same_laplacian(i, &b, j) {
                continue;
            }
            let d = da.distance(db);
            if d < best {
                (second, best, best_j) = (best, d, j);
            } else if d < second {
                second = d;
            }
        }
        if best < 0.8 * second {
            matches += 1;
            let kb = b.features.keypoints[best_j];
            correct += usize::from((kb.x - px).hypot(kb.y - py) <= 3.0);
        }
    }
    (matches, correct)
}

#[test]
fn oriented_descriptors_match_under_rotation_and_scale() {
    let Some(frame) = load_kitti() else {
        return;
    };
    let warp_h = Similarity {
        cx: (frame.w - 1) as f32 / 2.0,
        cy: (frame.h - 1) as f32 / 2.0,
        scale: 0.8,
        angle: 30f32.to_radians(),
    };
    let mut rates = Vec::new();
    for surf in [Surf::default(), Surf::upright()] {
        let (matches, correct) = match_under(&surf, &frame, warp_h);
        let rate = correct as f32 / matches.max(1) as f32;
        println!(
            "{}: {correct} / {matches} ratio-test matches correct within 3 px = {:.1} % (rotation 30°, scale 0.8)",
            surf.name(),
            100.0 * rate
        );
        rates.push((matches, correct, rate));
    }
    // Measured: 130 / 185 = 70.3 % (143 / 212 = 67.5 % before the detector changes that
    // raised the repeatability from 43 % to 64.5 %). The wrong ones are mostly keypoints
    // of the original that were not detected again, whose nearest descriptor still
    // passes the ratio test.
    let (matches, correct, rate) = rates[0];
    assert!(matches >= 100 && rate >= 0.6, "surf: {correct} / {matches}");
    // Upright SURF is not made for a 30° roll: it finds fewer correct matches.
    assert!(
        rates[1].1 < correct,
        "upright {:?} vs oriented {:?}",
        rates[1],
        rates[0]
    );
}
