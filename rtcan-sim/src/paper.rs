//! The RTCAN paper's §4 benchmark: `robots/rtcan-paper.toml` (1 Mbit/s, 10 ms cycle of
//! 60 slots, three nodes each with HRT H_A 1 ms, H_B 5 ms, H_C 10 ms and 5 × S_A, S_B,
//! S_C SRT topics, plus a capture module) planned by rtcan-model, with the Table 2 event
//! periods of `rtcan-sim/scenarios/rtcan-paper.toml`. Every table comes from the model
//! (the one way tables are made); the only knob is the laxity encoding under comparison,
//! set in the robot's `[bus]` before planning so the plan (and fingerprint) carries it.
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::Nanos;
use rtcan_model::Plan;

use crate::robot::{expand, parse_user, scale_load, scenario as plan_scenario, Traffic};
use crate::run::Scenario;

/// The benchmark robot, as shipped.
pub const ROBOT_TOML: &str = include_str!("../../robots/rtcan-paper.toml");
/// Its file name in diagnostics and reports.
pub const ROBOT_FILE: &str = "robots/rtcan-paper.toml";
/// Table 2 traffic (user-scenario format, docs/SIM.md).
pub const TRAFFIC_TOML: &str = include_str!("../scenarios/rtcan-paper.toml");

const MS: Nanos = 1_000_000;

/// Our encoding: logarithmic, unit chosen so that the longest deadline (50 ms) still
/// has distinct codes; `robots/rtcan-paper.toml` declares exactly this one (tested).
pub fn our_laxity() -> LaxityEncoding {
    let mut unit = 1_000u32;
    while (LaxityEncoding::Log { unit_ns: unit }).max_laxity_ns() < 50 * MS && unit < 1_000_000 {
        unit += 1_000;
    }
    LaxityEncoding::Log { unit_ns: unit }
}

/// The paper's encoding as published by the 2014 code: linear, 1 ms per code.
pub const PAPER_LAXITY: LaxityEncoding = LaxityEncoding::Linear { unit_ns: 1_000_000 };

/// The robot text with its `[bus]` laxity set to `laxity`.
fn robot_text(laxity: LaxityEncoding) -> Result<String, String> {
    let mut doc: toml_edit::DocumentMut = ROBOT_TOML
        .parse()
        .map_err(|e: toml_edit::TomlError| format!("{ROBOT_FILE}: {e}"))?;
    let bus = doc
        .get_mut("bus")
        .and_then(toml_edit::Item::as_table_like_mut)
        .ok_or_else(|| format!("{ROBOT_FILE}: no [bus] table"))?;
    let (kind, unit) = match laxity {
        LaxityEncoding::Linear { unit_ns } => ("linear", unit_ns),
        LaxityEncoding::Log { unit_ns } => ("log", unit_ns),
    };
    bus.insert("laxity", toml_edit::value(kind));
    bus.insert("laxity_unit", toml_edit::value(format!("{unit}ns")));
    Ok(doc.to_string())
}

/// The plan of the benchmark robot with `laxity`.
pub fn plan(laxity: LaxityEncoding) -> Result<Plan, String> {
    let text = robot_text(laxity)?;
    rtcan_model::Robot::parse(ROBOT_FILE, &text).map_err(|d| d.render())
}

/// Table 2 traffic on `plan`.
pub fn traffic(plan: &Plan) -> Result<Vec<Traffic>, String> {
    let user = parse_user(TRAFFIC_TOML, std::path::Path::new("."))?;
    expand(&user, plan)
}

/// Report label of a benchmark topic: its name up to the node digit, upper case
/// (`h_a1` → `H_A`, `s_b2_3` → `S_B`), so figures group by the paper's classes.
pub fn class_label(name: &str) -> String {
    name.chars()
        .take_while(|c| !c.is_ascii_digit())
        .collect::<String>()
        .to_ascii_uppercase()
}

/// The whole scenario at SRT load `load` with the given laxity encoding.
pub fn scenario(laxity: LaxityEncoding, load: f64) -> Result<Scenario, String> {
    let p = plan(laxity)?;
    let t = traffic(&p)?;
    let mut sc = plan_scenario(&p, &t)?;
    scale_load(&mut sc, load);
    for i in &mut sc.topics {
        i.label = class_label(&i.label);
    }
    Ok(sc)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::traffic::GenKind;
    use rtcan_core::fragment::wire_len;

    #[test]
    fn the_robot_file_declares_our_laxity() {
        let shipped = rtcan_model::Robot::parse(ROBOT_FILE, ROBOT_TOML).unwrap();
        assert_eq!(shipped.bus.laxity, our_laxity());
        assert_eq!(our_laxity(), LaxityEncoding::Log { unit_ns: 61_000 });
        assert!(our_laxity().max_laxity_ns() >= 50 * MS);
        // Setting the encoding it already has changes nothing (same fingerprint).
        assert_eq!(plan(our_laxity()).unwrap().fingerprint, shipped.fingerprint);
        let p = plan(PAPER_LAXITY).unwrap();
        assert_eq!(p.bus.laxity, PAPER_LAXITY);
        assert_ne!(p.fingerprint, shipped.fingerprint);
    }

    #[test]
    fn calendar_matches_fig3() {
        let p = plan(our_laxity()).unwrap();
        let m = *p.master_masks.first().unwrap();
        // Fig. 3: slots 0..=15 reserved, 16..=18 free, 19..=21 reserved, 22..=24 free.
        for s in 0..=15 {
            assert!(m & (1 << s) != 0, "slot {s}");
        }
        for s in [16, 17, 18, 22, 23, 24, 58, 59] {
            assert!(m & (1 << s) == 0, "slot {s}");
        }
        assert_eq!(m.count_ones(), 40, "sync + 3 nodes x 13 HRT slots");
        let c1 = p.tables(1).unwrap().calendar;
        assert_eq!(c1.iter().filter(|e| e.tx == 0).count(), 10);
        assert_eq!(c1.first().map(|e| (e.slot, e.tx)), Some((2, 0)));
        assert!(c1.iter().any(|e| e.slot == 5 && e.tx == 1));
        assert!(c1.iter().any(|e| e.slot == 35 && e.tx == 1));
        assert!(c1.iter().any(|e| e.slot == 11 && e.tx == 2));
    }

    /// The defect of the hand-laid tables (`off += size` where the wire length was
    /// size + 2 with the old transfer CRC): bytes landed in the next topic's buffer. The
    /// model's buffers are disjoint and hold the wire length.
    #[test]
    fn receive_buffers_are_disjoint_and_hold_the_wire_length() {
        let sc = scenario(our_laxity(), 1.0).unwrap();
        assert_eq!(
            sc.tables.len(),
            4,
            "three benchmark nodes and the capture module"
        );
        let capture = sc.tables.get(3).unwrap();
        assert_eq!(capture.rx.len(), 54);
        let mut spans: Vec<(usize, usize)> = capture
            .rx
            .iter()
            .map(|r| {
                let at = usize::from(r.arena_offset);
                (at, at + wire_len(usize::from(r.size)))
            })
            .collect();
        spans.sort_unstable();
        for w in spans.windows(2) {
            assert!(w[0].1 <= w[1].0, "overlap {:?} {:?}", w[0], w[1]);
        }
    }

    #[test]
    fn labels_and_traffic_follow_table2() {
        assert_eq!(class_label("h_a1"), "H_A");
        assert_eq!(class_label("s_c3_5"), "S_C");
        let p = plan(our_laxity()).unwrap();
        let t = traffic(&p).unwrap();
        assert_eq!(t.len(), 45);
        let sa = t.iter().find(|x| x.topic == "s_a2_4").unwrap();
        assert_eq!(
            sa.kind,
            GenKind::Random {
                lo: 10 * MS,
                hi: 20 * MS
            }
        );
        // Load 2: twice the rate. Node 1 (bench2), topic 6 = s_a2_4.
        let sc = scenario(our_laxity(), 2.0).unwrap();
        let g = sc.gens[1].iter().find(|g| g.tx == 6).unwrap();
        assert_eq!(
            g.kind,
            GenKind::Random {
                lo: 5 * MS,
                hi: 10 * MS
            }
        );
        let sc = scenario(our_laxity(), 1.0).unwrap();
        let labels: Vec<&str> = sc
            .topics
            .iter()
            .filter(|i| i.node == 1)
            .map(|i| i.label.as_str())
            .collect();
        assert_eq!(labels.len(), 18);
        assert_eq!(&labels[..4], ["H_A", "H_B", "H_C", "S_A"]);
        assert_eq!(labels[17], "S_C");
    }
}
