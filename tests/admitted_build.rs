//! "`rtcan check` admits ⇒ the build succeeds", tested rather than hoped (issue 9).
//!
//! Every robot file of the repository (the robots, the UI suite's robots, the broken
//! ones) and a set of robots full of hostile names (Rust keywords, prelude and
//! generated item names, primitive type names, near-collisions after case conversion,
//! very long names) goes through the model. Each one `check` admits becomes one
//! `rtcan::robot!` module of a single scratch crate, compiled by ONE `cargo check`
//! (the cost of one compile, not one per robot). Every one `check` refuses is not
//! compiled, and the hostile names it refuses must be refused for a stated reason
//! (a keyword, a collision), which `rtcan-model/tests/names.rs` pins down.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_model::{analyze, Status};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.toml` robot of the repository, sorted.
fn repository_robots() -> Vec<PathBuf> {
    let mut out = vec![root().join("robot.toml")];
    for dir in ["robots", "robots/broken", "tests/robots", "tests/ui/robots"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
        out.extend(files);
    }
    out
}

const BUS: &str = "[bus]\ncycle = \"10ms\"\nslots = 20\nmaster = \"main\"\n\n";

/// Types named like prelude, core and generated items.
const TYPE_NAMES: &[&str] = &[
    "Option",
    "Some",
    "None",
    "Result",
    "Ok",
    "Err",
    "Default",
    "Clone",
    "Copy",
    "Debug",
    "PartialEq",
    "Eq",
    "Hash",
    "Send",
    "Sync",
    "Sized",
    "Fn",
    "Box",
    "Vec",
    "String",
    "Message",
    "Topic",
    "TopicInfo",
    "Engine",
    "Nanos",
    "Writer",
    "Reader",
    "Field",
    "Wire",
    "Node",
    "Publisher",
    "Subscriber",
    "ModuleHost",
    "BUS",
    "MASTER",
    "FINGERPRINT",
    "SIZE",
    "A",
    "U8",
    "SelfMsg",
    "Core",
    "Rtcan",
];

/// Fields named like what the generated `encode`/`decode` use, primitives, near-keywords.
const FIELD_NAMES: &[&str] = &[
    "w",
    "r",
    "out",
    "bytes",
    "size",
    "len",
    "u8",
    "f32",
    "bool",
    "str",
    "default",
    "encode",
    "decode",
    "put",
    "take",
    "zero",
    "self_",
    "type_",
    "r_type",
    "core",
    "std",
    "rtcan",
    "some",
    "none",
    "ok",
    "err",
    "option",
    "clone",
    "hash",
    "string",
    "unions",
    "abstract_",
    "a1",
    "a_1",
];

/// Modules named like generated items, crates and the items inside a module.
const MODULE_NAMES: &[&str] = &[
    "core",
    "std",
    "alloc",
    "rtcan_",
    // `nodes` itself is reserved (the generated `nodes` placement module).
    "nodes_",
    "pool",
    "tx",
    "rx",
    "reset",
    "engine",
    "host",
    "index",
    "bus",
    "master",
    "fingerprint",
    "topics_",
    "status",
    "tables",
    "filters",
    "a",
];

/// Nodes named like items of the module's `nodes`/`topics` modules and crates.
const NODE_NAMES: &[&str] = &[
    "nodes",
    "topics",
    "node",
    "priority",
    "core",
    "std",
    "pool",
    "super_",
    "reset",
    "tx",
    "rx",
    "engine",
    "host",
    "main_node",
];

/// Topics named like items next to them (`all`, `pool`, `tx`, `rx`), handles of other
/// topics (`x` and `x_pub`), crates, and near-collisions after CamelCase (`ab1` vs
/// `a_b1` → `Ab1Topic` / `AB1Topic`).
const TOPIC_NAMES: &[&str] = &[
    "all",
    "pool",
    "tx",
    "rx",
    "node",
    "priority",
    "nodes",
    "core",
    "std",
    "topics",
    "info",
    "reset",
    "status",
    "x",
    "x_pub",
    "x_sub",
    "x_pub_sub",
    "ab1",
    "a_b1",
    "engine",
    "host",
    "index",
    "bus",
    "master",
    "fingerprint",
    "topic",
    "a1b",
    "a1_b",
];

/// Robots whose names are all hostile; returns (file stem, text).
fn hostile_robots() -> Vec<(String, String)> {
    let long = "l".repeat(300);
    let long_camel = format!("L{}", "l".repeat(299));
    let mut out = Vec::new();

    // Types (each used by one topic so messages, aliases and handles are generated).
    let mut s = format!("{BUS}[modules.main]\nboard = \"stm32f103c8\"\n[modules.far]\nboard = \"stm32f103c8\"\n[nodes.n]\nmodule = \"main\"\n[nodes.f]\nmodule = \"far\"\n");
    for (i, t) in TYPE_NAMES.iter().chain([&long_camel.as_str()]).enumerate() {
        s += &format!("[types.{t}]\nv = \"u8\"\n[topics.t{i}]\ntype = \"{t}\"\npublisher = \"n\"\nclass = \"nrt\"\nsubscribers = [\"f\"]\n");
    }
    out.push(("types".to_string(), s));

    // Fields: one type with all of them, and the same names as fields of a second type.
    let mut fields = String::new();
    for f in FIELD_NAMES.iter().chain([&long.as_str()]) {
        fields += &format!("{f} = \"u8\"\n");
    }
    out.push((
        "fields".to_string(),
        format!("{BUS}[types.Many]\n{fields}[types.Again]\n{fields}[modules.main]\nboard = \"stm32f103re\"\n[modules.far]\nboard = \"qemu\"\n[nodes.n]\nmodule = \"main\"\n[nodes.f]\nmodule = \"far\"\n[topics.many]\ntype = \"Many\"\npublisher = \"n\"\nclass = \"srt\"\ndeadline = \"50ms\"\nrate = \"10Hz\"\nsubscribers = [\"f\", \"n\"]\n[topics.again]\ntype = \"Again\"\npublisher = \"f\"\nclass = \"hrt\"\nperiod_slots = 10\nsubscribers = [\"n\"]\n"),
    ));

    // Modules: one node each, publishing to the next module.
    let names: Vec<&str> = MODULE_NAMES
        .iter()
        .copied()
        .chain([long.as_str()])
        .collect();
    let mut s = BUS.replace("master = \"main\"", &format!("master = \"{}\"", names[0]));
    s += "[types.T]\nv = \"u16\"\n";
    for (i, m) in names.iter().enumerate() {
        s += &format!("[modules.{m}]\nboard = \"qemu\"\n[nodes.n{i}]\nmodule = \"{m}\"\n");
    }
    for i in 0..names.len() {
        let to = (i + 1) % names.len();
        s += &format!("[topics.t{i}]\ntype = \"T\"\npublisher = \"n{i}\"\nclass = \"nrt\"\nsubscribers = [\"n{to}\"]\n");
    }
    out.push(("modules".to_string(), s));

    // Nodes: half on each module, each publishing one topic to a node on the other.
    let names: Vec<&str> = NODE_NAMES.iter().copied().chain([long.as_str()]).collect();
    let mut s = format!("{BUS}[types.T]\nv = \"u32\"\n[modules.main]\nboard = \"stm32f103c8\"\n[modules.far]\nboard = \"stm32f103c8\"\n");
    for (i, n) in names.iter().enumerate() {
        let m = if i % 2 == 0 { "main" } else { "far" };
        s += &format!("[nodes.{n}]\nmodule = \"{m}\"\n");
    }
    for (i, n) in names.iter().enumerate() {
        let to = names[(i + 1) % names.len()];
        s += &format!("[topics.t{i}]\ntype = \"T\"\npublisher = \"{n}\"\nclass = \"nrt\"\nsubscribers = [\"{to}\", \"{n}\"]\n");
    }
    out.push(("nodes".to_string(), s));

    // Topics: all published on `main`, subscribed on `far` and locally.
    let mut s = format!("{BUS}[types.T]\nv = \"[u8; 12]\"\n[modules.main]\nboard = \"stm32f103c8\"\n[modules.far]\nboard = \"stm32f103c8\"\n[nodes.n]\nmodule = \"main\"\n[nodes.f]\nmodule = \"far\"\n");
    for (i, t) in TOPIC_NAMES.iter().chain([&long.as_str()]).enumerate() {
        let class = match i % 3 {
            0 => "class = \"nrt\"",
            1 => "class = \"srt\"\ndeadline = \"100ms\"\nrate = \"1Hz\"",
            _ => "class = \"hrt\"\nperiod_slots = 100",
        };
        s += &format!("[topics.{t}]\ntype = \"T\"\npublisher = \"n\"\n{class}\nsubscribers = [\"f\", \"n\"]\n");
    }
    out.push(("topics".to_string(), s));

    // Payload edges: an empty message, the largest one, every array type, one field of
    // each primitive; single- and multi-frame, on every class.
    let mut s = BUS
        .replace("slots = 20", "slots = 10")
        .replace("cycle = \"10ms\"", "cycle = \"100ms\"");
    s += "[types.Empty]\n[types.Max]\nv = \"[u8; 256]\"\n[types.Arrays]\n";
    for p in [
        "u8", "u16", "u32", "u64", "i8", "i16", "i32", "i64", "f32", "f64", "bool",
    ] {
        s += &format!("a_{p} = \"[{p}; 2]\"\n{p}_ = \"{p}\"\n");
    }
    s += "[modules.main]\nboard = \"stm32f103re\"\n[modules.far]\nboard = \"stm32f103re\"\n[nodes.n]\nmodule = \"main\"\n[nodes.f]\nmodule = \"far\"\n";
    for (i, ty) in ["Empty", "Max", "Arrays"].iter().enumerate() {
        s += &format!("[topics.nrt_{i}]\ntype = \"{ty}\"\npublisher = \"n\"\nclass = \"nrt\"\nsubscribers = [\"f\"]\n");
        s += &format!("[topics.srt_{i}]\ntype = \"{ty}\"\npublisher = \"f\"\nclass = \"srt\"\ndeadline = \"1s\"\nsubscribers = [\"n\"]\n");
    }
    s += "[topics.hrt_0]\ntype = \"Empty\"\npublisher = \"n\"\nclass = \"hrt\"\nperiod_slots = 10\nsubscribers = [\"f\"]\n";
    s += "[types.Pair]\nv = \"[u16; 5]\"\n[topics.hrt_2]\ntype = \"Pair\"\npublisher = \"f\"\nclass = \"hrt\"\nperiod_slots = 20\nsubscribers = [\"n\"]\n";
    out.push(("payloads".to_string(), s));
    out
}

#[test]
fn every_robot_check_admits_builds() {
    let scratch = root().join("target/admitted-build");
    let robots_dir = scratch.join("robots");
    std::fs::create_dir_all(robots_dir.join("x")).unwrap();
    let mut admitted: Vec<PathBuf> = Vec::new();
    let mut refused = Vec::new();
    for path in repository_robots() {
        let src = std::fs::read_to_string(&path).unwrap();
        match analyze(&path.display().to_string(), &src).status() {
            Status::Admissible => admitted.push(path),
            _ => refused.push(path),
        }
    }
    // The repository's robot files that must be admitted (and therefore build).
    for must in [
        "robot.toml",
        "robots/rtcan-paper.toml",
        "robots/hrt200.toml",
        "tests/robots/codec.toml",
        "robots/services.toml",
    ] {
        assert!(admitted.contains(&root().join(must)), "{must} not admitted");
    }
    // The UI suite's build-only failures of before (a module named `topics`, a pool of
    // 42 blocks) are now refused by check.
    for must in [
        "tests/ui/robots/reserved-module.toml",
        "tests/ui/robots/pool-too-large.toml",
    ] {
        assert!(refused.contains(&root().join(must)), "{must} admitted");
    }
    for (stem, text) in hostile_robots() {
        let path = robots_dir.join(format!("{stem}.toml"));
        std::fs::write(&path, &text).unwrap();
        let a = analyze(&path.display().to_string(), &text);
        // Every hostile name is a legal name: all of these robots must be admitted.
        assert_eq!(
            a.status(),
            Status::Admissible,
            "{stem}: {}",
            a.diagnostics.render()
        );
        admitted.push(path);
    }

    let krate = scratch.join("crate");
    std::fs::create_dir_all(krate.join("src")).unwrap();
    std::fs::write(
        krate.join("Cargo.toml"),
        format!(
            "[package]\nname = \"admitted-build\"\nversion = \"0.0.0\"\nedition = \"2021\"\npublish = false\n\n[dependencies]\nrtcan = {{ path = {:?} }}\n\n# Its own workspace, not a member of the rtcan workspace it sits in.\n[workspace]\n",
            root().display().to_string()
        ),
    )
    .unwrap();
    // Same dependency versions as the workspace, resolved offline.
    std::fs::copy(root().join("Cargo.lock"), krate.join("Cargo.lock")).unwrap();
    let mut lib = String::from(
        "//! @generated by tests/admitted_build.rs: one module per robot `rtcan check` admits.\n#![no_std]\n",
    );
    for (i, p) in admitted.iter().enumerate() {
        lib += &format!(
            "/// {}\npub mod robot{i} {{\n    rtcan::robot!({:?});\n}}\n",
            p.display(),
            p.display().to_string()
        );
    }
    std::fs::write(krate.join("src/lib.rs"), lib).unwrap();

    let out = Command::new(env!("CARGO"))
        .args(["check", "--offline", "--quiet", "--manifest-path"])
        .arg(krate.join("Cargo.toml"))
        .env("CARGO_TARGET_DIR", scratch.join("target"))
        // The scratch crate has no workspace robot of its own.
        .env_remove("RTCAN_ROBOT")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "{} admitted robots, the build failed:\n{stderr}",
        admitted.len()
    );
    assert_eq!(
        stderr.matches("warning").count(),
        0,
        "generated code has warnings:\n{stderr}"
    );
    assert!(Path::new(&krate.join("src/lib.rs")).exists());
}
