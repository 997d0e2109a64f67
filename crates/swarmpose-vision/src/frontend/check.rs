//! The ranges of the front ends' settings ([`OrbFrontendConfig::check`],
//! [`SurfFrontendConfig::check`]): a value outside them is an error naming the setting
//! before the first frame, not a panic or a meaningless run.

use super::settings::{OrbFrontendConfig, SurfFrontendConfig};
use crate::bucketing::BucketConfig;
use crate::orb::OrbConfig;
use crate::stereo::StereoConfig;
use crate::surf::SurfConfig;
use crate::temporal::TemporalConfig;
use swarmpose_core::settings::{
    InvalidSetting, at_least_zero, count_at_least, finite, not_below, positive, ratio,
};

impl OrbFrontendConfig {
    /// Checks every setting's range; `prefix` is the settings' path in a run
    /// configuration (`"orb"`), which the error's name starts with.
    ///
    /// # Errors
    /// [`InvalidSetting`] naming the first setting out of range.
    pub fn check(&self, prefix: &str) -> Result<(), InvalidSetting> {
        check_orb(&self.left, &format!("{prefix}.left"))?;
        check_orb(&self.right, &format!("{prefix}.right"))?;
        self.stereo.check(&format!("{prefix}.stereo"))?;
        self.temporal.check(&format!("{prefix}.temporal"))
    }
}

impl SurfFrontendConfig {
    /// Checks every setting's range; `prefix` is the settings' path in a run
    /// configuration (`"surf"`), which the error's name starts with.
    ///
    /// # Errors
    /// [`InvalidSetting`] naming the first setting out of range.
    pub fn check(&self, prefix: &str) -> Result<(), InvalidSetting> {
        check_surf(&self.surf, &format!("{prefix}.surf"))?;
        self.stereo.check(&format!("{prefix}.stereo"))?;
        self.temporal.check(&format!("{prefix}.temporal"))?;
        match &self.bucketing {
            Some(b) => check_bucketing(b, &format!("{prefix}.bucketing")),
            None => Ok(()),
        }
    }
}

impl StereoConfig {
    /// Checks every setting's range: tolerances, disparities and noise sigmas are
    /// finite and not negative (sigmas above 0), the largest disparity is at least the
    /// smallest, the ratio is in `(0, 1]`; `prefix` starts the error's name.
    ///
    /// # Errors
    /// [`InvalidSetting`] naming the first setting out of range.
    pub fn check(&self, prefix: &str) -> Result<(), InvalidSetting> {
        let name = |field: &str| format!("{prefix}.{field}");
        at_least_zero(name("row_tolerance_px"), f64::from(self.row_tolerance_px))?;
        at_least_zero(name("min_disparity_px"), f64::from(self.min_disparity_px))?;
        not_below(
            name("max_disparity_px"),
            f64::from(self.max_disparity_px),
            f64::from(self.min_disparity_px),
            "a finite number of pixels, at least min_disparity_px",
        )?;
        positive(name("max_distance"), f64::from(self.max_distance))?;
        ratio(name("ratio"), f64::from(self.ratio))?;
        finite(
            name("disparity_offset_px"),
            f64::from(self.disparity_offset_px),
        )?;
        at_least_zero(
            name("min_point_disparity_px"),
            f64::from(self.min_point_disparity_px),
        )?;
        positive(name("disparity_sigma_px"), self.disparity_sigma_px)?;
        positive(name("position_sigma_px"), self.position_sigma_px)
    }
}

impl TemporalConfig {
    /// Checks every setting's range: the descriptor distance and the displacement above
    /// 0, the ratio in `(0, 1]`, the guided search's radius above 0 and its ratio finite
    /// and not negative; `prefix` starts the error's name.
    ///
    /// # Errors
    /// [`InvalidSetting`] naming the first setting out of range.
    pub fn check(&self, prefix: &str) -> Result<(), InvalidSetting> {
        let name = |field: &str| format!("{prefix}.{field}");
        positive(name("max_distance"), f64::from(self.max_distance))?;
        ratio(name("ratio"), f64::from(self.ratio))?;
        if let Some(d) = self.max_displacement_px {
            positive(name("max_displacement_px"), f64::from(d))?;
        }
        if let Some(r) = self.guided_radius_px {
            positive(name("guided_radius_px"), f64::from(r))?;
        }
        at_least_zero(name("guided_min_ratio"), f64::from(self.guided_min_ratio))
    }
}

fn check_orb(c: &OrbConfig, prefix: &str) -> Result<(), InvalidSetting> {
    match &c.bucketing {
        Some(b) => check_bucketing(b, &format!("{prefix}.bucketing")),
        None => Ok(()),
    }
}

fn check_bucketing(b: &BucketConfig, prefix: &str) -> Result<(), InvalidSetting> {
    count_at_least(format!("{prefix}.cell_width"), b.cell_width, 1)?;
    count_at_least(format!("{prefix}.cell_height"), b.cell_height, 1)?;
    count_at_least(format!("{prefix}.per_cell"), b.per_cell, 1)
}

fn check_surf(c: &SurfConfig, prefix: &str) -> Result<(), InvalidSetting> {
    let name = |field: &str| format!("{prefix}.{field}");
    at_least_zero(name("hessian_threshold"), f64::from(c.hessian_threshold))?;
    count_at_least(name("octaves"), c.octaves, 1)?;
    count_at_least(name("intervals"), c.intervals, 1)?;
    count_at_least(name("initial_step"), c.initial_step, 1)?;
    at_least_zero(name("smoothing"), f64::from(c.smoothing))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_are_in_range() {
        assert_eq!(OrbFrontendConfig::default().check("orb"), Ok(()));
        assert_eq!(SurfFrontendConfig::default().check("surf"), Ok(()));
    }

    #[test]
    fn a_setting_out_of_range_is_named() {
        let mut c = OrbFrontendConfig::default();
        c.stereo.row_tolerance_px = -1.0;
        let e = c.check("orb").expect_err("out of range");
        assert_eq!(e.name, "orb.stereo.row_tolerance_px");
        let mut c = OrbFrontendConfig::default();
        c.stereo.max_disparity_px = 0.5;
        assert_eq!(
            c.check("orb").expect_err("out of range").name,
            "orb.stereo.max_disparity_px"
        );
        let mut c = OrbFrontendConfig::default();
        c.stereo.disparity_sigma_px = 0.0;
        assert_eq!(
            c.check("orb").expect_err("out of range").name,
            "orb.stereo.disparity_sigma_px"
        );
        let mut c = OrbFrontendConfig::default();
        c.temporal.ratio = f32::NAN;
        assert_eq!(
            c.check("orb").expect_err("out of range").name,
            "orb.temporal.ratio"
        );
        let mut c = OrbFrontendConfig::default();
        c.left.bucketing = Some(BucketConfig {
            cell_width: 0,
            ..BucketConfig::default()
        });
        assert_eq!(
            c.check("orb").expect_err("out of range").name,
            "orb.left.bucketing.cell_width"
        );
        let mut c = SurfFrontendConfig::default();
        c.surf.octaves = 0;
        assert_eq!(
            c.check("surf").expect_err("out of range").name,
            "surf.surf.octaves"
        );
        let mut c = SurfFrontendConfig::default();
        c.temporal.max_displacement_px = Some(-3.0);
        assert_eq!(
            c.check("surf").expect_err("out of range").name,
            "surf.temporal.max_displacement_px"
        );
    }
}
