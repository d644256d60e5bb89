//! `rtcan check` refuses every name and setting the build would refuse (issue 9): Rust
//! keywords of every kind, names colliding after case conversion or with generated
//! items, bit rates a board's CAN clock cannot reach, pools larger than a topic holds.
//! `tests/admitted_build.rs` in the root crate compiles what check admits.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use rtcan_model::{analyze, Code, Status};

/// A valid robot with placeholders for each kind of name.
fn robot(ty: &str, field: &str, module: &str, node: &str, topic: &str) -> String {
    format!(
        r#"[bus]
cycle = "10ms"
slots = 20
master = "{module}"

[types.{ty}]
{field} = "u8"

[modules.{module}]
board = "stm32f103c8"

[modules.other]
board = "stm32f103c8"

[nodes.{node}]
module = "{module}"

[nodes.sink]
module = "other"

[topics.{topic}]
type = "{ty}"
publisher = "{node}"
class = "hrt"
period_slots = 10
subscribers = ["sink"]
"#
    )
}

fn errors(src: &str) -> Vec<(Code, String)> {
    analyze("robot.toml", src)
        .diagnostics
        .items
        .into_iter()
        .map(|d| (d.code, d.message))
        .collect()
}

#[test]
fn the_base_robot_is_admissible() {
    let a = analyze("robot.toml", &robot("T", "v", "m", "n", "t"));
    assert_eq!(a.status(), Status::Admissible, "{}", a.diagnostics.render());
}

#[test]
fn keywords_of_every_kind_are_refused_for_every_name() {
    for kw in [
        "abstract",
        "become",
        "do",
        "final",
        "macro",
        "override",
        "priv",
        "typeof",
        "unsized",
        "virtual",
        "async",
        "await",
        "dyn",
        "try",
        "union",
        "box",
        "yield",
        "gen",
        "self",
        "super",
        "crate",
        "macro_rules",
        "raw",
        "safe",
        "fn",
        "match",
    ] {
        for (what, src) in [
            ("field", robot("T", kw, "m", "n", "t")),
            ("module", robot("T", "v", kw, "n", "t")),
            ("node", robot("T", "v", "m", kw, "t")),
            ("topic", robot("T", "v", "m", "n", kw)),
        ] {
            let e = errors(&src);
            assert!(
                e.contains(&(
                    Code::BadName,
                    format!("{what} name `{kw}` is a Rust keyword")
                )),
                "{what} {kw}: {e:?}"
            );
        }
    }
}

#[test]
fn a_type_named_self_is_refused() {
    let e = errors(&robot("Self", "v", "m", "n", "t"));
    assert_eq!(
        e[0],
        (Code::BadName, "type name `Self` is a Rust keyword".into())
    );
    let a = analyze("robot.toml", &robot("Self", "v", "m", "n", "t"));
    assert!(a
        .diagnostics
        .render()
        .contains("it cannot be an identifier at all, not even `r#Self`"));
}

#[test]
fn topics_colliding_after_camel_case_are_refused() {
    let src = robot("T", "v", "m", "n", "enc1")
        + "\n[topics.enc_1]\ntype = \"T\"\npublisher = \"n\"\nclass = \"nrt\"\nsubscribers = [\"sink\"]\n";
    assert_eq!(
        errors(&src),
        [(
            Code::NameCollision,
            "topics `enc1` and `enc_1` both become the Rust type `Enc1Topic`".into()
        )]
    );
    let src = robot("T", "v", "m", "n", "a_b")
        + "\n[topics.a__b_]\ntype = \"T\"\npublisher = \"n\"\nclass = \"nrt\"\n";
    assert_eq!(errors(&src)[0].0, Code::NameCollision);
}

#[test]
fn modules_named_like_generated_items_or_primitives_are_refused() {
    for (name, what) in [
        ("topics", "the generated module holding the topic constants"),
        (
            "nodes",
            "the generated module placing every node on its module",
        ),
        (
            "rtcan",
            "the `rtcan` crate (`rtcan::robot!` next to it would be ambiguous)",
        ),
        ("u8", "a primitive type the generated message structs use"),
        ("f32", "a primitive type the generated message structs use"),
        ("bool", "a primitive type the generated message structs use"),
    ] {
        let e = errors(&robot("T", "v", name, "n", "t"));
        assert_eq!(
            e,
            [(
                Code::NameCollision,
                format!("module name `{name}` collides with {what}")
            )],
            "{name}"
        );
    }
}

#[test]
fn bit_rate_unreachable_from_the_board_clock_is_refused() {
    let src = robot("T", "v", "m", "n", "t").replace("[bus]\n", "[bus]\nbitrate = \"700kbit/s\"\n");
    let a = analyze("robot.toml", &src);
    assert_eq!(a.status(), Status::Invalid);
    let d = &a.diagnostics.items[0];
    assert_eq!(d.code, Code::BitrateUnreachable);
    assert_eq!(
        d.message,
        "bit rate 700000 bit/s is not reachable on board stm32f103c8 (CAN clock 36 MHz): no prescaler 1..=1024 divides 36 MHz into 8..=25 time quanta per bit"
    );
    assert_eq!(d.notes, ["modules on this board: `m`, `other`"]);
    assert!(d.help[0]
        .starts_with("bit rates this board reaches exactly: 1000 kbit/s, 800 kbit/s, 500 kbit/s"));
    let rendered = a.diagnostics.render();
    assert!(rendered.contains("--> robot.toml:2:11\n"), "{rendered}");
    // The same rate on QEMU's software CAN (no prescaler) is fine, and every rate the
    // firmware's `can_btr!` accepts is accepted.
    // (A guard of 6 us: at 700 kbit/s a slave's clock error bound, two bit times, is
    // 2.858 us, so the timing check wants more than the default 5 us.)
    let qemu = src
        .replace("stm32f103c8", "qemu")
        .replace("[bus]\n", "[bus]\nguard = \"6us\"\n");
    let q = analyze("robot.toml", &qemu);
    assert_eq!(q.status(), Status::Admissible, "{}", q.diagnostics.render());
    for rate in [
        "1Mbit/s",
        "800kbit/s",
        "500kbit/s",
        "250kbit/s",
        "125kbit/s",
    ] {
        let ok = robot("T", "v", "m", "n", "t")
            .replace(
                "[bus]\n",
                &format!("[bus]\nbitrate = \"{rate}\"\ncycle = \"100ms\"\n"),
            )
            .replace("cycle = \"10ms\"\n", "");
        let a = analyze("robot.toml", &ok);
        assert!(
            !a.diagnostics
                .items
                .iter()
                .any(|d| d.code == Code::BitrateUnreachable),
            "{rate}: {}",
            a.diagnostics.render()
        );
    }
}

#[test]
fn pools_larger_than_a_topic_holds_are_refused_by_check() {
    let src = robot("T", "v", "m", "n", "t").replace(
        "subscribers = [\"sink\"]",
        "subscribers = [{ node = \"sink\", queue = 40 }]",
    );
    let e = errors(&src);
    assert_eq!(
        e,
        [(
            Code::PoolTooLarge,
            "topic `t` needs 42 message blocks on module `other`; a topic has at most 32".into()
        )]
    );
    let ok = robot("T", "v", "m", "n", "t").replace(
        "subscribers = [\"sink\"]",
        "subscribers = [{ node = \"sink\", queue = 15 }]",
    );
    assert!(errors(&ok).is_empty());
}
