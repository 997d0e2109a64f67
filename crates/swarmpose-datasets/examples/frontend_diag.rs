//! Diagnostics of the front end on a sequence with ground truth: features, stereo
//! matches, temporal matches, and residuals against the true motion.
//! `cargo run --release -p swarmpose-datasets --example frontend_diag -- DIR [PAIRS]`

use swarmpose_core::{Estimator, PsoEstimator, PsoEstimatorConfig};
use swarmpose_datasets::open;
use swarmpose_vision::frontend::{CHI2_3_99, Frontend, refine_stereo, refine_weighted};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dir = std::path::PathBuf::from(args.get(1).ok_or("usage: DIR [PAIRS]")?);
    let pairs: usize = args.get(2).map_or(Ok(5), |s| s.parse())?;
    let seq = open(&dir)?;
    let mut fe = Frontend::orb(seq.calibration());
    let env = |k: &str, d: f64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    fe.extractor.config.oriented = env("ORIENTED", 0.0) > 0.5;
    fe.extractor.config.fast_threshold = env("FAST", 12.0) as u8;
    if let Some(r) = fe.right_extractor.as_mut() {
        r.config.fast_threshold = env("RFAST", 10.0) as u8;
        r.config.oriented = fe.extractor.config.oriented;
    }
    if let Some(b) = fe.extractor.config.bucketing.as_mut() {
        b.per_cell = env("PERCELL", b.per_cell as f64) as usize;
        b.cell_width = env("CELL", b.cell_width as f64) as usize;
        b.cell_height = b.cell_width;
    }
    fe.stereo.ratio = env("SRATIO", fe.stereo.ratio as f64) as f32;
    fe.stereo.max_distance = env("SDIST", fe.stereo.max_distance as f64) as f32;
    fe.stereo.row_tolerance_px = env("ROWTOL", fe.stereo.row_tolerance_px as f64) as f32;
    fe.temporal.ratio = env("TRATIO", fe.temporal.ratio as f64) as f32;
    fe.temporal.max_distance = env("TDIST", fe.temporal.max_distance as f64) as f32;
    fe.temporal.circular_check = env("CIRC", 0.0) > 0.5;
    fe.temporal.max_displacement_px = Some(env("WIN", 150.0) as f32);
    fe.stereo.min_point_disparity_px = env("MIND", 5.0) as f32;
    fe.stereo.disparity_offset_px = env("DOFF", 0.0) as f32;
    fe.stereo.gauss_newton = env("GN", 1.0) > 0.5;
    fe.stereo.subpixel_radius = env("SUBR", 3.0) as usize;
    let verbose = env("VERBOSE", 0.0) > 0.5;
    let refine = env("REFINE", 1.0) > 0.5;
    let est = PsoEstimator::new(PsoEstimatorConfig::default());
    let (mut counts, mut good, mut times) = (Vec::new(), 0, Vec::new());
    let (mut rot_ok, mut dir_ok, mut ratios) = (0, 0, Vec::new());
    let mut deltas: Vec<f64> = Vec::new();
    let mut prev = None;
    for i in 0..=pairs.min(seq.len() - 1) {
        let p = seq.frame(i)?;
        let t = std::time::Instant::now();
        let f = fe.stereo_frame(p.left.view(), p.right.view());
        let ms = t.elapsed().as_secs_f64() * 1e3;
        times.push(ms);
        if env("ROAD", 0.0) > 0.5 {
            let mut ys: Vec<f64> = f
                .points
                .iter()
                .filter(|p| p.x.abs() < 2.5 && p.z < 20.0 && p.y > 1.0)
                .map(|p| p.y)
                .collect();
            ys.sort_by(f64::total_cmp);
            if !ys.is_empty() {
                println!(
                    "  road points {} median Y {:.3} m",
                    ys.len(),
                    ys[ys.len() / 2]
                );
            }
        }
        if verbose {
            println!(
                "frame {i}: {} left, {} right features, {} stereo ({ms:.1} ms)",
                f.n_left_features,
                f.n_right_features,
                f.len()
            );
        }
        if let Some(pf) = prev.take() {
            let mut m = fe.match_frames(&pf, &f)?;
            let sel = env("SEL", 0.0) as i32;
            if sel != 0 {
                let c = &m.correspondences;
                let keep: Vec<usize> = (0..c.len())
                    .filter(|&k| {
                        let d = c.dst()[k];
                        let below = d.y > 1.0;
                        if sel == 1 { below } else { !below }
                    })
                    .collect();
                let src = keep.iter().map(|&k| c.src()[k]).collect();
                let dst = keep.iter().map(|&k| c.dst()[k]).collect();
                let sig = keep.iter().map(|&k| m.noise_sigma_m[k]).collect();
                m.src_covariances = keep.iter().map(|&k| m.src_covariances[k]).collect();
                m.dst_covariances = keep.iter().map(|&k| m.dst_covariances[k]).collect();
                m.src_disparities_px = keep.iter().map(|&k| m.src_disparities_px[k]).collect();
                m.dst_disparities_px = keep.iter().map(|&k| m.dst_disparities_px[k]).collect();
                m.noise_sigma_m = sig;
                m.correspondences = swarmpose_core::Correspondences::new(src, dst)?;
            }
            let gt = seq.relative_ground_truth(i - 1, i).ok_or("no gt")?;
            counts.push(m.correspondences.len());
            let e = if env("SIGMA", 0.0) > 0.5 {
                est.estimate_seeded(&m.correspondences_with_noise()?, i as u64)?
            } else {
                est.estimate_seeded(&m.correspondences, i as u64)?
            };
            let (pose, ninl) = if refine {
                let (p, inl) = if env("MAHA", 1.0) > 0.5 {
                    refine_stereo(
                        &m.correspondences,
                        &m.src_covariances,
                        &m.dst_covariances,
                        &e.transform,
                        CHI2_3_99,
                        10,
                    )?
                } else {
                    refine_weighted(&m.correspondences_with_noise()?, &e.transform, 3.0, 10)?
                };
                (p, inl.len())
            } else {
                (e.transform, e.inliers.len())
            };
            let d = gt.inverse() * pose;
            let (deg, cm) = (
                d.rotation.angle().to_degrees(),
                d.translation.vector.norm() * 100.0,
            );
            good += usize::from(deg < 0.2 && cm < 5.0);
            rot_ok += usize::from(deg < 0.2);
            let te = pose.translation.vector;
            let tg = gt.translation.vector;
            ratios.push(te.norm() / tg.norm());
            let dir_cm = (te.normalize() * tg.norm() - tg).norm() * 100.0;
            dir_ok += usize::from(deg < 0.2 && dir_cm < 5.0);
            if env("SHOWT", 0.0) > 0.5 {
                println!(
                    "  t_est {:?} t_gt {:?} ratio {:.4}",
                    pose.translation.vector.as_slice(),
                    gt.translation.vector.as_slice(),
                    pose.translation.vector.norm() / gt.translation.vector.norm()
                );
            }
            println!(
                "pair {i}: {} corr, {} inl (pso {}), {deg:.3} deg {cm:.2} cm{}",
                m.correspondences.len(),
                ninl,
                e.inliers.len(),
                if deg < 0.2 && cm < 5.0 { "" } else { " <--" }
            );
            if env("DSIGNED", 0.0) > 0.5 {
                let rig = seq.calibration();
                let mut dd: Vec<f64> = m
                    .correspondences
                    .src()
                    .iter()
                    .zip(m.correspondences.dst())
                    .filter(|(_, d)| d.z < 40.0)
                    .map(|(s, d)| {
                        let p = gt * s;
                        rig.fx * rig.baseline_m / d.z - rig.fx * rig.baseline_m / p.z
                    })
                    .collect();
                dd.sort_by(f64::total_cmp);
                let med = dd[dd.len() / 2];
                let mut ad: Vec<f64> = dd.iter().map(|v| (v - med).abs()).collect();
                ad.sort_by(f64::total_cmp);
                println!(
                    "  signed disparity residual median {med:.3} px, MAD {:.3} px (n {})",
                    ad[ad.len() / 2],
                    dd.len()
                );
            }
            if env("BINS", 0.0) > 0.5 {
                for (lo, hi) in [
                    (0.0, 8.0),
                    (8.0, 12.0),
                    (12.0, 20.0),
                    (20.0, 40.0),
                    (40.0, 80.0),
                ] {
                    let mut rz: Vec<f64> = m
                        .correspondences
                        .src()
                        .iter()
                        .zip(m.correspondences.dst())
                        .filter(|(_, d)| d.z >= lo && d.z < hi)
                        .map(|(s, d)| (d - gt * s).z)
                        .collect();
                    rz.sort_by(f64::total_cmp);
                    if !rz.is_empty() {
                        print!(
                            "  [{lo}-{hi}) n {} med dz {:.3};",
                            rz.len(),
                            rz[rz.len() / 2]
                        );
                    }
                }
                println!();
            }
            if verbose {
                let mut r: Vec<f64> = m
                    .correspondences
                    .src()
                    .iter()
                    .zip(m.correspondences.dst())
                    .map(|(s, d)| (d - gt * s).norm())
                    .collect();
                r.sort_by(f64::total_cmp);
                let rig = seq.calibration();
                let mut img_err: Vec<(f64, f64)> = m
                    .correspondences
                    .src()
                    .iter()
                    .zip(m.correspondences.dst())
                    .map(|(s, d)| {
                        let p = gt * s;
                        let (u, v) = rig.project_left(&p);
                        let (u0, v0) = rig.project_left(d);
                        let disp = |z: f64| rig.fx * rig.baseline_m / z;
                        (
                            ((u - u0).powi(2) + (v - v0).powi(2)).sqrt(),
                            (disp(p.z) - disp(d.z)).abs(),
                        )
                    })
                    .collect();
                let good_px = img_err.iter().filter(|e| e.0 < 2.0).count();
                let good_d = img_err.iter().filter(|e| e.0 < 2.0 && e.1 < 1.0).count();
                img_err.sort_by(|a, b| a.1.total_cmp(&b.1));
                let mut zs: Vec<f64> = m.correspondences.dst().iter().map(|p| p.z).collect();
                zs.sort_by(f64::total_cmp);
                println!(
                    "  pixel err<2px: {good_px}, and disparity err<1px: {good_d}; median disparity err {:.2}; depth median {:.1} m",
                    img_err[img_err.len() / 2].1,
                    zs[zs.len() / 2]
                );
                let n = r.len();
                let within = |x: f64| r.iter().filter(|&&v| v < x).count();
                println!(
                    "  {n} temporal; residual median {:.3} m; <0.1 m {} <0.2 m {} <0.5 m {} <1 m {}",
                    r[n / 2],
                    within(0.1),
                    within(0.2),
                    within(0.5),
                    within(1.0)
                );
            }
        }
        prev = Some(f);
    }
    ratios.sort_by(f64::total_cmp);
    deltas.sort_by(f64::total_cmp);
    if !deltas.is_empty() {
        println!(
            "disparity offset median {:.3} p10 {:.3} p90 {:.3}",
            deltas[deltas.len() / 2],
            deltas[deltas.len() / 10],
            deltas[deltas.len() * 9 / 10]
        );
    }
    println!(
        "rotation < 0.2 deg: {rot_ok}; with the translation scaled to the truth's length: {dir_ok}; |t_est|/|t_gt| median {:.4} p10 {:.4} p90 {:.4}",
        ratios[ratios.len() / 2],
        ratios[ratios.len() / 10],
        ratios[ratios.len() * 9 / 10]
    );
    counts.sort_unstable();
    times.sort_by(f64::total_cmp);
    println!(
        "min {} median {} corr; good {good}/{}; stereo frame median {:.1} ms",
        counts[0],
        counts[counts.len() / 2],
        counts.len(),
        times[times.len() / 2]
    );
    Ok(())
}
