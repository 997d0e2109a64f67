//! `swarmpose.OdometryConfig`: the odometry engine's settings, and the one place their
//! keywords, defaults and doc are declared. `swarmpose.Odometry(...)`,
//! `Odometry.from_sequence`, `Odometry.rgbd` and `swarmpose.odometry` take one as
//! `config=`, or its keywords as `**options`, which [`OdometryConfig::resolve`] hands
//! to its constructor.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use std::path::PathBuf;

use pyo3::types::PyDict;
use swarmpose_odometry::config::Calibration;
use swarmpose_odometry::frontend::RgbdNoise;
use swarmpose_odometry::window::Marginalisation;
use swarmpose_odometry::working::check_band;
use swarmpose_odometry::{CorrectionModel, StereoCamera};
use swarmpose_runs::config::RunConfig;

use crate::args::{FixedCorrection, Seed};
use crate::errors::odometry_error;
use crate::methods;

/// Declares the Python class `OdometryConfig` from one list of keywords, each `name:
/// type = default => "doc"` (`name: &str as String = ...` for a string the constructor
/// borrows and the class keeps): its fields (read-only properties documented by the doc),
/// its keyword-only constructor (the defaults), its `repr`, the class docstring (every
/// keyword's doc) and [`OdometryConfig::KEYWORDS`] (the names `**options` accepts).
macro_rules! odometry_config {
    (
        $(#[doc = $class_doc:tt])*
        keywords {
            $($name:ident: $arg:ty $(as $field:ty)? = $default:tt => $doc:literal,)*
        }
    ) => {
        $(#[doc = $class_doc])*
        #[doc = concat!($("\n* ``", stringify!($name), "``: ", $doc),*)]
        #[pyclass(frozen, eq, get_all, module = "swarmpose")]
        #[derive(Debug, PartialEq)]
        pub(crate) struct OdometryConfig {
            $(#[doc = $doc] $name: odometry_config!(@field $arg $(as $field)?),)*
        }

        impl OdometryConfig {
            /// The constructor's keywords, in its order.
            pub(crate) const KEYWORDS: &'static [&'static str] = &[$(stringify!($name)),*];
        }

        #[pymethods]
        impl OdometryConfig {
            #[new]
            #[pyo3(signature = (*, $($name = $default),*))]
            #[allow(clippy::too_many_arguments)]
            fn new($($name: $arg),*) -> PyResult<Self> {
                let config = Self { $($name: $name.into()),* };
                config.check()?;
                Ok(config)
            }

            /// ``OdometryConfig(method='pso', ...)``: every keyword with its value.
            fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
                let mut fields = Vec::with_capacity(Self::KEYWORDS.len());
                for name in Self::KEYWORDS {
                    fields.push(format!("{name}={}", slf.getattr(*name)?.repr()?));
                }
                Ok(format!("OdometryConfig({})", fields.join(", ")))
            }
        }
    };
    (@field $arg:ty) => { $arg };
    (@field $arg:ty as $field:ty) => { $field };
}

odometry_config! {
    /// The odometry engine's settings, checked when made (``ValueError`` with the command
    /// line's one-line message for a bad value). Every keyword has a read-only property of
    /// the same name; ``swarmpose.Odometry(...)``, ``Odometry.from_sequence``,
    /// ``Odometry.rgbd`` and ``swarmpose.odometry`` take one as ``config=``, or these
    /// keywords themselves. The keywords:
    keywords {
        method: Option<String> = None => "the estimator of each motion, one of \
            ``swarmpose.METHODS`` (``None``: ``\"pso\"``, or the configuration file's)",
        threshold: Option<f64> = None => "its inlier threshold in metres (``None``: ``pso`` \
            estimates it from the data; ``svd`` and ``wls`` have none)",
        detector: Option<String> = None => "the feature detector, ``\"orb\"`` or \
            ``\"surf\"`` (``None``: ``\"orb\"``; RGB-D: ``\"orb\"``)",
        refine: Option<bool> = None => "refine each motion on the reprojection error \
            (``None``: ``True``)",
        calibrate: Option<String> = None => "the causes self-calibration may correct, e.g. \
            ``\"principal-point+yaw+focal\"``, or ``\"none\"`` (``None``: as the command line)",
        disparity_correction: Option<FixedCorrection> = None => "a fixed ``(offset, \
            quadratic)`` or ``(offset, quadratic, linear)`` disparity correction in pixels \
            (the terms in 1, x² and x) instead of self-calibration",
        min_inliers: Option<usize> = None => "fewest inliers for a motion, at least 3 \
            (``None``: 12)",
        seed: Option<Seed> = None => "the estimator's seed; frame k uses seed + k (``None``: 0)",
        window: Option<usize> = None => "keyframes of the sliding-window bundle adjustment; \
            0: frame to frame (``None``: as the command line, 10)",
        marginalise: Option<String> = None => "what happens to the window's oldest keyframe \
            when it leaves: ``\"off\"`` (``None``), ``\"finished\"`` or ``\"all\"`` (see \
            docs/window.md)",
        correction_per_frame: Option<bool> = None => "each window measurement keeps the \
            disparity correction of the frame where it was made, so that a calibration change \
            moves no online step (costs drift; docs/self-calibration.md; ``None``: ``False``)",
        guided_radius_px: Option<f32> = None => "search each feature's partner in the next \
            frame within this many pixels of where the engine's constant-velocity prediction \
            puts it (opt-in; a third of the matching time, not the default: docs/history.md; \
            ``None``: the whole search window)",
        max_working_pixels: Option<usize> = None => "stereo images are halved while they have \
            more pixels than this (``None``: 1 500 000; at least 10 000; see \
            ``Odometry.working_camera``)",
        min_working_pixels: Option<usize> = None => "stereo images are doubled while they have \
            fewer pixels than this (``None``: 0, never; at most a quarter of \
            max_working_pixels, and at most 16 777 216)",
        split_check: Option<bool> = None => "check each pair's covariance on two spatially \
            disjoint halves of its matches (``Frame.split``; two more refinements a frame; \
            ``None``: ``False``)",
        config_file: Option<PathBuf> = None => "a run configuration: the ``config.json`` \
            every command-line run writes, or ``OdometryRun.config_json`` saved; its settings \
            replace the defaults, and the keywords given beside it replace its settings",
    }
}

impl OdometryConfig {
    /// The settings an entry point called `caller` was given: `config`, or else its
    /// option keywords `options` (`**options`) given to the constructor.
    ///
    /// # Errors
    /// `TypeError` for both `config` and option keywords, or a keyword that is not an
    /// option; the constructor's errors.
    pub(crate) fn resolve<'py>(
        py: Python<'py>,
        caller: &str,
        config: Option<Bound<'py, Self>>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, Self>> {
        let options = options.filter(|o| !o.is_empty());
        if let Some(options) = options {
            let given: Vec<String> = options
                .keys()
                .iter()
                .map(|k| k.extract())
                .collect::<PyResult<_>>()?;
            if let Some(unknown) = given.iter().find(|k| !Self::KEYWORDS.contains(&k.as_str())) {
                return Err(PyTypeError::new_err(format!(
                    "{caller}() got an unexpected keyword argument '{unknown}' (the options \
                     are {})",
                    Self::KEYWORDS.join(", ")
                )));
            }
            if config.is_some() {
                return Err(PyTypeError::new_err(format!(
                    "{caller}() takes config= or option keywords, not both (given: config and {})",
                    given.join(", ")
                )));
            }
        }
        if let Some(config) = config {
            return Ok(config);
        }
        Ok(py
            .get_type::<Self>()
            .call((), options)?
            .cast_into::<Self>()?)
    }

    /// Checks every setting as the engine will read it.
    fn check(&self) -> PyResult<()> {
        let c = self.run_config()?.odometry;
        c.check().map_err(|e| odometry_error(&e))?;
        check_band(c.min_working_pixels, c.max_working_pixels).map_err(|e| odometry_error(&e))
    }

    /// The run's configuration: the defaults (those of the command line), or the
    /// `config_file`'s settings, with the keywords given applied over them.
    pub(crate) fn run_config(&self) -> PyResult<RunConfig> {
        let mut rc = match &self.config_file {
            Some(path) => {
                RunConfig::read(path).map_err(|e| PyValueError::new_err(e.to_string()))?
            }
            None => RunConfig::default(),
        };
        let c = &mut rc.odometry;
        if let Some(name) = &self.detector {
            c.detector =
                name.parse()
                    .map_err(|e: swarmpose_vision::frontend::UnknownDetector| {
                        PyValueError::new_err(e.to_string())
                    })?;
        }
        c.refine = self.refine.unwrap_or(c.refine);
        c.split_check = self.split_check.unwrap_or(c.split_check);
        c.seed = self.seed.map_or(c.seed, |s| s.0);
        c.window.keyframes = self.window.unwrap_or(c.window.keyframes);
        c.window.correction_per_frame = self
            .correction_per_frame
            .unwrap_or(c.window.correction_per_frame);
        if let Some(r) = self.guided_radius_px {
            c.orb.temporal.guided_radius_px = Some(r);
            c.surf.temporal.guided_radius_px = Some(r);
        }
        if let Some(mode) = &self.marginalise {
            let mode: Marginalisation = mode
                .parse()
                .map_err(|e: String| PyValueError::new_err(format!("marginalise {e}")))?;
            c.window.marginalise = mode;
        }
        c.max_working_pixels = self.max_working_pixels.unwrap_or(c.max_working_pixels);
        c.min_working_pixels = self.min_working_pixels.unwrap_or(c.min_working_pixels);
        c.min_inliers = self.min_inliers.unwrap_or(c.min_inliers);
        if let Some(text) = &self.calibrate {
            c.selfcal.candidates = CorrectionModel::parse(text).map_err(PyValueError::new_err)?;
        }
        let terms = match self.disparity_correction {
            None => [None; 3],
            Some(FixedCorrection::Two((a, q))) => [Some(a), Some(q), None],
            Some(FixedCorrection::Three((a, q, l))) => [Some(a), Some(q), Some(l)],
        };
        if self.calibrate.is_some() || self.disparity_correction.is_some() {
            c.calibration = Calibration::from_terms(
                c.selfcal.candidates,
                terms,
                [
                    "disparity_correction offset",
                    "disparity_correction quadratic",
                    "disparity_correction linear",
                ],
            )
            .map_err(PyValueError::new_err)?;
        }
        c.estimator =
            methods::configure(c.estimator.clone(), self.method.as_deref(), self.threshold)?;
        Ok(rc)
    }

    /// The engine for a stereo `camera`, or for an RGB-D camera with the depth noise
    /// `rgbd` (which has no disparity to correct and whose frames are never resampled).
    ///
    /// # Errors
    /// `ValueError` for a camera that is not valid, or for an RGB-D camera, a setting it
    /// has no use for.
    pub(crate) fn build(
        &self,
        camera: StereoCamera,
        rgbd: Option<RgbdNoise>,
    ) -> PyResult<swarmpose_odometry::Odometry> {
        let mut builder =
            swarmpose_odometry::Odometry::builder(camera).config(self.run_config()?.odometry);
        if let Some(noise) = rgbd {
            if let Some(name) = self.stereo_only() {
                return Err(PyValueError::new_err(format!(
                    "{name} does not apply to an RGB-D camera (no disparity to correct, \
                     frames never resampled)"
                )));
            }
            builder = builder.rgbd(noise);
        }
        builder.build().map_err(|e| odometry_error(&e))
    }

    /// The first of the settings only a stereo camera has a use for that is given.
    fn stereo_only(&self) -> Option<&'static str> {
        [
            ("calibrate", self.calibrate.is_some()),
            ("disparity_correction", self.disparity_correction.is_some()),
            ("max_working_pixels", self.max_working_pixels.is_some()),
            ("min_working_pixels", self.min_working_pixels.is_some()),
        ]
        .into_iter()
        .find_map(|(name, given)| given.then_some(name))
    }
}
