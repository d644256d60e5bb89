//! The standard ROS 2 types robot.toml can map a topic to: their type descriptions (for
//! the RIHS01 type hash of REP-2016 that rmw_zenoh puts in every key expression), their
//! DDS names, and the conversion of a robot.toml value to / from their CDR.
//!
//! RIHS01 (rosidl_generator_type_description): SHA-256 of the JSON
//! `{"type_description": T, "referenced_type_descriptions": [R...]}` written with
//! `", "` / `": "` separators, where each description is `{"type_name", "fields"}` and
//! each field `{"name", "type": {"type_id", "capacity", "string_capacity",
//! "nested_type_name"}}` (default values left out), the referenced types sorted by name.
//! Tested against the hashes published with rmw_zenoh's design.md examples.
use rtcan_model::bridge_keys::Ros2Type;
use serde_json::Value;

use super::cdr::{Reader, Writer};

/// `type_id` values of type_description_interfaces/msg/FieldType.
mod id {
    pub const NESTED: u8 = 1;
    pub const UINT8: u8 = 3;
    pub const INT32: u8 = 6;
    pub const UINT32: u8 = 7;
    pub const FLOAT: u8 = 10;
    pub const DOUBLE: u8 = 11;
    pub const BOOLEAN: u8 = 15;
    pub const STRING: u8 = 17;
    /// Added to a type for a fixed-size array.
    pub const ARRAY: u8 = 48;
    /// Added to a type for an unbounded sequence.
    pub const SEQUENCE: u8 = 144;
}

/// One field of a type description.
#[derive(Clone, Copy, Debug)]
pub struct FieldDesc {
    name: &'static str,
    type_id: u8,
    capacity: u32,
    nested: &'static str,
}

/// One individual type description.
#[derive(Clone, Copy, Debug)]
pub struct TypeDesc {
    /// `pkg/msg/Type`.
    pub name: &'static str,
    fields: &'static [FieldDesc],
}

const fn f(name: &'static str, type_id: u8) -> FieldDesc {
    FieldDesc {
        name,
        type_id,
        capacity: 0,
        nested: "",
    }
}

const fn nested(name: &'static str, ty: &'static str) -> FieldDesc {
    FieldDesc {
        name,
        type_id: id::NESTED,
        capacity: 0,
        nested: ty,
    }
}

const fn array(name: &'static str, type_id: u8, capacity: u32) -> FieldDesc {
    FieldDesc {
        name,
        type_id: type_id + id::ARRAY,
        capacity,
        nested: "",
    }
}

const TIME: TypeDesc = TypeDesc {
    name: "builtin_interfaces/msg/Time",
    fields: &[f("sec", id::INT32), f("nanosec", id::UINT32)],
};
const HEADER: TypeDesc = TypeDesc {
    name: "std_msgs/msg/Header",
    fields: &[
        nested("stamp", "builtin_interfaces/msg/Time"),
        f("frame_id", id::STRING),
    ],
};
const VECTOR3: TypeDesc = TypeDesc {
    name: "geometry_msgs/msg/Vector3",
    fields: &[f("x", id::DOUBLE), f("y", id::DOUBLE), f("z", id::DOUBLE)],
};
const TWIST: TypeDesc = TypeDesc {
    name: "geometry_msgs/msg/Twist",
    fields: &[
        nested("linear", "geometry_msgs/msg/Vector3"),
        nested("angular", "geometry_msgs/msg/Vector3"),
    ],
};
const POINT: TypeDesc = TypeDesc {
    name: "geometry_msgs/msg/Point",
    fields: &[f("x", id::DOUBLE), f("y", id::DOUBLE), f("z", id::DOUBLE)],
};
const QUATERNION: TypeDesc = TypeDesc {
    name: "geometry_msgs/msg/Quaternion",
    fields: &[
        f("x", id::DOUBLE),
        f("y", id::DOUBLE),
        f("z", id::DOUBLE),
        f("w", id::DOUBLE),
    ],
};
const POSE: TypeDesc = TypeDesc {
    name: "geometry_msgs/msg/Pose",
    fields: &[
        nested("position", "geometry_msgs/msg/Point"),
        nested("orientation", "geometry_msgs/msg/Quaternion"),
    ],
};
const POSE_COV: TypeDesc = TypeDesc {
    name: "geometry_msgs/msg/PoseWithCovariance",
    fields: &[
        nested("pose", "geometry_msgs/msg/Pose"),
        array("covariance", id::DOUBLE, 36),
    ],
};
const TWIST_COV: TypeDesc = TypeDesc {
    name: "geometry_msgs/msg/TwistWithCovariance",
    fields: &[
        nested("twist", "geometry_msgs/msg/Twist"),
        array("covariance", id::DOUBLE, 36),
    ],
};
const ODOMETRY: TypeDesc = TypeDesc {
    name: "nav_msgs/msg/Odometry",
    fields: &[
        nested("header", "std_msgs/msg/Header"),
        f("child_frame_id", id::STRING),
        nested("pose", "geometry_msgs/msg/PoseWithCovariance"),
        nested("twist", "geometry_msgs/msg/TwistWithCovariance"),
    ],
};
/// sensor_msgs/msg/Range with its `variance` field (the current common_interfaces).
const RANGE: TypeDesc = TypeDesc {
    name: "sensor_msgs/msg/Range",
    fields: &[
        nested("header", "std_msgs/msg/Header"),
        f("radiation_type", id::UINT8),
        f("field_of_view", id::FLOAT),
        f("min_range", id::FLOAT),
        f("max_range", id::FLOAT),
        f("range", id::FLOAT),
        f("variance", id::FLOAT),
    ],
};
const BATTERY_STATE: TypeDesc = TypeDesc {
    name: "sensor_msgs/msg/BatteryState",
    fields: &[
        nested("header", "std_msgs/msg/Header"),
        f("voltage", id::FLOAT),
        f("temperature", id::FLOAT),
        f("current", id::FLOAT),
        f("charge", id::FLOAT),
        f("capacity", id::FLOAT),
        f("design_capacity", id::FLOAT),
        f("percentage", id::FLOAT),
        f("power_supply_status", id::UINT8),
        f("power_supply_health", id::UINT8),
        f("power_supply_technology", id::UINT8),
        f("present", id::BOOLEAN),
        FieldDesc {
            name: "cell_voltage",
            type_id: id::FLOAT + id::SEQUENCE,
            capacity: 0,
            nested: "",
        },
        FieldDesc {
            name: "cell_temperature",
            type_id: id::FLOAT + id::SEQUENCE,
            capacity: 0,
            nested: "",
        },
        f("location", id::STRING),
        f("serial_number", id::STRING),
    ],
};
/// std_msgs/msg/String: the type of design.md's `chatter` examples (tests only).
pub const STRING_MSG: TypeDesc = TypeDesc {
    name: "std_msgs/msg/String",
    fields: &[f("data", id::STRING)],
};

const ALL: [TypeDesc; 13] = [
    TIME,
    HEADER,
    VECTOR3,
    TWIST,
    POINT,
    QUATERNION,
    POSE,
    POSE_COV,
    TWIST_COV,
    ODOMETRY,
    RANGE,
    BATTERY_STATE,
    STRING_MSG,
];

/// The description of a mapped type.
pub fn description(t: Ros2Type) -> TypeDesc {
    match t {
        Ros2Type::Twist => TWIST,
        Ros2Type::Odometry => ODOMETRY,
        Ros2Type::Range => RANGE,
        Ros2Type::BatteryState => BATTERY_STATE,
    }
}

fn json_desc(d: &TypeDesc) -> String {
    let fields: Vec<String> = d
        .fields
        .iter()
        .map(|x| {
            format!(
                "{{\"name\": \"{}\", \"type\": {{\"type_id\": {}, \"capacity\": {}, \"string_capacity\": 0, \"nested_type_name\": \"{}\"}}}}",
                x.name, x.type_id, x.capacity, x.nested
            )
        })
        .collect();
    format!(
        "{{\"type_name\": \"{}\", \"fields\": [{}]}}",
        d.name,
        fields.join(", ")
    )
}

/// The JSON a RIHS01 hash is the SHA-256 of.
pub fn hash_input(d: &TypeDesc) -> String {
    // Every type `d` refers to, transitively, sorted by name.
    let mut refs: Vec<&TypeDesc> = Vec::new();
    let mut todo: Vec<&str> = d.fields.iter().map(|x| x.nested).collect();
    while let Some(n) = todo.pop() {
        if n.is_empty() || refs.iter().any(|r| r.name == n) {
            continue;
        }
        if let Some(r) = ALL.iter().find(|r| r.name == n) {
            todo.extend(r.fields.iter().map(|x| x.nested));
            refs.push(r);
        }
    }
    refs.sort_by_key(|r| r.name);
    let refs: Vec<String> = refs.iter().map(|r| json_desc(r)).collect();
    format!(
        "{{\"type_description\": {}, \"referenced_type_descriptions\": [{}]}}",
        json_desc(d),
        refs.join(", ")
    )
}

/// `RIHS01_<sha256 hex>` of a type description.
pub fn type_hash(d: &TypeDesc) -> String {
    let digest = sha2_const_stable::Sha256::new()
        .update(hash_input(d).as_bytes())
        .finalize();
    let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
    format!("RIHS01_{hex}")
}

/// The DDS name rmw_zenoh uses in keys: `pkg/msg/Type` → `pkg::msg::dds_::Type_`.
pub fn dds_name(ros_name: &str) -> String {
    let mut parts: Vec<&str> = ros_name.split('/').collect();
    let last = parts.pop().unwrap_or("");
    format!("{}::dds_::{last}_", parts.join("::"))
}

/// A ROS 2 `builtin_interfaces/Time` (seconds, nanoseconds).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stamp {
    /// Seconds since the UNIX epoch.
    pub sec: i32,
    /// Nanoseconds.
    pub nanosec: u32,
}

impl Stamp {
    /// From ns since the UNIX epoch.
    pub fn from_ns(ns: i64) -> Stamp {
        Stamp {
            sec: i32::try_from(ns.div_euclid(1_000_000_000)).unwrap_or(i32::MAX),
            nanosec: u32::try_from(ns.rem_euclid(1_000_000_000)).unwrap_or(0),
        }
    }
}

fn num(v: &Value, k: &str) -> f64 {
    v.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN)
}

fn header(w: &mut Writer, stamp: Stamp, frame_id: &str) {
    w.i32(stamp.sec).u32(stamp.nanosec).string(frame_id);
}

/// The ROS 2 messages of one robot message `v` (robot.toml field names, as
/// `rtcan_host::value::to_json` gives them): one per topic, `Range` one per element of
/// `range_mm`. `frame` names the frames (`odom`/`base_link`; `<frame>_<i>` for rangers);
/// `range_max_m` is the largest range the field can hold.
pub fn encode(t: Ros2Type, v: &Value, stamp: Stamp, frame: &str, range_max_m: f32) -> Vec<Vec<u8>> {
    let mut w = Writer::new();
    match t {
        Ros2Type::Twist => {
            w.f64(num(v, "vx")).f64(num(v, "vy")).f64(0.0);
            w.f64(0.0).f64(0.0).f64(num(v, "wz"));
        }
        Ros2Type::Odometry => {
            header(&mut w, stamp, "odom");
            w.string("base_link");
            let half = num(v, "theta") / 2.0;
            w.f64(num(v, "x")).f64(num(v, "y")).f64(0.0);
            w.f64(0.0).f64(0.0).f64(half.sin()).f64(half.cos());
            for _ in 0..36 {
                w.f64(0.0);
            }
            w.f64(num(v, "vx")).f64(num(v, "vy")).f64(0.0);
            w.f64(0.0).f64(0.0).f64(num(v, "wz"));
            for _ in 0..36 {
                w.f64(0.0);
            }
        }
        Ros2Type::Range => {
            let ranges: Vec<f64> = match v.get("range_mm") {
                Some(Value::Array(a)) => a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect(),
                Some(x) => vec![x.as_f64().unwrap_or(f64::NAN)],
                None => Vec::new(),
            };
            let single = !matches!(v.get("range_mm"), Some(Value::Array(_)));
            return ranges
                .iter()
                .enumerate()
                .map(|(i, mm)| {
                    let mut w = Writer::new();
                    let id = if single {
                        frame.to_string()
                    } else {
                        format!("{frame}_{i}")
                    };
                    header(&mut w, stamp, &id);
                    // INFRARED; field of view unknown (0); metres.
                    w.u8(1).f32(0.0).f32(0.0).f32(range_max_m);
                    w.f32((mm / 1000.0) as f32).f32(0.0);
                    w.finish()
                })
                .collect();
        }
        Ros2Type::BatteryState => {
            header(&mut w, stamp, frame);
            w.f32((num(v, "mv") / 1000.0) as f32);
            w.f32(f32::NAN); // temperature: not measured
            w.f32((num(v, "ma") / 1000.0) as f32);
            w.f32(f32::NAN).f32(f32::NAN).f32(f32::NAN); // charge, capacity, design
            w.f32((num(v, "pct") / 100.0) as f32);
            // status, health, technology: UNKNOWN; present.
            w.u8(0).u8(0).u8(0).bool(true);
            w.seq_len(0).seq_len(0).string("").string("");
        }
    }
    vec![w.finish()]
}

/// A `geometry_msgs/msg/Twist` from ROS 2 as robot.toml's fields `vx`, `vy`, `wz`
/// (linear.x, linear.y, angular.z: a planar base ignores the other three).
pub fn decode_twist(cdr: &[u8]) -> Result<Value, String> {
    let mut r = Reader::new(cdr)?;
    let mut x = [0.0f64; 6];
    for v in &mut x {
        *v = r.f64()?;
    }
    if r.rest() > 3 {
        return Err(format!("{} bytes: a Twist is 52", cdr.len()));
    }
    Ok(serde_json::json!({"vx": x[0], "vy": x[1], "wz": x[5]}))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dds_names_follow_rmw_zenoh() {
        assert_eq!(
            dds_name("std_msgs/msg/String"),
            "std_msgs::msg::dds_::String_"
        );
        assert_eq!(
            dds_name("geometry_msgs/msg/Twist"),
            "geometry_msgs::msg::dds_::Twist_"
        );
    }

    #[test]
    fn the_hash_input_is_rosidl_json() {
        assert_eq!(
            hash_input(&STRING_MSG),
            r#"{"type_description": {"type_name": "std_msgs/msg/String", "fields": [{"name": "data", "type": {"type_id": 17, "capacity": 0, "string_capacity": 0, "nested_type_name": ""}}]}, "referenced_type_descriptions": []}"#
        );
    }
}
