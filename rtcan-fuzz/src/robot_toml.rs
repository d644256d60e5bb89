//! `robot_toml`: bytes → `rtcan_model::analyze` (parse, validate, plan, timing check) →
//! reports → `rtcan_codegen::generate`. Never a panic or a hang (libFuzzer's `-timeout`
//! catches the latter); every diagnostic has a span, inside the input on character
//! boundaries; the status agrees with what was produced; and what `check` admits
//! generates code without `compile_error!` whose tables pass the engine's
//! `check_tables` with the generated sizes (the const assertion of the generated code).
use rtcan_model::{analyze, report, Diagnostic, Status};

/// One fuzz run. Panics (assert) on a finding.
pub fn run(data: &[u8]) {
    // Non-UTF-8 input is refused before parsing (`read_source`, `invalid-utf8`): the
    // lossy text still goes through the parser, as the CLI would show it.
    let text = String::from_utf8_lossy(data);
    let a = analyze("fuzz.toml", &text);
    assert_spans_inside(&text, &a.diagnostics.items);
    // Rendered rustc-style, every error of `analyze` points into the file (`file:line:col`);
    // only reading the file (`io`, `file-too-large`) has nothing to point at.
    for d in &a.diagnostics.items {
        assert!(
            d.span.is_some(),
            "{:?} without a span: {}",
            d.code,
            d.message
        );
    }
    let status = a.status();
    assert_eq!(
        status == Status::Admissible,
        a.plan.is_some(),
        "status {status:?} with plan {}",
        a.plan.is_some()
    );
    assert_eq!(
        status == Status::Admissible,
        a.diagnostics.is_empty(),
        "status {status:?} with {} diagnostics",
        a.diagnostics.items.len()
    );
    let rendered = a.diagnostics.render();
    if let Some(first) = a.diagnostics.items.first() {
        let head = format!("error[{}]", first.code.name());
        assert!(rendered.contains(&head), "`{head}` not rendered");
    }
    let _ = report::json_text(&a);
    let Some(plan) = &a.plan else {
        return;
    };
    let _ = report::text(plan);
    let _ = report::calendar(plan);
    let code = rtcan_codegen::generate(plan, &rtcan_codegen::Options::default()).to_string();
    assert!(
        !code.contains("compile_error"),
        "an admitted robot generates a compile error"
    );
    for (i, m) in plan.modules.iter().enumerate() {
        let tables = plan.tables(i).expect("every module of a plan has tables");
        let fit =
            rtcan_core::engine::check_tables(&tables.view(), tables.rx.len(), m.rx_arena_bytes);
        assert_eq!(
            fit,
            Ok(()),
            "module `{}`: generated tables rejected",
            m.name
        );
    }
}

/// Every span lies inside `text` (`start <= end <= len`) on character boundaries.
pub fn assert_spans_inside(text: &str, items: &[Diagnostic]) {
    for d in items {
        if let Some(span) = &d.span {
            assert!(
                span.start <= span.end
                    && span.end <= text.len()
                    && text.is_char_boundary(span.start)
                    && text.is_char_boundary(span.end),
                "span {span:?} of {:?} outside the input ({} bytes) or not on a character boundary",
                d.code,
                text.len()
            );
        }
    }
}
