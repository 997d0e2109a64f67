//! ROS 2 images to what the engine takes: 8-bit gray, or depth in metres.
//!
//! | encoding | to gray |
//! |---|---|
//! | `mono8` | as is |
//! | `mono16` | scaled to 8 bits as a 16-bit PNG without `sBIT` is by the folder loaders ([`swarmpose_vision::image::depth`]) |
//! | `rgb8`, `bgr8`, `rgba8`, `bgra8` | luma as the `image` crate computes it for a colour PNG |
//! | `CompressedImage` PNG | decoded as the folder loaders decode a PNG |
//! | `CompressedImage` JPEG | decoded by the `image` crate (zune-jpeg), then luma |
//!
//! Depth: `16UC1` (millimetres; 65535, saturated, is none) and `32FC1` (metres) to metres,
//! 0 where there is none.
//! Any other encoding is refused by name.

use std::path::Path;

use swarmpose_vision::image::GrayImage;
use swarmpose_vision::image::depth::{of_16bit, to_8bit};

use crate::msg::{CompressedImage, Image};

/// The encodings [`image_to_gray`] reads.
pub const GRAY_ENCODINGS: &[&str] = &["mono8", "mono16", "rgb8", "bgr8", "rgba8", "bgra8"];
/// The encodings [`image_to_depth_m`] reads.
pub const DEPTH_ENCODINGS: &[&str] = &["16UC1", "32FC1"];

/// The rows of `img`, each `width * bytes_per_pixel` bytes, checked against `step` and
/// the data's length.
fn rows(img: &Image, bytes_per_pixel: usize) -> Result<impl Iterator<Item = &[u8]>, String> {
    let (w, h) = (img.width as usize, img.height as usize);
    let row = w.checked_mul(bytes_per_pixel).ok_or("width too large")?;
    let step = img.step as usize;
    if w == 0 || h == 0 {
        return Err(format!("an empty {}x{} image", w, h));
    }
    if step < row {
        return Err(format!(
            "step {step} is shorter than a row of {w} {} pixels ({row} bytes)",
            img.encoding
        ));
    }
    let need = step
        .checked_mul(h - 1)
        .and_then(|x| x.checked_add(row))
        .ok_or("image too large")?;
    if img.data.len() < need {
        return Err(format!(
            "{} bytes of data for a {w}x{h} {} image of step {step} (needs {need})",
            img.data.len(),
            img.encoding
        ));
    }
    Ok(img.data.chunks(step).take(h).map(move |r| &r[..row]))
}

/// Colour pixels (`channels` bytes each, red at `r`, blue at `b`) to gray as the `image`
/// crate converts a colour PNG.
fn colour_to_gray(img: &Image, channels: usize, r: usize, b: usize) -> Result<GrayImage, String> {
    // The rows first: they check the size against the data before anything is allocated
    // for it (a header's size alone once asked for 260 GB).
    let rows = rows(img, channels)?;
    let mut rgb = Vec::with_capacity(img.width as usize * img.height as usize * 3);
    for row in rows {
        for px in row.chunks_exact(channels) {
            rgb.extend_from_slice(&[px[r], px[1], px[b]]);
        }
    }
    let buf = image::RgbImage::from_raw(img.width, img.height, rgb).ok_or("bad image size")?;
    let luma = image::DynamicImage::ImageRgb8(buf).into_luma8();
    GrayImage::from_raw(img.width as usize, img.height as usize, luma.into_raw())
        .ok_or_else(|| "bad image size".to_owned())
}

/// 16-bit values of the rows of `img`, honouring `is_bigendian`.
fn values_u16(img: &Image) -> Result<Vec<u16>, String> {
    let rows = rows(img, 2)?;
    let mut out = Vec::with_capacity(img.width as usize * img.height as usize);
    for row in rows {
        out.extend(row.chunks_exact(2).map(|p| {
            if img.is_bigendian != 0 {
                u16::from_be_bytes([p[0], p[1]])
            } else {
                u16::from_le_bytes([p[0], p[1]])
            }
        }));
    }
    Ok(out)
}

/// An [`Image`] as 8-bit gray.
///
/// # Errors
/// A one-line message naming an encoding not in [`GRAY_ENCODINGS`], or data too short
/// for the size.
pub fn image_to_gray(img: &Image) -> Result<GrayImage, String> {
    let (w, h) = (img.width as usize, img.height as usize);
    match img.encoding.as_str() {
        "mono8" | "8UC1" => {
            let rows = rows(img, 1)?;
            let mut data = Vec::with_capacity(w * h);
            for row in rows {
                data.extend_from_slice(row);
            }
            GrayImage::from_raw(w, h, data).ok_or_else(|| "bad image size".to_owned())
        }
        "mono16" => {
            let v = values_u16(img)?;
            let depth = of_16bit(&v, None);
            GrayImage::from_raw(w, h, to_8bit(&v, depth.bits))
                .ok_or_else(|| "bad image size".to_owned())
        }
        "rgb8" => colour_to_gray(img, 3, 0, 2),
        "bgr8" => colour_to_gray(img, 3, 2, 0),
        "rgba8" => colour_to_gray(img, 4, 0, 2),
        "bgra8" => colour_to_gray(img, 4, 2, 0),
        other => Err(format!(
            "image encoding '{other}' is not one of {} (nor a depth image for a gray one)",
            GRAY_ENCODINGS.join(", ")
        )),
    }
}

/// An [`Image`] as 8-bit gray, as [`image_to_gray`]; a `mono8` image whose rows are
/// packed (`step` = `width`) gives its pixels without a copy.
///
/// # Errors
/// As [`image_to_gray`].
pub fn image_into_gray(img: Image) -> Result<GrayImage, String> {
    let (w, h) = (img.width as usize, img.height as usize);
    if matches!(img.encoding.as_str(), "mono8" | "8UC1") && img.step as usize == w {
        rows(&img, 1).map(|_| ())?;
        let mut data = img.data;
        data.truncate(w * h);
        return GrayImage::from_raw(w, h, data).ok_or_else(|| "bad image size".to_owned());
    }
    image_to_gray(&img)
}

/// A depth [`Image`] in metres (0 where there is none).
///
/// # Errors
/// A one-line message naming an encoding not in [`DEPTH_ENCODINGS`].
pub fn image_to_depth_m(img: &Image) -> Result<Vec<f32>, String> {
    match img.encoding.as_str() {
        // Divided in f64, then rounded once to f32: the depth a TUM folder gives for the
        // same millimetres (5 units each). 65535 is a sensor's saturated or "too far"
        // value, not 65.5 m: no depth, as in the TUM reader.
        "16UC1" | "mono16" => Ok(values_u16(img)?
            .into_iter()
            .map(|mm| {
                if mm == u16::MAX {
                    0.0
                } else {
                    (f64::from(mm) / 1000.0) as f32
                }
            })
            .collect()),
        "32FC1" => {
            let rows = rows(img, 4)?;
            let mut out = Vec::with_capacity(img.width as usize * img.height as usize);
            for row in rows {
                out.extend(row.chunks_exact(4).map(|p| {
                    let b = [p[0], p[1], p[2], p[3]];
                    let m = if img.is_bigendian != 0 {
                        f32::from_be_bytes(b)
                    } else {
                        f32::from_le_bytes(b)
                    };
                    if m.is_finite() && m > 0.0 { m } else { 0.0 }
                }));
            }
            Ok(out)
        }
        other => Err(format!(
            "depth encoding '{other}' is not one of {}",
            DEPTH_ENCODINGS.join(", ")
        )),
    }
}

/// A [`CompressedImage`] (PNG or JPEG) as 8-bit gray.
///
/// # Errors
/// A one-line message for another format (`compressedDepth` included) or bytes that do
/// not decode.
pub fn compressed_to_gray(img: &CompressedImage) -> Result<GrayImage, String> {
    let format = img.format.to_ascii_lowercase();
    if format.contains("compresseddepth") {
        return Err(format!(
            "CompressedImage format '{}' (compressedDepth) is not read: record depth as Image 16UC1 or 32FC1",
            img.format
        ));
    }
    if format.contains("png") {
        return GrayImage::decode_png(&img.data, Path::new("CompressedImage"))
            .map_err(|e| e.to_string());
    }
    if format.contains("jpeg") || format.contains("jpg") {
        let decoded = image::load_from_memory_with_format(&img.data, image::ImageFormat::Jpeg)
            .map_err(|e| format!("not a readable JPEG: {e}"))?;
        let (w, h) = (decoded.width() as usize, decoded.height() as usize);
        return GrayImage::from_raw(w, h, decoded.into_luma8().into_raw())
            .ok_or_else(|| "bad JPEG size".to_owned());
    }
    Err(format!(
        "CompressedImage format '{}' is neither png nor jpeg",
        img.format
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mono8(width: u32, step: u32, height: u32, len: usize) -> Image {
        Image {
            width,
            height,
            step,
            encoding: "mono8".to_owned(),
            data: (0..len).map(|i| (i * 7 % 251) as u8).collect(),
            ..Image::default()
        }
    }

    #[test]
    fn owned_gray_is_the_borrowed_one() {
        // Packed rows (moved), padded rows (copied row by row), extra bytes after the last
        // row (dropped), and too few bytes (refused by both).
        for img in [mono8(5, 5, 3, 15), mono8(5, 8, 3, 21), mono8(5, 5, 3, 17)] {
            let borrowed = image_to_gray(&img).expect("gray");
            assert_eq!(borrowed.data.len(), 15);
            assert_eq!(image_into_gray(img).expect("gray"), borrowed);
        }
        let short = mono8(5, 5, 3, 14);
        let err = image_to_gray(&short).expect_err("too short");
        assert_eq!(image_into_gray(short).expect_err("too short"), err);
    }

    /// A header claiming a huge image over a few bytes of data is refused before anything
    /// is allocated for its size (the fuzzer's bag asked for 260 GB, and the process
    /// aborted), in every encoding, depth images' too.
    #[test]
    fn a_size_beyond_the_data_allocates_nothing() {
        for encoding in ["mono8", "8UC1", "mono16", "rgb8", "bgra8"] {
            let img = Image {
                encoding: encoding.to_owned(),
                ..mono8(300_000, 1_200_000, 290_000, 64)
            };
            let err = image_to_gray(&img).expect_err("too short");
            assert!(err.contains("bytes of data"), "{encoding}: {err}");
            assert_eq!(image_into_gray(img).expect_err("too short"), err);
        }
        for encoding in ["16UC1", "32FC1"] {
            let img = Image {
                encoding: encoding.to_owned(),
                ..mono8(300_000, 1_200_000, 290_000, 64)
            };
            let err = image_to_depth_m(&img).expect_err("too short");
            assert!(err.contains("bytes of data"), "{encoding}: {err}");
        }
    }
}
