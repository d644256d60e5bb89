//! rmw_zenoh's format byte for byte (ros2/rmw_zenoh docs/design.md at commit
//! 99a6a2bd10b949052f4f12c5854825dc005e95a5): key expressions and liveliness tokens
//! against design.md's own examples, type hashes against published ones, the
//! attachment layout of design.md §Publishers, GIDs against XXH3-128 reference values,
//! and the CDR of each mapped type written out field by field from its .msg definition.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use rtcan_bridge::ros2::rmw::{self, Kind, NodeNames};
use rtcan_bridge::ros2::types::{self, Stamp, STRING_MSG};
use rtcan_model::bridge_keys::Ros2Type;
use serde_json::json;

const STRING_HASH: &str = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18";

fn node(domain: u32, zid: &str, ns: &str, name: &str) -> NodeNames {
    NodeNames {
        domain,
        zid: zid.into(),
        node_id: 0,
        namespace: ns.into(),
        name: name.into(),
    }
}

#[test]
fn type_hashes_are_the_published_ones() {
    // design.md, "Topic and Service name mapping": the `chatter` example.
    assert_eq!(types::type_hash(&STRING_MSG), STRING_HASH);
    // Published with rmw_zenoh keys of ROS 2 nodes (e.g. turtlesim's cmd_vel, odom).
    let h = |t| types::type_hash(&types::description(t));
    assert_eq!(
        h(Ros2Type::Twist),
        "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a"
    );
    assert_eq!(
        h(Ros2Type::Odometry),
        "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0"
    );
    // Range with `variance`: a published key shows `RIHS01_b42b6256...`.
    assert_eq!(
        h(Ros2Type::Range),
        "RIHS01_b42b62562e93cbfe9d42b82fe5994dfa3d63d7d5c90a317981703f7388adff3a"
    );
    // No published value found: the same algorithm as the four above.
    assert_eq!(
        h(Ros2Type::BatteryState),
        "RIHS01_4bee5dfce981c98faa6828b868307a0a73f992ed0789f374ee96c8f840e69741"
    );
}

#[test]
fn key_expressions_are_design_md_examples() {
    let dds = types::dds_name("std_msgs/msg/String");
    // `chatter` topic, ROS_DOMAIN_ID 0, without and with the `/robot1` namespace.
    assert_eq!(
        node(0, "x", "/", "talker").topic_key("chatter", &dds, STRING_HASH),
        format!("0/chatter/std_msgs::msg::dds_::String_/{STRING_HASH}")
    );
    assert_eq!(
        node(0, "x", "/robot1", "talker").topic_key("chatter", &dds, STRING_HASH),
        format!("0/robot1/chatter/std_msgs::msg::dds_::String_/{STRING_HASH}")
    );
    // Liveliness tokens of the `listener` node and its subscription, the `talker`'s
    // publisher (depth 7).
    let listener = node(2, "aac3178e146ba6f1fc6e6a4085e77f21", "/", "listener");
    assert_eq!(
        listener.node_token(),
        "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener"
    );
    assert_eq!(
        listener.entity_token(10, Kind::Subscription, "chatter", &dds, STRING_HASH, &rmw::qos_default(10)),
        format!("@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/10/MS/%/%/listener/%chatter/std_msgs::msg::dds_::String_/{STRING_HASH}/::,10:,:,:,,")
    );
    let talker = node(2, "8b20917502ee955ac4476e0266340d5c", "/", "talker");
    assert_eq!(
        talker.entity_token(10, Kind::Publisher, "chatter", &dds, STRING_HASH, &rmw::qos_default(7)),
        format!("@ros2_lv/2/8b20917502ee955ac4476e0266340d5c/0/10/MP/%/%/talker/%chatter/std_msgs::msg::dds_::String_/{STRING_HASH}/::,7:,:,:,,")
    );
    // The bridge of robot `triskar2`: namespace `/triskar2`.
    let b = node(0, "1f", "/triskar2", "rtcan_bridge");
    assert_eq!(
        b.node_token(),
        "@ros2_lv/0/1f/0/0/NN/%/%triskar2/rtcan_bridge"
    );
    let tw = types::dds_name("geometry_msgs/msg/Twist");
    let th = types::type_hash(&types::description(Ros2Type::Twist));
    assert_eq!(
        b.entity_token(1, Kind::Subscription, "teleop", &tw, &th, &rmw::qos_default(10)),
        format!("@ros2_lv/0/1f/0/1/MS/%/%triskar2/rtcan_bridge/%triskar2%teleop/geometry_msgs::msg::dds_::Twist_/{th}/::,10:,:,:,,")
    );
}

#[test]
fn gids_are_xxh3_128_of_the_token_and_ride_in_the_attachment() {
    // XXH3-128 reference values (python-xxhash 3.x), low 64 bits first, little-endian.
    assert_eq!(
        rmw::gid(""),
        0x99aa06d3014798d86001c324468d497fu128.to_le_bytes()
    );
    let token = format!("@ros2_lv/0/aac3178e146ba6f1fc6e6a4085e77f21/0/10/MS/%/%/listener/%chatter/std_msgs::msg::dds_::String_/{STRING_HASH}/::,10:,:,:,,");
    assert_eq!(token.len(), 187);
    assert_eq!(
        rmw::gid(&token),
        0xcbbf098386dbb01b8922fcfad2215ff1u128.to_le_bytes()
    );
    assert_eq!(
        rmw::gid(&"x".repeat(200)),
        0x062dfbe359870f1a0f7bed28ebd8500du128.to_le_bytes()
    );
    // design.md §Publishers: seq i64 LE, timestamp i64 LE, GID length 16, GID.
    let gid: [u8; 16] = core::array::from_fn(|i| i as u8 + 1);
    let a = rmw::attachment(3, 0x0102_0304_0506_0708, &gid);
    let mut want = vec![3, 0, 0, 0, 0, 0, 0, 0, 8, 7, 6, 5, 4, 3, 2, 1, 16];
    want.extend_from_slice(&gid);
    assert_eq!(a, want);
    assert_eq!(
        rmw::parse_attachment(&a),
        Some((3, 0x0102_0304_0506_0708, gid))
    );
    assert_eq!(rmw::parse_attachment(&a[..32]), None);
}

fn f64s(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

const STAMP: Stamp = Stamp {
    sec: 1_763_900_000,
    nanosec: 250_000_000,
};

/// header { stamp { int32 sec, uint32 nanosec }, string frame_id } from offset 0.
fn header(frame: &str) -> Vec<u8> {
    let mut h = vec![0, 1, 0, 0];
    h.extend(1_763_900_000i32.to_le_bytes());
    h.extend(250_000_000u32.to_le_bytes());
    h.extend((frame.len() as u32 + 1).to_le_bytes());
    h.extend(frame.as_bytes());
    h.push(0);
    h
}

fn pad(v: &mut Vec<u8>, to: usize) {
    while !(v.len() - 4).is_multiple_of(to) {
        v.push(0);
    }
}

#[test]
fn twist_cdr_is_six_float64_after_the_header() {
    let v = json!({"vx": 0.5, "vy": -0.25, "wz": 1.0});
    let out = types::encode(Ros2Type::Twist, &v, STAMP, "teleop", 0.0);
    let mut want = vec![0, 1, 0, 0];
    want.extend(f64s(&[0.5, -0.25, 0.0, 0.0, 0.0, 1.0]));
    assert_eq!(out, [want.clone()]);
    assert_eq!(want.len(), 52);
    // And back, as robot.toml's fields; bad encodings are refused.
    assert_eq!(types::decode_twist(&want).unwrap(), v);
    assert!(types::decode_twist(&want[..40]).is_err());
    let mut be = want.clone();
    be[1] = 0; // CDR_BE
    assert!(types::decode_twist(&be)
        .unwrap_err()
        .contains("00 00 00 00"));
    let mut long = want.clone();
    long.extend([0; 8]);
    assert!(types::decode_twist(&long)
        .unwrap_err()
        .contains("a Twist is 52"));
}

#[test]
fn odometry_cdr_follows_nav_msgs_odometry() {
    let v = json!({"x": 1.0, "y": 2.0, "theta": std::f64::consts::PI / 2.0, "vx": 0.3, "vy": 0.0, "wz": 0.1});
    let out = types::encode(Ros2Type::Odometry, &v, STAMP, "odometry", 0.0);
    let mut want = header("odom"); // 4 + 8 + 4 + 5 = 21
    pad(&mut want, 4);
    want.extend(10u32.to_le_bytes());
    want.extend(b"base_link\0");
    pad(&mut want, 8);
    let s = std::f64::consts::FRAC_PI_4.sin();
    let c = std::f64::consts::FRAC_PI_4.cos();
    want.extend(f64s(&[1.0, 2.0, 0.0, 0.0, 0.0, s, c]));
    want.extend(f64s(&[0.0; 36]));
    want.extend(f64s(&[0.3, 0.0, 0.0, 0.0, 0.0, 0.1]));
    want.extend(f64s(&[0.0; 36]));
    assert_eq!(out, [want.clone()]);
    assert_eq!(want.len(), 724);
}

#[test]
fn four_rangers_are_four_range_messages() {
    let v = json!({"range_mm": [800, 250, 0, 65535]});
    let out = types::encode(Ros2Type::Range, &v, STAMP, "proximity", 65.535);
    assert_eq!(out.len(), 4);
    for (i, mm) in [800.0f32, 250.0, 0.0, 65535.0].into_iter().enumerate() {
        let mut want = header(&format!("proximity_{i}"));
        want.push(1); // radiation_type INFRARED
        pad(&mut want, 4);
        for x in [0.0f32, 0.0, 65.535, mm / 1000.0, 0.0] {
            want.extend(x.to_le_bytes()); // fov, min, max, range, variance
        }
        assert_eq!(out[i], want, "ranger {i}");
    }
}

#[test]
fn battery_state_cdr_follows_sensor_msgs_battery_state() {
    let v = json!({"mv": 24960, "ma": -500, "pct": 90});
    let out = types::encode(Ros2Type::BatteryState, &v, STAMP, "battery", 0.0);
    let mut want = header("battery");
    pad(&mut want, 4);
    for x in [24.96f32, f32::NAN, -0.5, f32::NAN, f32::NAN, f32::NAN, 0.9] {
        want.extend(x.to_le_bytes());
    }
    want.extend([0, 0, 0, 1]); // status, health, technology UNKNOWN; present
    want.extend(0u32.to_le_bytes()); // cell_voltage []
    want.extend(0u32.to_le_bytes()); // cell_temperature []
    want.extend(1u32.to_le_bytes()); // location ""
    want.push(0);
    pad(&mut want, 4);
    want.extend(1u32.to_le_bytes()); // serial_number ""
    want.push(0);
    assert_eq!(out, [want]);
}
