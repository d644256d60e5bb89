//! `rtcan flash` against the simulated Triskar2 (issue 15, docs/SERVICES.md §4).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use std::process::Command;

fn rtcan(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rtcan"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn flash_motor1_with_the_default_test_image() {
    let (code, out, err) = rtcan(&["flash", "robot.toml", "--module", "motor1"]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 3, "{out}");
    assert!(
        lines[0].contains("1000000 bit/s; image: deterministic 28 KiB test image"),
        "{out}"
    );
    // Begin, 115 Data, End of 32 frames each; the bus time is simulated, deterministic.
    assert!(
        lines[1].starts_with("motor1     28672 bytes, 3744 frames, "),
        "{out}"
    );
    assert!(
        lines[1].ends_with(" s bus time, 0 retries: ok (committed to slot 1, seq 2)"),
        "{out}"
    );
    assert_eq!(
        lines[2],
        "robot traffic meanwhile (10.5 s): 0 HRT misses, 0 SRT misses"
    );
}

#[test]
fn flash_json_fields_and_a_refused_image() {
    let (code, out, err) = rtcan(&["flash", "--module", "psu", "--json", "--seconds", "8"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["module"], "psu");
    assert_eq!(v["bytes"], 28672);
    assert_eq!(v["frames"], 3744);
    assert_eq!(v["retries"], 0);
    assert_eq!(v["ok"], true);
    let ms = v["bus_time_ms"].as_f64().unwrap();
    assert!(ms > 1000.0 && ms <= 10_000.0, "{ms}");
    // An image without this robot's fingerprint at 0x1D0: refused at End (Begin, 9
    // Data, End: 352 frames), exit 1.
    let dir = std::env::temp_dir().join(format!("rtcan-flash-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let img = dir.join("zeros.bin");
    std::fs::write(&img, vec![0u8; 2048]).unwrap();
    let (code, out, _) = rtcan(&[
        "flash",
        "--module",
        "motor2",
        "--image",
        img.to_str().unwrap(),
        "--seconds",
        "3",
    ]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("motor2     2048 bytes, 352 frames, ")
            && out.contains("FAILED: refused by the module (Fingerprint)"),
        "{out}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn flash_usage_errors() {
    for (args, msg) in [
        (&["flash"][..], "required arguments were not provided"),
        (
            &["flash", "--module", "gateway"],
            "updated over its host link",
        ),
        (&["flash", "--module", "wheel9"], "no module `wheel9`"),
        (
            &["flash", "--all", "--module", "psu"],
            "cannot be used with",
        ),
        (&["flash", "--all", "--can", "can0"], "simulator only"),
        (
            &["flash", "--module", "psu", "--image", "/nonexistent"],
            "/nonexistent",
        ),
    ] {
        let (code, _, err) = rtcan(args);
        assert_eq!(code, 2, "{args:?}");
        assert!(err.contains(msg), "{args:?}: {err}");
    }
}
