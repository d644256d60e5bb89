//! End-to-end chains (`[chains.NAME]`): bounds from the calendar and `chain-over-budget`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
use rtcan_model::analyze;

const TRISKAR: &str = include_str!("../../robot.toml");

fn with_chain(body: &str) -> String {
    // The shipped chains are replaced so each test sees only its own.
    let cut = TRISKAR.find("[chains.").unwrap();
    let end = TRISKAR.find("# ---- parameters").unwrap();
    format!("{}{}\n{}", &TRISKAR[..cut], body, &TRISKAR[end..])
}

#[test]
fn triskar2_chains_have_their_calendar_bounds() {
    let a = analyze("robot.toml", TRISKAR);
    assert!(a.diagnostics.is_empty(), "{}", a.diagnostics.render());
    let p = a.plan.unwrap();
    let slot = p.bus.slot_ns;
    assert_eq!(slot, 166_666);
    let c: Vec<_> = p
        .chains
        .iter()
        .map(|c| (c.name.as_str(), c.bound_ns, c.budget_ns))
        .collect();
    assert_eq!(
        c,
        [
            // encoder1: 30-slot period + 1 slot; odometry node loop 120 slots; odometry
            // 120-slot period + 3 slots.
            (
                "odometry_feedback",
                Some((30 + 1 + 120 + 120 + 3) * slot),
                50_000_000
            ),
            // velocity: SRT deadline 10 ms; kinematics loop 60 slots; wheel_setpoints
            // 60-slot period + 2 slots.
            (
                "command_to_wheels",
                Some(10_000_000 + (60 + 60 + 2) * slot),
                40_000_000
            ),
        ]
    );
}

#[test]
fn a_chain_over_budget_is_an_error_with_a_hint() {
    let src = with_chain(
        "[chains.tight]\npath = [\"velocity\", \"wheel_setpoints\"]\nbudget = \"30ms\"\n",
    );
    let a = analyze("robot.toml", &src);
    assert!(a.plan.is_none());
    assert_eq!(a.diagnostics.items.len(), 1, "{}", a.diagnostics.render());
    let d = &a.diagnostics.items[0];
    assert_eq!(d.code.name(), "chain-over-budget");
    assert!(
        d.message
            .starts_with("chain `tight`: worst-case latency 30.33"),
        "{}",
        d.message
    );
    let span = d.span.clone().unwrap();
    assert_eq!(&src[span], "\"30ms\"");
    assert_eq!(d.help[0], "the largest term is `wheel_setpoints`: shorten its period or deadline, or raise the budget");
    assert_eq!(a.status().exit_code(), 1);
}

#[test]
fn bad_chains_are_reported() {
    let cases: [(&str, &str, &str); 6] = [
        ("[chains.x]\npath = [\"battery\"]\nbudget = \"1s\"\n", "chain-over-budget", "chain `x` has no latency bound"),
        ("[chains.x]\npath = [\"encoder1\", \"velocity\"]\nbudget = \"1s\"\n", "bad-value", "chain `x`: `velocity` is published by `obstacle_avoid`, which does not subscribe `encoder1`"),
        ("[chains.x]\npath = [\"nope\"]\nbudget = \"1s\"\n", "bad-value", "chain `x`: not a topic name"),
        ("[chains.x]\npath = [\"encoder1\"]\n", "missing-key", "chain `x` needs `path` and `budget`"),
        ("[chains.x]\npath = [\"encoder1\"]\nbudget = \"soon\"\n", "bad-value", "chain `x`: bad budget `soon`"),
        ("[chains.x]\npath = [\"encoder1\"]\nbudget = \"1s\"\nmax = 3\n", "unknown-key", "unknown key `max` in `chains.x`"),
    ];
    for (body, code, msg) in cases {
        let a = analyze("robot.toml", &with_chain(body));
        assert!(a.plan.is_none(), "{body}");
        let d = &a.diagnostics.items[0];
        assert_eq!((d.code.name(), d.message.as_str()), (code, msg), "{body}");
        assert!(!d.help.is_empty());
    }
}
