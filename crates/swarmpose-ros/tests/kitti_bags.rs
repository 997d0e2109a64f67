//! KITTI stereo frames written into ROS 2 bags by the independent `rosbags` writer (MCAP
//! plain, MCAP with zstd chunks, SQLite; Image mono8, rgb8 and CompressedImage PNG) read
//! back as the folder reads them: the same calibration to the bit, the same pixels. A bag
//! cut in the middle (a recorder killed; plain, zstd or LZ4 chunks) gives every whole frame
//! before the cut.

mod common;

use std::path::{Path, PathBuf};

use swarmpose_datasets::StereoSequence;
use swarmpose_datasets::kitti::KittiSequence;
use swarmpose_ros::msg::decode_header;
use swarmpose_ros::{Bag, BagSequence, StereoOptions, Topic};

/// Frames put in each bag.
const FRAMES: usize = 6;
/// Time of the first frame, nanoseconds, and the frame period.
const T0_NS: i64 = 1_317_000_000_000_000_000;
const PERIOD_NS: i64 = 100_000_000;

/// The first numbers of the `P0:`/`P1:` rows of a KITTI `calib.txt`.
fn projection(calib: &str, key: &str) -> Vec<f64> {
    let line = calib
        .lines()
        .find(|l| l.starts_with(key))
        .unwrap_or_else(|| panic!("{key}"));
    line[key.len()..]
        .split_whitespace()
        .map(|x| x.parse().expect("number"))
        .collect()
}

/// Writes the frames folder the bag maker reads.
fn frames_dir(kitti: &Path, seq: &KittiSequence, out: &Path) {
    let calib = std::fs::read_to_string(kitti.join("calib.txt")).expect("calib");
    let (w, h) = seq.image_size();
    let meta = serde_json::json!({
        "width": w, "height": h,
        "p_left": projection(&calib, "P0:"), "p_right": projection(&calib, "P1:"),
        "stamps_ns": (0..FRAMES as i64).map(|k| T0_NS + k * PERIOD_NS).collect::<Vec<_>>(),
    });
    std::fs::write(out.join("meta.json"), meta.to_string()).expect("meta");
    for k in 0..FRAMES {
        let pair = seq.frame(k).expect("frame");
        std::fs::write(out.join(format!("left_{k}.raw")), &pair.left.data).expect("raw");
        std::fs::write(out.join(format!("right_{k}.raw")), &pair.right.data).expect("raw");
        for (side, dir) in [("left", "image_0"), ("right", "image_1")] {
            let png = kitti.join(dir).join(format!("{k:06}.png"));
            std::fs::copy(&png, out.join(format!("{side}_{k}.png"))).expect("png");
        }
    }
}

fn make(py: &str, frames: &Path, out: &Path, storage: &str, opts: &[&str]) -> PathBuf {
    let mut args: Vec<&Path> = vec![frames, out, Path::new(storage)];
    args.extend(opts.iter().map(Path::new));
    common::run_script(py, "make_stereo_bag.py", &args);
    out.to_owned()
}

fn same_frames(bag: &BagSequence, seq: &KittiSequence, n: usize) {
    assert_eq!(
        bag.calibration(),
        seq.calibration(),
        "calibration to the bit"
    );
    assert_eq!(bag.image_size(), seq.image_size());
    for k in 0..n {
        assert_eq!(
            bag.frame(k).expect("bag frame"),
            seq.frame(k).expect("folder frame"),
            "frame {k}"
        );
        let t = bag.timestamp_s(k).expect("stamp");
        assert!((t - k as f64 * 0.1).abs() < 1e-9, "{t}");
    }
}

/// The first file of a bag folder with this extension.
fn file_in(dir: &Path, ext: &str) -> PathBuf {
    std::fs::read_dir(dir)
        .expect("dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|e| e == ext))
        .expect("bag file")
}

/// What a test needs: the Python with rosbags, the KITTI sequence, a scratch folder and
/// the frames folder in it; `None` (after saying why) without the data or rosbags.
fn prepare(name: &str) -> Option<(String, KittiSequence, PathBuf, PathBuf)> {
    let kitti = swarmpose_testdata::dataset_for_test("kitti_vo_seq2")?;
    let py = common::python_with_rosbags()?;
    let seq = KittiSequence::open(&kitti).expect("kitti");
    let dir = common::scratch(name);
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).expect("frames");
    frames_dir(&kitti, &seq, &frames);
    Some((py, seq, dir, frames))
}

#[test]
fn kitti_bags_read_as_the_folder() {
    let Some((py, seq, dir, frames)) = prepare("kitti_bags") else {
        return;
    };
    let opts = StereoOptions::default();
    for (storage, extra, ext) in [
        ("mcap", &[][..], "mcap"),
        ("mcap-zstd", &[][..], "mcap"),
        ("mcap-lz4", &[][..], "mcap"),
        ("sqlite3", &[][..], "db3"),
        ("mcap", &["png"][..], "mcap"),
        ("sqlite3", &["rgb8"][..], "db3"),
    ] {
        let out = make(
            &py,
            &frames,
            &dir.join(format!("{storage}_{}", extra.join("_"))),
            storage,
            extra,
        );
        let bag = BagSequence::open(&out, &opts).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(bag.len(), FRAMES, "{storage} {extra:?}");
        assert!(bag.notes().is_empty(), "{:?}", bag.notes());
        assert_eq!(bag.frames().frame_id(), "camera_left_optical");
        same_frames(&bag, &seq, FRAMES);
        // The file alone reads as the folder.
        let file = BagSequence::open(&file_in(&out, ext), &opts).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(file.len(), FRAMES);
        if ext == "mcap" {
            // A short bag: its chunks, decompressed when opening, kept for the reads.
            assert!(file.frames().bag().chunk_cache_bytes() > 0);
            // No chunk kept but the last one (a bag longer than the cache): the same frames.
            let mut uncached = Bag::open(&file_in(&out, ext)).expect("bag");
            uncached.set_chunk_cache_bytes(0);
            let uncached = BagSequence::from_bag(uncached, &opts).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(uncached.frames().bag().chunk_cache_bytes(), 0);
            same_frames(&uncached, &seq, FRAMES);
        }
        eprintln!("{storage} {extra:?}: {FRAMES} frames equal to the folder's");
    }
}

#[test]
fn a_cut_mcap_gives_every_whole_frame_before_the_cut() {
    let Some((py, seq, dir, frames)) = prepare("kitti_cut") else {
        return;
    };
    // Plain, zstd and LZ4 chunks: a cut inside a compressed chunk gives the messages its
    // decompressed prefix holds whole.
    for storage in ["mcap", "mcap-zstd", "mcap-lz4"] {
        let out = make(&py, &frames, &dir.join(storage), storage, &[]);
        let whole = std::fs::read(file_in(&out, "mcap")).expect("read");
        let full = Bag::open(&file_in(&out, "mcap")).expect("open");
        assert!(full.stopped().is_none(), "{:?}", full.stopped());
        for share in [0.35, 0.6, 0.95] {
            let cut = dir.join(format!("cut_{storage}_{share}.mcap"));
            std::fs::write(&cut, &whole[..(whole.len() as f64 * share) as usize]).expect("write");
            let bag = BagSequence::open(&cut, &StereoOptions::default())
                .unwrap_or_else(|e| panic!("{e}"));
            let stopped = bag.frames().bag().stopped().expect("says where it stopped");
            assert!(
                stopped.contains("cut at byte")
                    && stopped.contains("read up to its last whole message"),
                "{stopped}"
            );
            assert!(
                bag.len() >= 1 && bag.len() < FRAMES,
                "{storage} {share}: {}",
                bag.len()
            );
            same_frames(&bag, &seq, bag.len());
            // No chunk kept but the last: the whole chunks before the cut are read at
            // opening only up to their last header, then whole.
            let mut uncached = Bag::open(&cut).expect("open");
            uncached.set_chunk_cache_bytes(0);
            let uncached = BagSequence::from_bag(uncached, &StereoOptions::default())
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(uncached.len(), bag.len());
            assert_eq!(uncached.notes(), bag.notes());
            same_frames(&uncached, &seq, bag.len());
            eprintln!(
                "{storage} cut at {share}: {} whole frames; {stopped}",
                bag.len()
            );
        }
    }
}

/// A compressed bag longer than the chunk cache: reading the images' headers decompresses
/// each chunk only up to the last header it holds, and gives the headers that reading the
/// whole messages gives.
#[test]
fn a_header_scan_decompresses_chunks_only_as_far_as_it_reads() {
    let Some((py, _seq, dir, frames)) = prepare("kitti_heads") else {
        return;
    };
    for storage in ["mcap-zstd", "mcap-lz4"] {
        let out = make(&py, &frames, &dir.join(storage), storage, &[]);
        let mut bag = Bag::open(&file_in(&out, "mcap")).expect("open");
        bag.set_chunk_cache_bytes(0);
        let images: Vec<&Topic> = bag
            .topics()
            .iter()
            .filter(|t| t.msg_type == "sensor_msgs/msg/Image")
            .collect();
        assert_eq!(images.len(), 2);
        let headers = |heads: &[Option<usize>]| {
            let mut out = Vec::new();
            let skipped = bag
                .visit_heads(&images, heads, |k, i, bytes| {
                    out.push((k, i, decode_header(bytes).expect("header")));
                    Ok(())
                })
                .expect("visit");
            (out, skipped)
        };
        let (whole, none_skipped) = headers(&[]);
        let (heads, skipped) = headers(&[Some(64), Some(64)]);
        assert_eq!(whole.len(), 2 * FRAMES);
        assert_eq!(heads, whole, "{storage}");
        assert_eq!(none_skipped, 0);
        // The data of at least one image at the end of a chunk was not decompressed.
        assert!(skipped > 1241 * 376, "{storage}: {skipped} bytes skipped");
        eprintln!("{storage}: {skipped} bytes of records not decompressed");
    }
}
