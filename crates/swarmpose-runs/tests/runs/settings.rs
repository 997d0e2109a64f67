//! Every numeric setting of the engine's configuration, set to values a user may type by
//! mistake (-1, -0.5, 0, 1e30): the engine refuses the configuration with an error naming
//! the setting, or runs the first frames without a panic. A negative stereo row tolerance
//! once passed the check and panicked in the middle of the first frame; an estimator's
//! ratio of 1e30 once passed it and failed every frame without naming the setting.

use serde_json::Value;
use swarmpose_datasets::StereoSequence;
use swarmpose_odometry::{Odometry, OdometryConfig, OdometryError, StereoInput};
use swarmpose_runs::batch::camera_of;
use swarmpose_runs::synthetic::SyntheticSequence;

/// The paths of the numeric leaves of `v` (objects only; the estimator's method and
/// the other strings are left alone).
fn numeric_leaves(v: &Value, path: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match v {
        Value::Object(m) => {
            for (k, child) in m {
                path.push(k.clone());
                numeric_leaves(child, path, out);
                path.pop();
            }
        }
        Value::Number(_) => out.push(path.clone()),
        _ => {}
    }
}

fn set(v: &mut Value, path: &[String], to: Value) {
    let mut at = v;
    for k in path {
        at = &mut at[k.as_str()];
    }
    *at = to;
}

#[test]
fn no_setting_makes_the_engine_panic() {
    let seq = SyntheticSequence::new(2, 0.5, 0.01);
    let camera = camera_of(&seq);
    let frames = [
        seq.frame(0).expect("frame 0"),
        seq.frame(1).expect("frame 1"),
    ];
    let base = serde_json::to_value(OdometryConfig::default()).expect("config as JSON");
    let mut leaves = Vec::new();
    numeric_leaves(&base, &mut Vec::new(), &mut leaves);
    assert!(leaves.len() > 80, "{} numeric settings", leaves.len());
    let (mut refused, mut ran) = (Vec::new(), 0);
    for path in &leaves {
        for to in [-1.0, -0.5, 0.0, 1e30] {
            let mut v = base.clone();
            set(&mut v, path, serde_json::json!(to));
            // A count given a negative or fractional value does not parse: refused
            // before the engine sees it.
            let Ok(config) = serde_json::from_value::<OdometryConfig>(v) else {
                continue;
            };
            let name = path.join(".");
            let outcome = std::panic::catch_unwind(|| {
                let mut odo = match Odometry::new(camera, config) {
                    Ok(odo) => odo,
                    Err(OdometryError::Config { message }) => return Err(message),
                    Err(e) => panic!("{name} = {to}: not a configuration error: {e}"),
                };
                for (i, f) in frames.iter().enumerate() {
                    let input = StereoInput {
                        left: f.left.view(),
                        right: f.right.view(),
                        timestamp_s: i as f64 * 0.1,
                    };
                    // An error for a frame is an answer too; a panic is not.
                    let _ = odo.track(input);
                }
                Ok(())
            });
            match outcome {
                Ok(Ok(())) => ran += 1,
                Ok(Err(message)) => {
                    let leaf = path.last().map_or("", String::as_str);
                    assert!(message.contains(leaf), "{name} = {to}: {message}");
                    refused.push(format!("{name} = {to}"));
                }
                Err(_) => panic!("{name} = {to} made the engine panic"),
            }
        }
    }
    println!(
        "{} settings: {} values refused, {ran} ran",
        leaves.len(),
        refused.len()
    );
    assert!(
        refused.len() > 40 && ran > 40,
        "{} refused, {ran} ran",
        refused.len()
    );
    // The estimator's settings are checked with the others, before the first frame.
    for named in [
        "estimator.ambiguity_ratio = 1000000000000000000000000000000",
        "estimator.pso.velocity_clamp = 1000000000000000000000000000000",
        "estimator.sigma_multiplier = -1",
    ] {
        assert!(
            refused.iter().any(|r| r == named),
            "{named} was not refused"
        );
    }
}
