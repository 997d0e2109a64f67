//! Shared by the tests: the Python with `rosbags` that makes and reads bags independently
//! of this crate.

#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use mcap::records::MessageHeader;
use swarmpose_ros::msg::schema_text;

/// The Python interpreter with `rosbags` (`$SWARMPOSE_PYTHON`, else `python3`), or `None`
/// after printing why the test is skipped (a failure under `CI=true`, where .ci/run
/// installs it).
pub fn python_with_rosbags() -> Option<String> {
    let py = std::env::var("SWARMPOSE_PYTHON").unwrap_or_else(|_| "python3".to_owned());
    let ok = Command::new(&py)
        .args(["-c", "import rosbags, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if ok {
        return Some(py);
    }
    let msg = format!(
        "{py} cannot import rosbags and numpy (pip install rosbags; or set SWARMPOSE_PYTHON)"
    );
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "CI=true: {msg}"
    );
    eprintln!("SKIPPED: {msg}");
    None
}

/// The test scripts' folder.
pub fn scripts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py")
}

/// Runs `script` of [`scripts`] with `args`; panics with its output when it fails.
pub fn run_script(py: &str, script: &str, args: &[&Path]) {
    let out = Command::new(py)
        .arg(scripts().join(script))
        .args(args)
        .output()
        .expect("run python");
    assert!(
        out.status.success(),
        "{script} failed: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A fresh scratch folder under the target directory.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// A topic to write: name, type, and (stamp ns, bytes) messages.
pub type TopicData = (&'static str, &'static str, Vec<(i64, Vec<u8>)>);

/// Writes `topics` as an MCAP bag (`ros2` profile, schemas in `ros2msg`) with the `mcap`
/// crate's writer (chunked, with its summary).
pub fn write_mcap(path: &Path, topics: &[TopicData]) {
    let f = std::io::BufWriter::new(std::fs::File::create(path).expect("create"));
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .create(f)
        .expect("writer");
    for (name, ty, msgs) in topics {
        let schema = w
            .add_schema(
                ty,
                "ros2msg",
                schema_text(ty).unwrap_or_default().as_bytes(),
            )
            .expect("schema");
        let ch = w
            .add_channel(schema, name, "cdr", &BTreeMap::new())
            .expect("channel");
        for (k, (t, data)) in msgs.iter().enumerate() {
            let header = MessageHeader {
                channel_id: ch,
                sequence: k as u32,
                log_time: *t as u64,
                publish_time: *t as u64,
            };
            w.write_to_known_channel(&header, data).expect("write");
        }
    }
    w.finish().expect("finish");
}
