//! `[params]` in robot.toml (issue 15): typed parameters, validated with spans.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use rtcan_model::params::{load, ParamTy};

fn robot() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    std::fs::read_to_string(path).unwrap()
}

#[test]
fn triskar2_params_are_read_in_declaration_order_per_module() {
    let (plan, params) = load("robot.toml", &robot()).unwrap();
    let names: Vec<_> = params
        .iter()
        .map(|p| (p.name.as_str(), p.module, p.index))
        .collect();
    assert_eq!(
        names,
        [
            ("motor1.kp", 1, 0),
            ("motor1.ki", 1, 1),
            ("proximity.stop_distance", 4, 0),
            ("proximity.log_every", 4, 1)
        ]
    );
    assert_eq!(plan.modules[1].name, "motor1");
    let kp = &params[0];
    assert_eq!(
        (kp.ty, kp.default, kp.min, kp.max, kp.persist),
        (ParamTy::F32, 0.04, 0.0, 1.0, true)
    );
    assert_eq!(kp.unit, "duty/(rad/s)");
    assert!(!params[3].persist);
}

fn errors(extra: &str) -> String {
    let src = format!("{}\n{extra}", robot());
    match load("robot.toml", &src) {
        Ok(_) => panic!("accepted: {extra}"),
        Err(d) => d.render(),
    }
}

#[test]
fn bad_params_are_rustc_style_errors_with_a_hint() {
    let e = errors("[params.nobody]\nx = { type = \"f32\", default = 1.0 }");
    assert!(
        e.contains("error[unknown-node]: `params.nobody`: no node or module"),
        "{e}"
    );
    assert!(e.contains("robot.toml:"), "{e}");
    let e = errors("[params.psu]\nx = { type = \"f64\", default = 1.0 }");
    assert!(
        e.contains("unknown parameter type `f64`") && e.contains("`f32`, `i32`"),
        "{e}"
    );
    let e = errors("[params.psu]\nx = { type = \"f32\", default = 5.0, min = 0.0, max = 1.0 }");
    assert!(
        e.contains("`params.psu.x`: default 5 outside [0, 1]"),
        "{e}"
    );
    let e = errors("[params.psu]\nx = { type = \"u32\", default = -1 }");
    assert!(e.contains("`default` is not a u32 value"), "{e}");
    let e = errors("[params.psu]\nx = { type = \"i32\", default = 1.5 }");
    assert!(e.contains("`default` is not a i32 value"), "{e}");
    let e = errors("[params.psu]\nx = { type = \"bool\" }");
    assert!(e.contains("has no `default`"), "{e}");
    let e = errors("[params.psu]\nx = { type = \"bool\", default = true, pesist = true }");
    assert!(e.contains("unknown key `pesist`"), "{e}");
    let e = errors("[params.psu]\nx = 3");
    assert!(e.contains("must be a table, found"), "{e}");
    // And `rtcan check` (analyze) reports the same: check admits => the params are good.
    let src = format!(
        "{}\n[params.psu]\nx = {{ type = \"f32\", default = 9.0, max = 1.0 }}",
        robot()
    );
    let a = rtcan_model::analyze("robot.toml", &src);
    assert!(a.plan.is_none());
    assert!(
        a.diagnostics.render().contains("outside"),
        "{}",
        a.diagnostics.render()
    );
}
