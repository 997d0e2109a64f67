use super::*;

fn odometry() -> Odometry {
    let mut o = Odometry {
        header: Header {
            stamp: Time {
                sec: 12,
                nanosec: 345,
            },
            frame_id: "odom".to_owned(),
        },
        child_frame_id: "camera".to_owned(),
        ..Odometry::default()
    };
    o.pose.pose.position.x = 1.5;
    o.pose.pose.orientation.w = 1.0;
    o.pose.covariance = std::array::from_fn(|i| i as f64 * 0.25);
    o.twist.twist.angular.z = -0.125;
    o
}

#[test]
fn messages_round_trip() {
    let o = odometry();
    let bytes = encode(&o).expect("encode");
    // Header 4 + stamp 8 + "odom\0" (4 + 5, padded to 4) + ... ; covariances 2 x 288.
    assert_eq!(&bytes[..4], &[0, 1, 0, 0]);
    assert_eq!(decode::<Odometry>(&bytes).expect("decode"), o);
    let img = Image {
        header: o.header.clone(),
        height: 2,
        width: 3,
        encoding: "mono8".to_owned(),
        is_bigendian: 0,
        step: 3,
        data: vec![1, 2, 3, 4, 5, 6],
    };
    assert_eq!(decode::<Image>(&encode(&img).expect("e")).expect("d"), img);
    let info = CameraInfo {
        d: vec![0.1, -0.2, 0.0, 0.0, 0.0],
        k: std::array::from_fn(|i| i as f64),
        p: std::array::from_fn(|i| -(i as f64)),
        ..CameraInfo::default()
    };
    assert_eq!(
        decode::<CameraInfo>(&encode(&info).expect("e")).expect("d"),
        info
    );
}

#[test]
fn known_bytes_both_byte_orders() {
    let le = [0u8, 1, 0, 0, 4, 0, 0, 0, b'f', b'o', b'o', 0];
    assert_eq!(decode::<StringMsg>(&le).expect("le").data, "foo");
    assert_eq!(
        encode(&StringMsg {
            data: "foo".to_owned()
        })
        .expect("e"),
        le
    );
    let be = [0u8, 0, 0, 0, 0, 0, 0, 4, b'f', b'o', b'o', 0];
    assert_eq!(decode::<StringMsg>(&be).expect("be").data, "foo");
    let t = [0u8, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
    let h = decode_header(&t).expect("header");
    assert_eq!(
        (h.stamp.as_nanos(), h.frame_id.as_str()),
        (1_000_000_002, "")
    );
}

#[test]
fn bad_bytes_are_refused_with_a_reason() {
    let good = encode(&odometry()).expect("encode");
    for (bytes, says) in [
        (vec![0u8, 1], "too short"),
        (vec![0u8, 7, 0, 0, 0, 0, 0, 0], "not plain CDR"),
        (
            good[..good.len() - 9].to_vec(),
            "not a nav_msgs/msg/Odometry",
        ),
        ([good.as_slice(), &[0; 8]].concat(), "left over"),
    ] {
        let e = decode::<Odometry>(&bytes).expect_err(says);
        assert!(e.0.contains(says), "{e}");
    }
    // A string that is not UTF-8.
    let bad = [0u8, 1, 0, 0, 3, 0, 0, 0, 0xff, 0xfe, 0];
    assert!(decode::<StringMsg>(&bad).is_err());
}

#[test]
fn time_from_and_to_nanoseconds() {
    for ns in [
        0i64,
        1,
        999_999_999,
        1_000_000_000,
        1_586_406_456_763_032_325,
        -1,
    ] {
        assert_eq!(Time::from_nanos(ns).as_nanos(), ns);
    }
    assert_eq!(
        Time::from_nanos(-1),
        Time {
            sec: -1,
            nanosec: 999_999_999
        }
    );
}
