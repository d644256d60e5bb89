//! `[robot] name`, `writable`, `link` and `ros2` in robot.toml (issue 13): read with
//! spans, link topics numbered from the declaration, bad values refused rustc-style.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use rtcan_model::bridge_keys::{default_name, LinkDir, LinkTopic, Ros2Type};
use rtcan_model::{analyze, Robot};

fn robot() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    std::fs::read_to_string(path).unwrap()
}

#[test]
fn triskar2_declares_its_name_link_writable_and_ros2_topics() {
    let plan = Robot::parse("robot.toml", &robot()).unwrap();
    let b = &plan.bridge;
    assert_eq!(b.robot, "triskar2");
    assert_eq!(b.writable(), ["teleop"]);
    let l = |n: u8, name: &str, dir, size| LinkTopic {
        number: n,
        name: name.into(),
        dir,
        size,
    };
    assert_eq!(
        b.link,
        [
            l(1, "teleop", LinkDir::In, 12),
            l(2, "odometry", LinkDir::Out, 24),
            l(3, "proximity", LinkDir::Out, 8),
            l(4, "battery", LinkDir::Out, 5),
            l(5, "log", LinkDir::Out, 32),
        ]
    );
    let ros2: Vec<_> = b
        .topics
        .iter()
        .filter_map(|t| Some((t.name.as_str(), t.ros2?)))
        .collect();
    assert_eq!(
        ros2,
        [
            ("teleop", Ros2Type::Twist),
            ("velocity", Ros2Type::Twist),
            ("odometry", Ros2Type::Odometry),
            ("proximity", Ros2Type::Range),
            ("battery", Ros2Type::BatteryState),
        ]
    );
    // The keys do not change the bus: same fingerprint without them.
    let bare: String = robot()
        .lines()
        .filter(|l| {
            !(l.starts_with("writable")
                || l.starts_with("link")
                || l.starts_with("ros2")
                || l.starts_with("[robot]")
                || l.starts_with("name ="))
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let p2 = Robot::parse("robot.toml", &bare).unwrap();
    assert_eq!(p2.fingerprint, plan.fingerprint);
    assert_eq!(p2.bridge.robot, "robot", "default: the file stem");
    assert!(p2.bridge.link.is_empty() && p2.bridge.writable().is_empty());
}

#[test]
fn the_default_name_is_the_file_stem_made_a_valid_name() {
    assert_eq!(default_name("robots/paper_bus.toml"), "paper_bus");
    assert_eq!(default_name("my robot-2.toml"), "my_robot_2");
    assert_eq!(default_name("2go.toml"), "robot");
    assert_eq!(default_name(""), "robot");
}

/// robot.toml with `extra` put into `[topics.teleop]` and `top` before `[bus]`.
fn with(top: &str, extra: &str) -> String {
    robot()
        .replace("[robot]\nname = \"triskar2\"", top)
        .replace(
            "writable = true         # the host / Zenoh / ROS 2 may command it\n",
            &format!("{extra}\n"),
        )
}

fn errors(src: &str) -> String {
    let a = analyze("robot.toml", src);
    assert!(a.plan.is_none(), "accepted");
    a.diagnostics.render()
}

#[test]
fn bad_values_are_rustc_style_errors_with_a_hint() {
    let cases: [(&str, &str, &[&str]); 8] = [
        (
            "[robot]\nname = \"tri/skar\"",
            "writable = true",
            &[
                "error[bad-value]: robot name \"tri/skar\"",
                "--> robot.toml:NAME:8",
                "help: use an ASCII letter",
            ],
        ),
        (
            "[robot]\nname = 7",
            "writable = true",
            &["error[wrong-type]: `[robot] name` must be a string, found an integer"],
        ),
        (
            "[robot]\nnmae = \"x\"",
            "writable = true",
            &["error[unknown-key]: unknown key `nmae` in `[robot]`", "help: expected `name`"],
        ),
        (
            "[robot]\nname = \"t\"",
            "writable = \"yes\"",
            &["error[wrong-type]: topic `teleop` `writable` must be a boolean, found a string"],
        ),
        (
            "[robot]\nname = \"t\"",
            "writable = true\nlink = \"both\"",
            &[
                "error[bad-value]: topic `teleop` `link` is \"both\"",
                "help: expected \"in\" (host → robot) or \"out\" (robot → host)",
            ],
        ),
        (
            "[robot]\nname = \"t\"",
            "writable = true\nros2 = \"geometry_msgs/msg/Pose\"",
            &[
                "error[bad-value]: topic `teleop` `ros2`: no mapping to \"geometry_msgs/msg/Pose\"",
                "help: supported: \"geometry_msgs/msg/Twist\", \"nav_msgs/msg/Odometry\"",
            ],
        ),
        (
            "[robot]\nname = \"t\"",
            "writable = true\nros2 = \"nav_msgs/msg/Odometry\"",
            &["error[bad-value]: topic `teleop` `ros2 = \"nav_msgs/msg/Odometry\"` reads fields `x`, `y`, `theta` of `Twist`"],
        ),
        (
            "[robot]\nname = \"t\"",
            "writable = true\nros2 = 3",
            &["error[wrong-type]: topic `teleop` `ros2` must be a string, found an integer"],
        ),
    ];
    // The `[robot] name` line of robot.toml, wherever edits above it moved it.
    let name_line = robot()
        .lines()
        .position(|l| l.starts_with("name = \"triskar2\""))
        .map(|i| i + 1)
        .expect("robot.toml has `[robot] name`");
    let name_at = format!("--> robot.toml:{name_line}:8");
    for (top, extra, want) in cases {
        // The duplicate keys of the unchanged lines would be TOML errors: drop them.
        let src = with(top, extra);
        let src = if extra.contains("link") {
            src.replacen(
                "link = \"in\"             # host -> gateway over the serial link\n",
                "",
                1,
            )
        } else {
            src
        };
        let src = if extra.contains("ros2") {
            src.replacen(
                "ros2 = \"geometry_msgs/msg/Twist\"\n\n[topics.velocity]",
                "\n[topics.velocity]",
                1,
            )
        } else {
            src
        };
        let out = errors(&src);
        for w in want {
            let w = if *w == "--> robot.toml:NAME:8" {
                name_at.as_str()
            } else {
                w
            };
            assert!(out.contains(w), "want `{w}` in\n{out}");
        }
    }
}

#[test]
fn a_link_topic_larger_than_a_link_frame_is_refused() {
    let src = robot().replace(
        "[topics.encoder1]       # 200 Hz PID loop on each motor module\ntype = \"Encoder\"",
        "[topics.encoder1]\ntype = \"Encoder\"\nlink = \"out\"",
    );
    let plan = Robot::parse("robot.toml", &src).unwrap();
    assert_eq!(plan.bridge.link_topic("encoder1").unwrap().number, 2);
    assert_eq!(plan.bridge.link_topic("log").unwrap().number, 6);
    // A 40-byte type on the link.
    let src = robot().replace("text = \"[u8; 29]\"", "text = \"[u8; 37]\"");
    let out = errors(&src);
    assert!(
        out.contains(
            "error[bad-value]: topic `log` is 40 bytes; the gateway's link carries at most 32"
        ),
        "{out}"
    );
}

#[test]
fn remote_imports_name_a_robot_and_topic_and_need_writable() {
    let src = robot().replace(
        "writable = true         # the host / Zenoh / ROS 2 may command it\n",
        "writable = true\nremote = \"leader/velocity\"\n",
    );
    let plan = Robot::parse("robot.toml", &src).unwrap();
    assert_eq!(
        plan.bridge.imports(),
        [(
            "teleop".to_string(),
            "leader".to_string(),
            "velocity".to_string()
        )]
    );
    for (line, want) in [
        (
            "remote = \"leader\"",
            "error[bad-value]: topic `teleop` `remote` is \"leader\": not `<robot>/<topic>`",
        ),
        ("remote = \"lead/er/velocity\"", "not `<robot>/<topic>`"),
        (
            "remote = 1",
            "error[wrong-type]: topic `teleop` `remote` must be a string",
        ),
    ] {
        let src = robot().replace(
            "writable = true         # the host / Zenoh / ROS 2 may command it\n",
            &format!("writable = true\n{line}\n"),
        );
        let out = errors(&src);
        assert!(out.contains(want), "want `{want}` in\n{out}");
    }
    let src = robot().replace(
        "writable = true         # the host / Zenoh / ROS 2 may command it\n",
        "remote = \"leader/velocity\"\n",
    );
    let out = errors(&src);
    assert!(
        out.contains("error[bad-value]: topic `teleop` takes messages from another robot but is not writable")
            && out.contains("help: add `writable = true`"),
        "{out}"
    );
}

#[test]
fn a_module_named_link_collides_with_the_generated_link_numbers() {
    let src = robot()
        .replace("[modules.psu]", "[modules.link]")
        .replace("module = \"psu\"", "module = \"link\"");
    let out = errors(&src);
    assert!(
        out.contains("error[name-collision]: module name `link` collides with the generated module holding the serial link's topic numbers"),
        "{out}"
    );
}
