use nalgebra::{Matrix6, Vector6};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::floor::{FloorConfig, SystematicFloor, excess_of};
use super::split::SplitCheck;

/// A model covariance of the split's difference with millimetres and milliradians and
/// some correlation (metres, radians).
fn model_covariance() -> Matrix6<f64> {
    let mut a = Matrix6::<f64>::identity();
    a[(0, 4)] = 0.5;
    a[(2, 3)] = -0.3;
    let s = Matrix6::from_diagonal(&Vector6::new(1e-3, 2e-3, 4e-3, 1e-3, 1.5e-3, 0.5e-3));
    s * a * a.transpose() * s
}

/// A split check whose difference is drawn from `L (I + excess) Lᵀ` for the model
/// covariance `c = L Lᵀ`.
fn draw(c: &Matrix6<f64>, excess: &Matrix6<f64>, rng: &mut ChaCha8Rng) -> SplitCheck {
    let l = c.cholesky().expect("positive definite").l();
    let e = (Matrix6::identity() + excess)
        .cholesky()
        .expect("positive definite")
        .l();
    let z = Vector6::from_fn(|_, _| StandardNormal.sample(rng));
    let difference = l * e * z;
    let nees = (difference.transpose() * c.try_inverse().expect("inverse") * difference)[0];
    SplitCheck {
        difference,
        covariance: *c,
        nees,
        model_nees: nees,
        inliers: [100, 100],
    }
}

/// Runs the floor online over `frames` draws: the mean of the NEES each check is given
/// by the floor learned from the checks before it, and of the model's NEES.
fn online(excess: &Matrix6<f64>, frames: usize, seed: u64) -> (f64, f64, SystematicFloor) {
    let c = model_covariance();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut floor = SystematicFloor::new(FloorConfig::default());
    let (mut judged, mut model) = (0.0, 0.0);
    for _ in 0..frames {
        let raw = draw(&c, excess, &mut rng);
        judged += floor.judge(&raw).nees;
        model += raw.nees;
        floor.learn(&raw);
    }
    (judged / frames as f64, model / frames as f64, floor)
}

/// Where the model is honest the floor adds nothing on most frames: the held-out mean
/// NEES stays near 6, and a covariance comes back bit for bit when the excess is zero.
#[test]
fn an_honest_model_gets_no_floor() {
    let mut zero_frames = 0;
    let mut means = Vec::new();
    for seed in 0..20 {
        let (judged, model, floor) = online(&Matrix6::zeros(), 100, seed);
        means.push((judged, model));
        if *floor.excess() == Matrix6::zeros() {
            zero_frames += 1;
            let c = model_covariance();
            assert_eq!(floor.widen(&c), c);
        }
    }
    let n = means.len() as f64;
    let judged = means.iter().map(|m| m.0).sum::<f64>() / n;
    let model = means.iter().map(|m| m.1).sum::<f64>() / n;
    eprintln!("honest: held-out mean NEES {judged:.2} (model {model:.2}), {zero_frames}/20 zero");
    assert!(zero_frames >= 16, "{zero_frames} of 20 floors were zero");
    assert!(
        judged > 0.95 * model && (5.0..7.0).contains(&judged),
        "{judged} {model}"
    );
}

/// Errors the model misses, four times its own along one whitened direction and twice
/// along another: the floor learned online from past frames brings the held-out mean
/// NEES from far above 6 to near it, and finds the direction.
#[test]
fn a_missing_error_is_learned_online() {
    let mut excess = Matrix6::zeros();
    excess[(0, 0)] = 15.0;
    excess[(4, 4)] = 5.0;
    let (judged, model, floor) = online(&excess, 200, 7);
    eprintln!("excess: held-out mean NEES {judged:.2}, model {model:.1}");
    assert!(model > 20.0, "model {model}");
    assert!((4.5..9.0).contains(&judged), "held out {judged}");
    let x = floor.excess();
    assert!(x[(0, 0)] > 7.0 && x[(0, 0)] > 2.0 * x[(4, 4)], "{x}");
    assert!(x[(4, 4)] > 1.5, "{x}");
}

/// The floor does not depend on units: the same checks in millimetres give the same
/// NEES and the same covariance in millimetres.
#[test]
fn the_floor_does_not_depend_on_units() {
    let mut excess = Matrix6::zeros();
    excess[(1, 1)] = 8.0;
    let c = model_covariance();
    let d = Matrix6::from_diagonal(&Vector6::new(1e3, 1e3, 1e3, 1.0, 1.0, 1.0));
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut metres = SystematicFloor::new(FloorConfig::default());
    let mut mm = SystematicFloor::new(FloorConfig::default());
    for _ in 0..40 {
        let raw = draw(&c, &excess, &mut rng);
        let scaled = SplitCheck {
            difference: d * raw.difference,
            covariance: d * raw.covariance * d,
            ..raw
        };
        let (a, b) = (metres.judge(&raw), mm.judge(&scaled));
        assert!(
            (a.nees - b.nees).abs() < 1e-6 * a.nees.max(1.0),
            "{a:?} {b:?}"
        );
        let back = d * a.covariance * d;
        assert!((back - b.covariance).norm() < 1e-9 * b.covariance.norm());
        metres.learn(&raw);
        mm.learn(&scaled);
    }
    assert!(metres.excess()[(1, 1)] > 2.0, "{}", metres.excess());
}

/// A check that cannot be whitened (a covariance not positive definite, a difference
/// not finite) is left out; a covariance that cannot be factored is given back as it is.
#[test]
fn bad_samples_are_left_out() {
    let mut floor = SystematicFloor::new(FloorConfig::default());
    let c = model_covariance();
    let bad = [
        SplitCheck {
            difference: Vector6::repeat(1.0),
            covariance: -c,
            nees: 1.0,
            model_nees: 1.0,
            inliers: [10, 10],
        },
        SplitCheck {
            difference: Vector6::repeat(f64::NAN),
            covariance: c,
            nees: 1.0,
            model_nees: 1.0,
            inliers: [10, 10],
        },
    ];
    for b in &bad {
        floor.learn(b);
    }
    assert_eq!(floor.samples(), 0);
    let mut excess = Matrix6::zeros();
    excess[(0, 0)] = 10.0;
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for _ in 0..20 {
        floor.learn(&draw(&c, &excess, &mut rng));
    }
    assert_ne!(*floor.excess(), Matrix6::zeros());
    assert_eq!(floor.widen(&-c), -c);
    assert!(excess_of(&(Matrix6::identity() * f64::NAN), 10.0, 2.0) == Matrix6::zeros());
}
