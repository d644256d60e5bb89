//! Compile-fail suite: broken robot files give rustc-style diagnostics with the
//! robot.toml excerpt, and the generated API rejects undeclared topics, wrong message
//! types and other modules' topics. Regenerate with `TRYBUILD=overwrite`, then read
//! every `.stderr`.
#[test]
fn ui() {
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/ui/*.rs");
}
