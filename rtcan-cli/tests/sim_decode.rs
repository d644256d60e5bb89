#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
//! `rtcan sim` and `rtcan decode` on the command line (issue 9): usage, rejected
//! options, the fingerprint check, stdin, skipped frames, streaming.
use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Command, Stdio};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn rtcan_in(args: &[&str], stdin: Option<&str>) -> (i32, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(args)
        .current_dir(root())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    // Written from a thread: a child that answers while it reads (decode streams line
    // by line) would otherwise fill its stdout pipe while this one still writes stdin,
    // and both wait forever.
    let text = stdin.unwrap_or("").to_string();
    let writer = std::thread::spawn(move || {
        // A child that exits early closes its stdin: not this test's concern.
        let _ = input.write_all(text.as_bytes());
    });
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

fn rtcan(args: &[&str]) -> (i32, String, String) {
    rtcan_in(args, None)
}

/// A fresh path per call (tests run in parallel).
fn tmp(name: &str) -> PathBuf {
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let d = std::env::temp_dir().join(format!("rtcan-cli-{}-{k}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// A 2 s candump log of the Triskar2 robot (workspace robot.toml).
fn triskar_log() -> String {
    let dir = tmp("triskar");
    let (code, _, err) = rtcan(&["sim", "--seconds", "2", "--out", dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    std::fs::read_to_string(dir.join("can0.log")).unwrap()
}

#[test]
fn help_prints_usage_and_exits_0() {
    for cmd in ["sim", "decode"] {
        let (code, out, err) = rtcan(&[cmd, "--help"]);
        assert_eq!(code, 0, "{cmd}: {err}");
        assert!(
            out.starts_with(&format!("usage: rtcan {cmd}")),
            "{cmd}: {out}"
        );
        assert!(err.is_empty(), "{cmd}: {err}");
    }
    let (_, out, _) = rtcan(&["sim", "-h"]);
    assert!(out.contains("built-in scenarios:") && out.contains("rtcan-paper"));
}

#[test]
fn sim_rejects_what_it_cannot_honour() {
    let (code, _, err) = rtcan(&["sim", "--scenario", "rtcan_paper"]);
    assert_eq!(code, 2);
    assert!(err.contains("unknown scenario `rtcan_paper`"), "{err}");
    assert!(
        err.contains("rtcan-paper") && err.contains("triskar2"),
        "{err}"
    );
    for v in ["-1", "NaN"] {
        let (code, _, err) = rtcan(&["sim", "--master-dies-at", v]);
        assert_eq!(code, 2, "{v}");
        assert!(err.contains("--master-dies-at must be"), "{v}: {err}");
    }
    let (code, _, err) = rtcan(&["sim", "--scenario", "rtcan-paper", "--master-dies-at", "1"]);
    assert_eq!(code, 2);
    assert!(err.contains("triskar2 scenario only"), "{err}");
    let (code, _, err) = rtcan(&["sim", "robot.toml", "robots/hrt200.toml"]);
    assert_eq!(code, 2);
    assert!(err.contains("two robot paths"), "{err}");
}

#[test]
fn sim_traffic_on_an_hrt_topic_is_an_error() {
    let dir = tmp("hrt-traffic");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("s.toml");
    std::fs::write(
        &file,
        format!(
            "robot = \"{}\"\n[traffic]\nh_a1 = {{ period = \"2ms\" }}\n",
            root().join("robots/rtcan-paper.toml").display()
        ),
    )
    .unwrap();
    let (code, out, err) = rtcan(&["sim", "--scenario", file.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(err.contains("matches HRT topic `h_a1`"), "{err}");
}

#[test]
fn sim_runs_every_robot_check_admits_hrt200() {
    let (code, out, err) = rtcan(&["check", "robots/hrt200.toml"]);
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, err) = rtcan(&["sim", "robots/hrt200.toml", "--seconds", "0.2"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("delivered ok/bad"), "{out}");
    assert!(!err.contains("simulator holds"), "{err}");
}

#[test]
fn sim_out_errors_come_before_the_run() {
    let blocker = tmp("blocker");
    std::fs::write(&blocker, "a file, not a directory").unwrap();
    let out_dir = blocker.join("sub");
    let t0 = std::time::Instant::now();
    let (code, out, err) = rtcan(&[
        "sim",
        "--scenario",
        "rtcan-paper",
        "--seconds",
        "1000",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(out.is_empty(), "{out}");
    assert!(err.contains("--out"), "{err}");
    // 1000 simulated seconds would take many seconds: the error comes first.
    assert!(t0.elapsed().as_secs_f64() < 5.0);
}

/// Issue 9's exact case: the Triskar2 log decoded with robots/rtcan-paper.toml printed
/// 845 plausible wrong messages. The heartbeats carry robot.toml's fingerprint.
#[test]
fn decode_with_another_robots_description_refuses_and_says_so() {
    let log = triskar_log();
    let (code, out, err) = rtcan_in(
        &["decode", "-", "--robot", "robots/rtcan-paper.toml"],
        Some(&log),
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("heartbeat carries another robot's fingerprint"),
        "{err}"
    );
    let summary = out.lines().rev().take(2).collect::<Vec<_>>().join("\n");
    // One message decoded: a frame of the supervised Triskar2 (`health_<m>` and the
    // module tables take IDs the paper's topics have) sent 2 ms into the log, before its
    // sender's first heartbeat showed the other fingerprint.
    assert!(summary.contains(": 1 messages,"), "{summary}");
    assert!(
        summary.contains("messages of their senders refused"),
        "{summary}"
    );
    let refused = out
        .lines()
        .filter(|l| l.contains("not decoded: sender module"))
        .count();
    assert!(refused > 800, "{refused}");
    assert!(out.contains("MISMATCH (robot: 0x"), "heartbeats marked");
    // With --force they are decoded, each marked.
    let (code, out, _) = rtcan_in(
        &[
            "decode",
            "-",
            "--robot",
            "robots/rtcan-paper.toml",
            "--force",
        ],
        Some(&log),
    );
    assert_eq!(code, 0);
    let forced = out
        .lines()
        .filter(|l| l.contains("[FOREIGN SENDER fingerprint=0x"))
        .count();
    assert_eq!(forced, refused);
    // The right robot: every message decoded, nothing refused or flagged.
    let (code, out, err) = rtcan_in(&["decode", "-", "--robot", "robot.toml"], Some(&log));
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("MISMATCH") && !out.contains("not decoded"));
    assert!(err.is_empty(), "{err}");
    assert!(out.contains(" 0 frames not attributed"), "{out}");
}

#[test]
fn decode_skips_remote_error_and_fd_frames_and_counts_bad_lines() {
    let log = "(0.000100) can0 00000123#R\n\
               (0.000200) can0 20000080#0000080000000000\n\
               (0.000300) can0 00000123##1AABB\n\
               (0.000400) can0 zz#00\n";
    let (code, out, err) = rtcan_in(
        &["decode", "-", "--robot", "robots/rtcan-paper.toml"],
        Some(log),
    );
    assert_eq!(code, 1, "a malformed line is reported in the exit code");
    assert!(
        out.contains("3 remote/error/FD frames skipped, 1 malformed lines"),
        "{out}"
    );
    assert!(err.contains("<stdin>:4: bad identifier"), "{err}");
}

/// A record is printed as soon as its frames are read, before the log ends.
#[test]
fn decode_streams_line_by_line() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(["decode", "-", "--robot", "robot.toml"])
        .current_dir(root())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    let mut output = BufReader::new(child.stdout.take().unwrap());
    // A sync frame of robot.toml's bus: decoded alone.
    let log = triskar_log();
    let first = log.lines().next().unwrap();
    writeln!(input, "{first}").unwrap();
    input.flush().unwrap();
    let mut line = String::new();
    output.read_line(&mut line).unwrap();
    assert!(
        line.contains("SYNC") || line.contains("heartbeat"),
        "{line}"
    );
    drop(input);
    assert!(child.wait().unwrap().success());
}

/// `--out` streams can0.log during the run (the wire is not kept in memory): the file
/// is the same log the library records for the same run.
#[test]
fn sim_out_streams_the_same_log_the_run_records() {
    use rtcan_core::engine::Policy;
    use rtcan_sim::policy::PolicyKind;
    use rtcan_sim::run::{run_engine, SimConfig};
    let dir = tmp("out-log");
    let (code, _, err) = rtcan(&[
        "sim",
        "--scenario",
        "rtcan-paper",
        "--seconds",
        "0.3",
        // The library run below has no CPU model (SimConfig's default).
        "--cpu",
        "off",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let written = std::fs::read_to_string(dir.join("can0.log")).unwrap();
    let sc = rtcan_sim::paper::scenario(rtcan_sim::paper::our_laxity(), 1.0).unwrap();
    let cfg = SimConfig {
        seconds: 0.3,
        ..SimConfig::default()
    };
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS).unwrap();
    assert!(written.lines().count() > 1000);
    assert_eq!(written, rtcan_sim::candump::log(&run.wire, "can0"));
    assert!(dir.join("report.json").exists());
    // Every plot has its numbers beside it; the calendar's CSV is the plan's (robot.toml's
    // module names, the master's mask).
    for f in ["calendar", "hrt-jitter-ours", "srt-latency-ours"] {
        let svg = std::fs::read_to_string(dir.join(format!("{f}.svg"))).unwrap();
        assert!(svg.starts_with("<svg"), "{f}.svg");
        let csv = std::fs::read_to_string(dir.join(format!("{f}.csv"))).unwrap();
        assert!(csv.lines().count() > 1, "{f}.csv: {csv}");
    }
    let calendar = std::fs::read_to_string(dir.join("calendar.csv")).unwrap();
    let rows = rtcan_sim::plot::calendar_rows(&sc);
    let bus = sc.bus().unwrap();
    let mask = sc.masks().first().copied().unwrap();
    let want = rtcan_sim::plot::calendar(bus.slots_per_cycle, mask, &rows).unwrap();
    assert_eq!(calendar, want.csv);
    assert!(calendar.starts_with("row,slot,topic\n"), "{calendar}");
    assert_eq!(
        calendar.lines().filter(|l| l.starts_with("mask,")).count(),
        usize::from(bus.slots_per_cycle)
    );
}

/// A line without end (`/dev/zero`-like input) is read in bounded pieces, each counted
/// malformed; decoding goes on after it.
#[test]
fn decode_reads_overlong_lines_in_bounded_pieces() {
    let mut input = "X".repeat(40_960);
    input.push('\n');
    input.push_str(triskar_log().lines().next().unwrap());
    input.push('\n');
    let (code, out, err) = rtcan_in(&["decode", "-", "--robot", "robot.toml"], Some(&input));
    assert_eq!(code, 1);
    assert!(err.contains("<stdin>:1: line too long"), "{err}");
    assert!(out.contains(" 1 frames: "), "{out}");
    // 40 960 bytes = 10 pieces of 4 096; the newline after them ends an empty line.
    assert!(out.contains(", 10 malformed lines"), "{out}");
}

#[test]
fn sim_measures_the_chains_beside_their_build_time_bound() {
    let plan = rtcan_model::Robot::load(root().join("robot.toml")).unwrap();
    let (code, out, err) = rtcan(&["sim", "--seconds", "1", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let chains = v["chains"].as_array().unwrap();
    assert_eq!(chains.len(), plan.chains.len());
    for (c, decl) in chains.iter().zip(&plan.chains) {
        assert_eq!(c["name"], decl.name.as_str());
        assert_eq!(c["bound_ns"].as_u64(), decl.bound_ns);
        assert_eq!(c["budget_ns"].as_u64(), Some(decl.budget_ns));
        // Measured on the node code's traffic, from the wire the run kept for them only.
        let worst = c["worst_ns"].as_u64().unwrap();
        assert!(c["samples"].as_u64().unwrap() > 20, "{c}");
        assert!(worst <= decl.bound_ns.unwrap(), "{c}");
        assert!(worst >= 1_000_000, "{c}");
    }
    let (code, out, _) = rtcan(&["sim", "--seconds", "1"]);
    assert_eq!(code, 0);
    assert!(out.contains(
        "end-to-end chains (bound from robot.toml at build time; worst measured on the wire):\n  odometry_feedback    bound 45.666 ms, budget 50 ms, measured worst "
    ), "{out}");
}
