//! Which robot.toml names can become the Rust identifiers of the generated code, and the
//! identifiers derived from them. rtcan-codegen derives its names with these functions
//! and `rtcan check` refuses every name whose identifier would not compile, so that
//! "check admits" implies "the build succeeds" (tested by compiling hostile names in
//! the root crate's `tests/admitted_build.rs`).

/// Every Rust keyword (edition 2015 to 2024): strict, reserved and weak. A generated
/// item with one of these names fails to compile (`pub mod virtual`) or needs a raw
/// identifier (`r#virtual`) at every use; `self`, `super`, `crate` and `Self` cannot
/// even be raw identifiers. Weak keywords (`union`, `macro_rules`, `safe`, `raw`) are
/// legal identifiers today but refused too: one rule, no surprises at a later edition.
pub const KEYWORDS: &[&str] = &[
    // strict, 2015
    "as",
    "break",
    "const",
    "continue",
    "crate",
    "else",
    "enum",
    "extern",
    "false",
    "fn",
    "for",
    "if",
    "impl",
    "in",
    "let",
    "loop",
    "match",
    "mod",
    "move",
    "mut",
    "pub",
    "ref",
    "return",
    "self",
    "Self",
    "static",
    "struct",
    "super",
    "trait",
    "true",
    "type",
    "unsafe",
    "use",
    "where",
    "while",
    // strict, 2018
    "async",
    "await",
    "dyn",
    // reserved
    "abstract",
    "become",
    "box",
    "do",
    "final",
    "macro",
    "override",
    "priv",
    "typeof",
    "unsized",
    "virtual",
    "yield",
    // reserved, 2018 / 2024
    "try",
    "gen",
    // weak
    "macro_rules",
    "union",
    "safe",
    "raw",
];

/// Keywords that cannot be raw identifiers either.
pub const NOT_RAW: &[&str] = &["self", "Self", "super", "crate", "_"];

/// Names the generated code gives its own items next to the module modules (`topics`,
/// `link`, `nodes`),
/// the crate the `rtcan::robot!` call next to them names (a module `rtcan` makes that
/// path ambiguous: found by `tests/admitted_build.rs`), and the primitive types the
/// message structs are written with: a module `u8` would shadow the type `u8` for every
/// field in the generated code.
pub const RESERVED_MODULE_NAMES: &[&str] = &[
    "topics",
    "link",
    "nodes",
    "supervision",
    "rtcan",
    "bool",
    "char",
    "str",
    "u8",
    "u16",
    "u32",
    "u64",
    "u128",
    "usize",
    "i8",
    "i16",
    "i32",
    "i64",
    "i128",
    "isize",
    "f16",
    "f32",
    "f64",
    "f128",
];

/// True for a Rust keyword of any kind.
pub fn is_keyword(name: &str) -> bool {
    KEYWORDS.contains(&name)
}

/// `wheel_setpoints` → `WheelSetpoints`: the generated `<Topic>Topic` type alias. Not
/// injective (`enc1` and `enc_1` → `Enc1`): the model refuses names that collide.
pub fn camel(name: &str) -> String {
    name.split('_')
        .filter(|p| !p.is_empty())
        .map(|p| {
            let mut c = p.chars();
            c.next()
                .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
                .unwrap_or_default()
        })
        .collect()
}

/// The topic's type alias in the generated code: `camel(name)` + `Topic`.
pub fn topic_alias(name: &str) -> String {
    camel(name) + "Topic"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camel_case_collides_on_underscores() {
        assert_eq!(camel("wheel_setpoints"), "WheelSetpoints");
        assert_eq!(camel("enc1"), camel("enc_1"));
        assert_eq!(camel("a__b_"), camel("a_b"));
        assert_eq!(topic_alias("enc_1"), "Enc1Topic");
    }

    #[test]
    fn keywords_include_reserved_and_weak() {
        for k in [
            "abstract", "become", "do", "final", "macro", "override", "priv", "typeof", "unsized",
            "virtual", "async", "await", "dyn", "try", "union", "Self", "gen",
        ] {
            assert!(is_keyword(k), "{k}");
        }
        assert!(!is_keyword("speed"));
    }
}
