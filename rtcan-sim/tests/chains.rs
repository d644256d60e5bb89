//! Triskar2's end-to-end chains measured in the simulator beside their build-time bound.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]
use rtcan_core::engine::Policy;
use rtcan_sim::policy::PolicyKind;
use rtcan_sim::run::{run_engine, SimConfig};

#[test]
fn measured_chain_latency_is_within_the_bound() {
    let plan = rtcan_model::Robot::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml"))
        .map_err(|d| d.render())
        .unwrap();
    assert_eq!(plan.chains.len(), 2);
    let sc = rtcan_sim::robot::scenario(&plan, &[]).unwrap();
    let cfg = SimConfig {
        seconds: 2.0,
        record_wire: true,
        ..SimConfig::default()
    };
    let run = run_engine(&sc, &cfg, PolicyKind::Ours, Policy::OURS).unwrap();
    let m = rtcan_sim::chains::measure(&plan, &run.wire);
    // Every complete message on the wire is found (2 s: 100 odometry at 50 Hz, 200 wheel set points at 100 Hz).
    let count = |n: &str| {
        let t = plan.topics.iter().position(|t| t.name == n).unwrap();
        rtcan_sim::chains::message_count(&plan, t, &run.wire)
    };
    assert!(
        (95..=100).contains(&count("odometry")),
        "{}",
        count("odometry")
    );
    assert!(
        (190..=200).contains(&count("wheel_setpoints")),
        "{}",
        count("wheel_setpoints")
    );
    for (c, decl) in m.iter().zip(&plan.chains) {
        eprintln!(
            "chain {}: measured worst {:?} ns over {} samples, bound {:?} ns, budget {} ns",
            c.name, c.worst_ns, c.samples, c.bound_ns, c.budget_ns
        );
        let worst = c.worst_ns.unwrap();
        assert!(c.samples > 20, "{c:?}");
        assert!(worst <= c.bound_ns.unwrap(), "{c:?}");
        // Never less than the last hop's own transmission (sanity: the trace is real).
        let last = plan.topics.get(*decl.path.last().unwrap()).unwrap();
        assert!(worst >= u64::from(last.fragments) * 100_000, "{c:?}");
    }
    // odometry_feedback in the simulator, where an HRT sample is taken at its slot: one
    // encoder1 slot, the wait for the next odometry slot (< 120 slots) and its 3 slots. The
    // build-time bound also allows a full encoder1 period and the odometry node's loop.
    let of = &m[0];
    assert_eq!(of.name, "odometry_feedback");
    assert!(
        of.worst_ns.unwrap() <= (1 + 120 + 3) * plan.bus.slot_ns,
        "{of:?}"
    );
}
