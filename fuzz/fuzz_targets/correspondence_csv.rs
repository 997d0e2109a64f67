//! The correspondence CSV read by `register` (bytes, as from standard input).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(c) = swarmpose_data::correspondence_csv::read_from(data, "fuzz.csv") {
        assert!(!c.is_empty());
        // What is read writes back and reads back the same.
        let mut out = Vec::new();
        swarmpose_data::correspondence_csv::write_to(&mut out, &c, "out.csv").expect("write");
        let back = swarmpose_data::correspondence_csv::read_from(out.as_slice(), "out.csv")
            .expect("read back");
        assert_eq!(back.src(), c.src());
        assert_eq!(back.dst(), c.dst());
    }
});
