#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! `rtcan new`: the files it writes for a robot that is not Triskar2, re-running after a
//! robot.toml edit (user files kept, new ones added), and a bad robot (exit 2, nothing
//! written). Building and simulating the written workspaces: scripts/scaffold-check.sh.
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .canonicalize()
        .unwrap()
}

fn rtcan(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

/// A fresh directory under the target dir (no temp-file crate in this workspace).
fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("new-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn all_files(d: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(d).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            all_files(&p, out);
        } else {
            out.push(p);
        }
    }
}

#[test]
fn kapeck_workspace_has_one_image_per_module_and_one_file_per_node() {
    let d = scratch("kapeck");
    let ds = d.to_str().unwrap();
    let (code, out, err) = rtcan(&["new", ds, "--robot", "robots/kapeck.toml"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("created   nodes/src/pid_left.rs"), "{out}");
    assert_eq!(
        read(&d.join("robot.toml")),
        read(&root().join("robots/kapeck.toml"))
    );
    for m in ["gateway", "motor_left", "motor_right", "sonar"] {
        let bin = read(&d.join(format!("firmware/src/bin/{m}.rs")));
        assert!(bin.contains(&format!("use robot::{m} as module;")), "{bin}");
        assert!(bin.contains(&format!("\nnodes::{m}_app!();\n")), "{bin}");
        assert!(!bin.contains("type App"), "{bin}");
        let manifest = read(&d.join("firmware/Cargo.toml"));
        assert!(manifest.contains(&format!(
            "[[bin]]\nname = \"{m}\"\npath = \"src/bin/{m}.rs\""
        )));
    }
    // Each node an RTIC task at the rank of its robot.toml priority (host 1, sonar_ctrl
    // 2, pid_* 3 → 1, 2, 3), generated into the nodes crate for the bins.
    let modules = read(&d.join("nodes/src/modules.rs"));
    for (m, n, p) in [
        ("gateway", "host", 1),
        ("sonar", "sonar_ctrl", 2),
        ("motor_left", "pid_left", 3),
        ("motor_right", "pid_right", 3),
    ] {
        assert!(
            modules.contains(&format!("macro_rules! {m}_app {{")),
            "{modules}"
        );
        assert!(
            modules.contains(&format!(
                "{{ index: 0, name: node_{n}, priority: {p}, task: nodes::modules::tasks::{n}, "
            )),
            "{modules}"
        );
    }
    // Exactly the four images: no bin for anything else.
    assert_eq!(
        std::fs::read_dir(d.join("firmware/src/bin"))
            .unwrap()
            .count(),
        4
    );
    for n in ["host", "pid_left", "pid_right", "sonar_ctrl"] {
        assert!(d.join(format!("nodes/src/{n}.rs")).is_file(), "{n}");
        assert!(read(&d.join("nodes/src/lib.rs")).contains(&format!("pub mod {n};\n")));
    }
    // Typed handles for exactly the node's topics, at their rates (kapeck: 40 slots of
    // 250 us, so the 100 Hz HRT encoder is every 10 000 000 ns; the 10 Hz SRT request
    // 1 / rate).
    let pid = read(&d.join("nodes/src/pid_left.rs"));
    assert!(pid.contains("use crate::robot::nodes::pid_left as io;"));
    assert!(pid.contains("io::encoder_left_pub().send(value, now)"));
    assert!(pid.contains("io::wheel_refs_sub().try_recv()"));
    // HRT: synchronous (lead before each slot, R2P §3.4.5), the period before sync.
    assert!(pid.contains(
        "encoder_left: rtcan::pubsub::SlotEvery::new(io::ENCODER_LEFT_SLOTS, 10000000),"
    ));
    assert!(pid.contains("if self.encoder_left.due(now, io::module::STATUS.grid()) && running {"));
    assert!(pid.contains("let running = run_node(&io::NODE, &io::module::STATUS);"));
    assert!(
        !pid.contains("motor_left::"),
        "no module named: the node can move"
    );
    assert!(pid.contains("robot::Encoder::default()"));
    assert!(
        !pid.contains("sonar") && !pid.contains("encoder_right"),
        "{pid}"
    );
    let host = read(&d.join("nodes/src/host.rs"));
    assert!(host.contains("sonar_request: Every::new(100000000),"));
    for t in ["encoder_left", "encoder_right", "sonar_ranges"] {
        assert!(host.contains(&format!("io::{t}_sub()")), "{t}");
    }
    assert!(!host.contains("_pub().send") || host.contains("io::wheel_refs_pub()"));
    // The module app polls its nodes; probe-rs chips per board; default budgets.
    let modules = read(&d.join("nodes/src/modules.rs"));
    assert!(modules
        .contains("pub struct MotorLeftApp {\n    pub pid_left: crate::pid_left::PidLeft,\n}"));
    let probe = read(&d.join("firmware/probe-run.sh"));
    assert!(probe.contains("    gateway) chip=STM32F103RE ;;\n"));
    assert!(probe.contains("    sonar) chip=STM32F103C8 ;;\n"));
    let budgets = read(&d.join("firmware/budgets.toml"));
    assert!(budgets.contains("[motor_right]\nflash = 40960\nram = 10240\n"));
    assert!(read(&d.join("README.md")).contains("cargo run -p sim"));
    assert!(read(&d.join("Cargo.toml")).contains("members = [\"nodes\", \"sim\"]"));
    // No placeholder anywhere: every body compiles and runs as written.
    let mut files = Vec::new();
    all_files(&d, &mut files);
    for f in files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "rs"))
    {
        let t = read(f);
        assert!(
            !t.contains("todo!") && !t.contains("unimplemented!"),
            "{}",
            f.display()
        );
    }
}

#[test]
fn rerun_after_an_edit_adds_new_files_and_keeps_the_users() {
    let d = scratch("rerun");
    let ds = d.to_str().unwrap();
    let (code, _, err) = rtcan(&["new", ds, "--robot", "robots/kapeck.toml"]);
    assert_eq!(code, 0, "{err}");
    // The user edits a node and a budget...
    let pid = d.join("nodes/src/pid_left.rs");
    let edited = format!("{}\n// my PID gains: kp 1.5\n", read(&pid));
    std::fs::write(&pid, &edited).unwrap();
    let budgets = d.join("firmware/budgets.toml");
    let b = read(&budgets).replace("[sonar]\nflash = 40960", "[sonar]\nflash = 20000");
    std::fs::write(&budgets, &b).unwrap();
    // ...and robot.toml: a bumper board with a node and a topic to the host.
    let robot = d.join("robot.toml");
    let mut t = read(&robot);
    t.push_str(
        "\n[modules.bumper]\nboard = \"stm32f103c8\"\n\n[nodes.bump_ctrl]\nmodule = \"bumper\"\n\n\
         [topics.bump]\ntype = \"SonarRequest\"\npublisher = \"bump_ctrl\"\nclass = \"srt\"\n\
         deadline = \"10ms\"\nrate = \"5Hz\"\nsubscribers = [\"host\"]\n",
    );
    std::fs::write(&robot, &t).unwrap();
    let host_before = read(&d.join("nodes/src/host.rs"));
    let (code, out, err) = rtcan(&["new", ds]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        read(&pid),
        edited,
        "a user's node file is never overwritten"
    );
    assert_eq!(read(&d.join("nodes/src/host.rs")), host_before);
    assert!(out.contains("kept      nodes/src/pid_left.rs"), "{out}");
    assert!(out.contains("created   nodes/src/bump_ctrl.rs"), "{out}");
    assert!(
        out.contains("created   firmware/src/bin/bumper.rs"),
        "{out}"
    );
    assert!(out.contains("updated   nodes/src/lib.rs"), "{out}");
    assert!(out.contains("appended  firmware/budgets.toml"), "{out}");
    let bump = read(&d.join("nodes/src/bump_ctrl.rs"));
    assert!(bump.contains("io::bump_pub().send(value, now)"));
    assert!(bump.contains("bump: Every::new(200000000),"));
    assert!(read(&d.join("nodes/src/lib.rs")).contains("pub mod bump_ctrl;\n"));
    let b2 = read(&budgets);
    assert!(
        b2.contains("[sonar]\nflash = 20000"),
        "the user's budget is kept: {b2}"
    );
    assert!(
        b2.ends_with("[bumper]\nflash = 40960\nram = 10240\n"),
        "{b2}"
    );
    assert_eq!(b2.matches("[gateway]").count(), 1);
    // A third run with nothing changed changes nothing.
    let (code, out, _) = rtcan(&["new", ds]);
    assert_eq!(code, 0);
    assert!(
        !out.contains("created") && !out.contains("updated") && !out.contains("appended"),
        "{out}"
    );
}

#[test]
fn bad_robot_exits_2_rustc_style_and_writes_nothing() {
    let d = scratch("bad");
    let ds = d.to_str().unwrap();
    let bad = d.with_extension("toml");
    std::fs::write(
        &bad,
        "[bus]\nmaster = \"m\"\n\n[modules.m]\nboard = \"stm32f103c8\"\n\n[nodes.n]\nmodule = \"m\"\n\n\
         [topics.t]\ntype = \"Nope\"\npublisher = \"n\"\nclass = \"hrt\"\nrate = \"100Hz\"\n",
    )
    .unwrap();
    let (code, out, err) = rtcan(&["new", ds, "--robot", bad.to_str().unwrap()]);
    assert_eq!(code, 2, "{out}");
    assert!(err.contains("error[unknown-type]"), "{err}");
    assert!(
        err.contains(".toml:11:8"),
        "file:line:col of the bad type: {err}"
    );
    assert!(err.contains("nothing written"), "{err}");
    assert!(!d.exists(), "nothing written for a bad robot");
    // No robot.toml at all, and usage errors.
    let (code, _, err) = rtcan(&["new", ds]);
    assert_eq!(code, 2);
    assert!(err.contains("robot.toml"), "{err}");
    assert_eq!(rtcan(&["new"]).0, 2);
    assert_eq!(rtcan(&["new", ds, "--robot"]).0, 2);
    assert_eq!(rtcan(&["new", ds, "--bogus"]).0, 2);
    assert!(!d.exists());
}
