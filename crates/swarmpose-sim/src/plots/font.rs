//! The one embedded font of every swarmpose figure (the simulation's, the odometry
//! plots, the KITTI segment plots): DejaVu Sans (Bitstream Vera license, see
//! `assets/DejaVuSans-LICENSE.txt`), registered with plotters as [`FAMILY`].

use std::sync::OnceLock;

use plotters::style::FontStyle;

/// The font family figures draw text in.
pub const FAMILY: &str = "sans-serif";

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Registers the embedded font (regular and bold) as [`FAMILY`], once per process.
/// False when it could not be registered (the embedded file is not a valid TTF).
pub fn register_font() -> bool {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    *REGISTERED.get_or_init(|| {
        [FontStyle::Normal, FontStyle::Bold]
            .into_iter()
            .all(|style| plotters::style::register_font(FAMILY, style, FONT).is_ok())
    })
}
