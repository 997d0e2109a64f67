//! The correspondence CSV read by `register` (bytes, as from standard input).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| swarmpose_fuzz_checks::correspondence_csv(data));
