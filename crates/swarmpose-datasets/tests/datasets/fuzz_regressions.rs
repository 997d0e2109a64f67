//! Inputs the fuzzers found (fuzz/, docs/testing.md): each must give an answer or a typed
//! error at once.

use std::path::Path;

fn input(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz_regressions")
        .join(name);
    String::from_utf8_lossy(&std::fs::read(path).expect("regression input")).into_owned()
}

/// A T_BS rotation entry of 2e58 made the nearest-rotation projection spin forever.
#[test]
fn sensor_yaml_with_a_huge_rotation_entry() {
    let text = input("sensor_yaml_huge_rotation.yaml");
    let t = std::time::Instant::now();
    let r = swarmpose_datasets::euroc::parse_sensor_yaml(&text, Path::new("sensor.yaml"));
    eprintln!("{:?} in {:?}", r.as_ref().map(|_| ()), t.elapsed());
    let e = r.expect_err("not a rotation").to_string();
    assert!(e.starts_with("sensor.yaml:"), "{e}");
}
