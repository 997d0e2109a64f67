//! The summary lines of `swarmpose odometry` about the disparity correction: what was
//! applied, and each term named after what its evidence shows (docs/self-calibration.md,
//! "What each term is, and how it is told apart").
//!
//! The rows' `x y` bend is what a yaw of the right camera would show, but a rectification
//! left with some lens distortion bends the rows too: it is printed as the rows' `x*y`
//! bend, and called a yaw only when the decision took it as one (rigidity did not prefer
//! its own `x²` term). The term linear in `x` (cause `focal`) is what a right camera whose
//! focal length is off would show, which would also scale the rows by the same number of
//! pixels times `y`: the line says whether the rows' `y` scale agrees.

use swarmpose_odometry::{CorrectionModel, Decision};

/// The lines about the correction of `decision` (`given`: fixed by the user, not decided).
pub(crate) fn calibration_lines(decision: &Decision, given: bool) -> Vec<String> {
    if given {
        return vec![format!(
            "disparity correction: {} (given)",
            decision.correction
        )];
    }
    let rows = &decision.rows;
    let focal = if decision.model.has(CorrectionModel::FOCAL_LENGTH) {
        format!("; focal length {:+.3} px", decision.focal_px)
    } else {
        String::new()
    };
    let bend = match (rows.yaw, rows.weight) {
        (false, _) => "not taken as a yaw".to_owned(),
        (true, w) if w < 1.0 => format!("taken as a yaw f*psi, applied {:.0} %", 100.0 * w),
        (true, _) => "taken as a yaw f*psi".to_owned(),
    };
    let mut lines = vec![format!(
        "disparity correction: {}{focal} ({}; rows: x*y bend {:.3} px ({bend}), roll f*theta \
         {:.3} px, y scale {:+.3} px{}, from {} row offsets; rigidity: {} pairs, held-out score \
         {:.1}{})",
        decision.correction,
        decision.model,
        rows.rotation_px[0],
        rows.rotation_px[1],
        rows.vertical_scale_px,
        if rows.vertical_scale {
            " (supported)"
        } else {
            ""
        },
        rows.measurements,
        decision.pairs,
        decision.rigidity_score,
        if decision.rigidity_weight > 0.0 && decision.rigidity_weight < 1.0 {
            format!(", applied {:.0} %", 100.0 * decision.rigidity_weight)
        } else {
            String::new()
        }
    )];
    if decision.model.has(CorrectionModel::FOCAL) {
        lines.push(linear_term_line(decision));
    }
    if decision.one_plane_pairs > 0 {
        lines.push(format!(
            "calibration {}: {} pair(s) saw one plane, where a disparity offset cannot be told \
             from the scene's scale; they corrected nothing",
            if decision.rigidity_unobservable() {
                "unobservable by rigidity"
            } else {
                "partly unobservable"
            },
            decision.one_plane_pairs
        ));
    }
    lines
}

/// What the term linear in `x` is consistent with: a right focal length `l` pixels long
/// scales the rows by `l y` as well, so the rows' `y` scale, when the held-out folds
/// support it, should have the sign of `l`.
fn linear_term_line(decision: &Decision) -> String {
    let l = decision.correction.linear_x_px;
    let v = decision.rows.vertical_scale_px;
    let agrees = decision.rows.vertical_scale && v * l > 0.0;
    if agrees {
        format!(
            "linear term {l:+.3} px x: the rows' y scale {v:+.3} px agrees in sign, as for a \
             right camera whose focal length is off"
        )
    } else {
        format!(
            "linear term {l:+.3} px x: a disparity error linear in x; the rows show no y scale \
             of its sign ({v:+.3} px{}), so it is not shown to be the right focal length",
            if decision.rows.vertical_scale {
                ", supported"
            } else {
                ", not supported"
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decided(model: CorrectionModel, linear: f64, y_scale: f64, supported: bool) -> Decision {
        let mut d = Decision {
            model,
            ..Decision::default()
        };
        d.correction.linear_x_px = linear;
        d.rows.rotation_px[0] = -6.76;
        d.rows.vertical_scale_px = y_scale;
        d.rows.vertical_scale = supported;
        d
    }

    /// The rows' x*y bend is a yaw only when taken as one; the linear term's line says
    /// whether the rows agree.
    #[test]
    fn terms_are_named_after_their_evidence() {
        let m = CorrectionModel::PRINCIPAL_POINT
            .with(CorrectionModel::QUADRATIC)
            .with(CorrectionModel::FOCAL);
        let lines = calibration_lines(&decided(m, 0.34, 0.53, true), false);
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(
            lines[0].contains("x*y bend -6.760 px (not taken as a yaw)"),
            "{}",
            lines[0]
        );
        assert!(!lines[0].contains("yaw f*psi"), "{}", lines[0]);
        assert!(lines[1].contains("agrees in sign"), "{}", lines[1]);
        let lines = calibration_lines(&decided(m, 0.34, -0.2, true), false);
        assert!(
            lines[1].contains("not shown to be the right focal length"),
            "{}",
            lines[1]
        );
        let lines = calibration_lines(&decided(m, 0.34, 0.53, false), false);
        assert!(lines[1].contains("not supported"), "{}", lines[1]);
        let mut yawed = decided(CorrectionModel::YAW, 0.0, 0.0, false);
        yawed.rows.yaw = true;
        yawed.rows.weight = 1.0;
        let lines = calibration_lines(&yawed, false);
        assert_eq!(lines.len(), 1);
        assert!(lines[0].contains("(taken as a yaw f*psi)"), "{}", lines[0]);
        let lines = calibration_lines(&decided(m, 0.34, 0.53, true), true);
        assert_eq!(lines.len(), 1);
        assert!(lines[0].ends_with("(given)"), "{}", lines[0]);
    }
}
