//! The JSON report of `register`, as read back by `correspondences --inliers`.
#![no_main]

use libfuzzer_sys::fuzz_target;

/// The checksum the seeds of the corpus carry.
const CHECKSUM: &str = "00112233445566ff";

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for rows in [0, 3, 16] {
        if let Ok(flags) =
            swarmpose_data::register_report::parse_inliers(text, "report.json", rows, CHECKSUM)
        {
            assert_eq!(flags.len(), rows);
        }
    }
});
