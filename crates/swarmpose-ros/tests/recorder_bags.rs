//! Every message of the bags written by the ROS 2 recorder itself (rosbag2's test
//! resources: MCAP and SQLite, split bags) and of a real recording (evo's
//! `nav2_turtlebot.mcap`, GPL-3.0, kept in shared/), read by this crate and by two
//! independent Python readers, `rosbags` (every bag) and either Foxglove's `mcap` with
//! `mcap-ros2-support` (MCAP bags) or Python's sqlite3 with rosbags' CDR decoder (SQLite
//! bags): the same topics, types, log times and bytes, and for
//! the types swarmpose models the same decoded values. Each bag must agree with at least
//! one reader that reads its messages, and with every reader that does.

mod common;

use std::path::{Path, PathBuf};

use serde_json::Value;
use swarmpose_ros::Bag;
use swarmpose_ros::msg::{
    CameraInfo, CompressedImage, DiagnosticArray, Image, Log, Odometry, Path as PathMsg,
    PointCloud2, PoseWithCovarianceStamped, RosMessage, StringMsg, TfMessage, decode,
};

/// The bags under `root`: folders with metadata.yaml, and .mcap/.db3 files outside them.
fn bags(root: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(root) else {
        return;
    };
    let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    if root.join("metadata.yaml").is_file() {
        out.push(root.to_owned());
        return;
    }
    for p in entries {
        if p.is_dir() {
            bags(&p, out);
        } else if p.extension().is_some_and(|e| e == "mcap" || e == "db3") {
            out.push(p);
        }
    }
}

fn as_json<T: RosMessage>(bytes: &[u8]) -> Value {
    let m: T = decode(bytes).unwrap_or_else(|e| panic!("{}: {e}", T::TYPE));
    serde_json::to_value(m).expect("json")
}

/// The message decoded by this crate as JSON, for the types it models.
fn decoded(msg_type: &str, bytes: &[u8]) -> Option<Value> {
    Some(match msg_type {
        StringMsg::TYPE => as_json::<StringMsg>(bytes),
        Log::TYPE => as_json::<Log>(bytes),
        TfMessage::TYPE => as_json::<TfMessage>(bytes),
        Odometry::TYPE => as_json::<Odometry>(bytes),
        PathMsg::TYPE => as_json::<PathMsg>(bytes),
        PoseWithCovarianceStamped::TYPE => as_json::<PoseWithCovarianceStamped>(bytes),
        Image::TYPE => as_json::<Image>(bytes),
        CompressedImage::TYPE => as_json::<CompressedImage>(bytes),
        CameraInfo::TYPE => as_json::<CameraInfo>(bytes),
        PointCloud2::TYPE => as_json::<PointCloud2>(bytes),
        DiagnosticArray::TYPE => as_json::<DiagnosticArray>(bytes),
        _ => return None,
    })
}

/// JSON values equal, numbers to the last bit but for JSON's float parsing (1e-15).
fn same(a: &Value, b: &Value, at: &str) -> Result<(), String> {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (
                x.as_f64().unwrap_or(f64::NAN),
                y.as_f64().unwrap_or(f64::NAN),
            );
            if x == y || (x - y).abs() <= 1e-15 * x.abs().max(y.abs()) {
                Ok(())
            } else {
                Err(format!("{at}: {x} != {y}"))
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .try_for_each(|(i, (x, y))| same(x, y, &format!("{at}[{i}]"))),
        (Value::Object(x), Value::Object(y)) if x.len() == y.len() => {
            x.iter().try_for_each(|(k, v)| {
                same(
                    v,
                    y.get(k).ok_or(format!("{at}.{k}: missing"))?,
                    &format!("{at}.{k}"),
                )
            })
        }
        _ if a == b => Ok(()),
        _ => Err(format!("{at}: {a} != {b}")),
    }
}

/// Compares one bag with `reader`'s reading of it; returns the number of messages
/// compared and decoded (0 when the reader cannot read the bag or reads no message).
/// With `raw`, the reader decodes nothing (the bytes are compared, and another reader
/// compared the values).
fn compare(py: &str, bag_path: &Path, reader: &str, raw: bool, scratch: &Path) -> (usize, usize) {
    let bag = Bag::open(bag_path).unwrap_or_else(|e| panic!("{e}"));
    let out = scratch.join("dump.json");
    let mode = Path::new(if raw { "raw" } else { "decoded" });
    common::run_script(
        py,
        "rosbags_dump.py",
        &[bag_path, &out, Path::new(reader), mode],
    );
    let dump: Value =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("dump")).expect("json");
    let ours: usize = bag.topics().iter().map(|t| t.entries.len()).sum();
    if let Some(e) = dump.get("error") {
        eprintln!(
            "{}: {reader} cannot read it ({e}); swarmpose indexed {ours} messages",
            bag_path.display()
        );
        return (0, 0);
    }
    let topics = dump["topics"].as_object().expect("topics");
    let theirs: usize = topics
        .values()
        .filter_map(|t| t["messages"].as_array())
        .map(Vec::len)
        .sum();
    if theirs == 0 && ours > 0 {
        eprintln!(
            "{}: {reader} reads no message of it; swarmpose reads {ours}",
            bag_path.display()
        );
        return (0, 0);
    }
    let (mut compared, mut decoded_n) = (0, 0);
    for (name, t) in topics {
        let theirs = t["messages"].as_array().expect("messages");
        if theirs.is_empty() {
            continue;
        }
        let ours = bag.topic(name).unwrap_or_else(|| {
            panic!(
                "{}: topic {name} missing; {}",
                bag_path.display(),
                bag.listing()
            )
        });
        assert_eq!(ours.msg_type, t["type"].as_str().expect("type"), "{name}");
        assert_eq!(
            ours.entries.len(),
            theirs.len(),
            "{}: {name} message count",
            bag_path.display()
        );
        let mut a: Vec<(i64, String, usize)> = (0..ours.entries.len())
            .map(|i| {
                let bytes = bag.read(ours, i).unwrap_or_else(|e| panic!("{e}"));
                let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
                (ours.entries[i].log_time_ns, hex, i)
            })
            .collect();
        let mut b: Vec<(i64, String, usize)> = theirs
            .iter()
            .enumerate()
            .map(|(k, m)| {
                (
                    m[0].as_i64().expect("stamp"),
                    m[1].as_str().expect("hex").to_owned(),
                    k,
                )
            })
            .collect();
        a.sort();
        b.sort();
        for (x, y) in a.iter().zip(&b) {
            assert_eq!((x.0, &x.1), (y.0, &y.1), "{}: {name}", bag_path.display());
            compared += 1;
            let want = &theirs[y.2][2];
            if want.is_null() {
                continue;
            }
            let bytes = bag.read(ours, x.2).expect("read");
            let got = decoded(&ours.msg_type, &bytes).expect("modelled type");
            same(&got, want, name).unwrap_or_else(|e| panic!("{}: {e}", bag_path.display()));
            decoded_n += 1;
        }
    }
    let with_messages = bag
        .topics()
        .iter()
        .filter(|t| !t.entries.is_empty())
        .count();
    let theirs_with = topics
        .values()
        .filter(|t| t["messages"].as_array().is_some_and(|m| !m.is_empty()))
        .count();
    assert_eq!(
        with_messages,
        theirs_with,
        "{}: topics with messages",
        bag_path.display()
    );
    (compared, decoded_n)
}

/// Compares one bag with each of its independent readers; returns the number of messages
/// compared and decoded over the readers. One of the readers must agree on every message.
fn check_bag(py: &str, bag: &Path, scratch: &Path) -> (usize, usize) {
    let (mut total, mut decoded) = (0, 0);
    let is_mcap = bag.extension().is_some_and(|e| e == "mcap")
        || bag.join("metadata.yaml").is_file()
            && std::fs::read_to_string(bag.join("metadata.yaml"))
                .is_ok_and(|m| m.contains("storage_identifier: mcap"));
    let readers: &[&str] = if is_mcap {
        &["rosbags", "mcap"]
    } else {
        &["rosbags", "sqlite"]
    };
    let ours: usize = Bag::open(bag)
        .expect("open")
        .topics()
        .iter()
        .map(|t| t.entries.len())
        .sum();
    let mut best = 0;
    for reader in readers {
        // The second reader decodes only what the first did not (the time is in
        // Python).
        let (n, d) = compare(py, bag, reader, best == ours, scratch);
        eprintln!(
            "{}: {reader}: {n} messages equal, {d} decoded equal",
            bag.display()
        );
        best = best.max(n);
        total += n;
        decoded += d;
    }
    assert_eq!(
        best,
        ours,
        "{}: no reader agrees on all {ours} messages",
        bag.display()
    );
    (total, decoded)
}

#[test]
fn every_message_of_the_recorder_bags_matches_independent_readers() {
    let Some(root) = swarmpose_testdata::dataset_for_test("ros2_bags") else {
        return;
    };
    let Some(py) = common::python_with_rosbags() else {
        return;
    };
    let mut list = Vec::new();
    bags(&root, &mut list);
    if !root.join("evo").is_dir() {
        eprintln!(
            "SKIPPED part: {}/evo (GPL-3.0 recording) is absent",
            root.display()
        );
    }
    assert!(list.len() >= 10, "found only {list:?}");
    let scratch = common::scratch("recorder_bags");
    // The readers' time is in their Python processes: the bags are compared by as many
    // workers as there are cores, each with its own scratch folder.
    let workers = std::thread::available_parallelism().map_or(1, usize::from);
    let per_worker: Vec<(usize, usize)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                let (list, py, scratch) = (&list, &py, scratch.join(format!("worker-{w}")));
                s.spawn(move || {
                    std::fs::create_dir_all(&scratch).expect("scratch");
                    let (mut total, mut decoded_total) = (0, 0);
                    for bag in list.iter().skip(w).step_by(workers) {
                        let (n, d) = check_bag(py, bag, &scratch);
                        total += n;
                        decoded_total += d;
                    }
                    (total, decoded_total)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a worker panicked"))
            .collect()
    });
    let total: usize = per_worker.iter().map(|w| w.0).sum();
    let decoded_total: usize = per_worker.iter().map(|w| w.1).sum();
    eprintln!(
        "{} bags: {total} messages equal, {decoded_total} decoded equal",
        list.len()
    );
    assert!(
        total > 10_000 && decoded_total > 8_000,
        "{total} {decoded_total}"
    );
}
