//! The bit depth of 16-bit PNG data: from the `sBIT` chunk where the file has one, else
//! 12 bits when every value fits in 12 bits (cameras store 10- and 12-bit data in 16-bit
//! PNGs; scaling by 16 bits would make such images near-black), else 16 bits.

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
#[cfg(feature = "png")]
pub(crate) fn sbit(bytes: &[u8]) -> Option<u8> {
    let reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .ok()?;
    let bits = reader.info().sbit.as_ref()?.iter().copied().max()?;
    (1..=16).contains(&bits).then_some(bits)
}

/// The depth of 16-bit `values` of a PNG whose `sBIT` is `sbit`.
#[cfg(feature = "png")]
pub fn of_16bit(values: &[u16], sbit: Option<u8>) -> Depth {
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
#[cfg(feature = "png")]
pub fn to_8bit(values: &[u16], bits: u8) -> Vec<u8> {
    let max = f64::from((1u32 << bits) - 1);
    values
        .iter()
        .map(|&v| (f64::from(v) * 255.0 / max).round().min(255.0) as u8)
        .collect()
}

#[cfg(all(test, feature = "png"))]
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

    /// A 16-bit gray PNG of `values` (4 x 1), with an `sBIT` chunk of 12 bits when asked.
    fn png16(values: [u16; 4], sbit12: bool) -> Vec<u8> {
        let mut bytes = Vec::new();
        let mut enc = png::Encoder::new(&mut bytes, 4, 1);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        let mut w = enc.write_header().expect("header");
        let data: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
        w.write_image_data(&data).expect("data");
        drop(w);
        if sbit12 {
            // After the signature (8 bytes) and IHDR (4 + 4 + 13 + 4 bytes): length 1,
            // "sBIT", 12, and the chunk's CRC-32.
            let chunk = [
                0, 0, 0, 1, b's', b'B', b'I', b'T', 12, 0xe1, 0x67, 0x9f, 0x80,
            ];
            bytes.splice(33..33, chunk);
        }
        bytes
    }

    #[test]
    fn sixteen_bit_pngs_are_scaled_by_the_depth_of_their_data() {
        use crate::image::GrayImage;
        let path = std::path::Path::new("t.png");
        // Full range: scaled by 65535.
        let (img, d) =
            GrayImage::decode_png_with_depth(&png16([0, 257, 32896, 65535], false), path)
                .expect("png");
        assert_eq!(
            (img.data, d.source),
            (vec![0, 1, 128, 255], DepthSource::Full16)
        );
        // 12-bit data, nothing says so: scaled by 4095 (by 65535 it was near-black).
        let (img, d) = GrayImage::decode_png_with_depth(&png16([0, 16, 2048, 4095], false), path)
            .expect("png");
        assert_eq!(
            (img.data, d.source),
            (vec![0, 1, 128, 255], DepthSource::Guessed12)
        );
        // sBIT says 12 bits: no guess.
        let (img, d) =
            GrayImage::decode_png_with_depth(&png16([0, 16, 2048, 4095], true), path).expect("png");
        assert_eq!(
            (img.data, d),
            (
                vec![0, 1, 128, 255],
                Depth {
                    bits: 12,
                    source: DepthSource::SBit
                }
            )
        );
    }
}
