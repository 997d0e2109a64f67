//! The bit depth of 16-bit PNG data: from the `sBIT` chunk where the file has one, else
//! 12 bits when every value fits in 12 bits (cameras store 10- and 12-bit data in 16-bit
//! PNGs; scaling by 16 bits would make such images near-black), else 16 bits.

use std::io::Cursor;

/// Where the depth used to scale an image to 8 bits comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthSource {
    /// An 8-bit (or lower) PNG: no scaling question.
    Eight,
    /// The PNG's `sBIT` chunk (significant bits).
    SBit,
    /// A 16-bit PNG without `sBIT` whose values all fit in 12 bits: read as 12-bit data
    /// (worth a warning: nothing in the file says so).
    Guessed12,
    /// A 16-bit PNG using the full range.
    Full16,
}

/// The depth of an image's data: significant bits and where that comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Depth {
    /// Significant bits of each value (8 for 8-bit images).
    pub bits: u8,
    /// Where `bits` comes from.
    pub source: DepthSource,
}

/// The largest `sBIT` entry of a PNG (significant bits of its channels), if it has one
/// that can be read.
pub(crate) fn sbit(bytes: &[u8]) -> Option<u8> {
    let reader = png::Decoder::new(Cursor::new(bytes)).read_info().ok()?;
    let bits = reader.info().sbit.as_ref()?.iter().copied().max()?;
    (1..=16).contains(&bits).then_some(bits)
}

/// The depth of 16-bit `values` of a PNG whose `sBIT` is `sbit`.
pub(crate) fn of_16bit(values: &[u16], sbit: Option<u8>) -> Depth {
    if let Some(bits) = sbit {
        return Depth {
            bits,
            source: DepthSource::SBit,
        };
    }
    if values.iter().all(|&v| v < 1 << 12) {
        Depth {
            bits: 12,
            source: DepthSource::Guessed12,
        }
    } else {
        Depth {
            bits: 16,
            source: DepthSource::Full16,
        }
    }
}

/// 16-bit values of `bits` significant bits scaled to 8 bits, rounded (values above the
/// depth saturate at 255).
pub(crate) fn to_8bit(values: &[u16], bits: u8) -> Vec<u8> {
    let max = f64::from((1u32 << bits) - 1);
    values
        .iter()
        .map(|&v| (f64::from(v) * 255.0 / max).round().min(255.0) as u8)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_depth_of_16_bit_values() {
        assert_eq!(of_16bit(&[0, 4095], None).source, DepthSource::Guessed12);
        assert_eq!(of_16bit(&[0, 4096], None).bits, 16);
        assert_eq!(of_16bit(&[0, 4096], Some(10)).source, DepthSource::SBit);
        assert_eq!(to_8bit(&[0, 4095, 2048, 9000], 12), vec![0, 255, 128, 255]);
        assert_eq!(to_8bit(&[65535, 257], 16), vec![255, 1]);
    }
}
