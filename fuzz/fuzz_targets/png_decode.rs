//! The image decoding path of every sequence loader: PNG bytes to 8-bit gray.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use swarmpose_vision::image::GrayImage;

fuzz_target!(|data: &[u8]| {
    if let Ok(img) = GrayImage::decode_png(data, Path::new("frame.png")) {
        assert_eq!(img.data.len(), img.width * img.height);
    }
});
