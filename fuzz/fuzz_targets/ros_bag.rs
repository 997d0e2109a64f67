//! The bag front door: any bytes as an `.mcap` file are indexed (a cut or corrupt file
//! gives an error or what it holds whole), every indexed message can be read back, and
//! the stereo search gives a sequence or an error; never a panic. The text of a
//! `metadata.yaml` is parsed too.
#![no_main]

use std::path::PathBuf;

use libfuzzer_sys::fuzz_target;
use swarmpose_datasets::StereoSequence;
use swarmpose_ros::bag::parse_metadata;
use swarmpose_ros::{Bag, BagSequence, StereoOptions};

fn scratch() -> PathBuf {
    std::env::temp_dir().join(format!("swarmpose-fuzz-ros-bag-{}.mcap", std::process::id()))
}

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = parse_metadata(text);
    }
    let path = scratch();
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(bag) = Bag::open(&path) {
        for t in bag.topics() {
            for i in 0..t.entries.len() {
                let _ = bag.read(t, i);
            }
        }
    }
    let opts = StereoOptions::default();
    if let Ok(seq) = BagSequence::open(&path, &opts) {
        for i in 0..seq.len().min(4) {
            let _ = seq.frame(i);
        }
    }
    let _ = std::fs::remove_file(&path);
});
