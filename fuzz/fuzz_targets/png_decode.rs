//! The image decoding path of every sequence loader: PNG bytes to 8-bit gray.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| swarmpose_fuzz_checks::png_decode(data));
