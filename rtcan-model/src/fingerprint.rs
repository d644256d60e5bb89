//! The robot fingerprint: FNV-1a 32 over a canonical text of everything that must agree
//! between modules (bus, types, module indices, topic IDs, classes, sizes, schedule).
//! Modules compare it in heartbeats to detect images built from different robot.toml.
use crate::plan::Plan;
use rtcan_core::laxity::LaxityEncoding;
use std::fmt::Write as _;

/// FNV-1a, 32 bits.
pub fn fnv1a32(bytes: &[u8]) -> u32 {
    let mut h: u32 = 0x811c_9dc5;
    for b in bytes {
        h ^= u32::from(*b);
        h = h.wrapping_mul(0x0100_0193);
    }
    h
}

/// The canonical text (one item per line; independent of file order of keys and comments).
pub fn canonical(plan: &Plan) -> String {
    let b = &plan.bus;
    let mut s = String::new();
    let lax = match b.laxity {
        LaxityEncoding::Linear { unit_ns } => format!("linear:{unit_ns}"),
        LaxityEncoding::Log { unit_ns } => format!("log:{unit_ns}"),
    };
    let module = |i: usize| plan.modules.get(i).map_or("", |m| m.name.as_str());
    let _ = writeln!(
        s,
        "bus {} {} {} {} {} {} master={}",
        b.bitrate,
        b.slots_per_cycle,
        b.slot_ns,
        b.hyperperiod_cycles,
        lax,
        b.guard_ns,
        module(b.master)
    );
    for t in &plan.types {
        let fields: Vec<String> = t
            .fields
            .iter()
            .map(|f| format!("{}:{}", f.name, f.ty.rust()))
            .collect();
        let _ = writeln!(s, "type {} {}", t.name, fields.join(","));
    }
    for m in &plan.modules {
        let _ = writeln!(s, "module {} {}", m.index, m.name);
    }
    let mut topics: Vec<_> = plan.topics.iter().collect();
    topics.sort_by_key(|t| t.msg_id);
    for t in topics {
        let subs: Vec<&str> = t.subscribers.iter().map(|x| module(x.module)).collect();
        let ty = plan.types.get(t.ty).map_or("", |x| x.name.as_str());
        let _ = writeln!(
            s,
            "topic {:#06x} {} {:?} {} {} {} {:?} {:?} {:?} {} -> {}",
            t.msg_id.0,
            t.name,
            t.class,
            ty,
            t.size,
            t.fragments,
            t.period_slots,
            t.phase_slot,
            t.deadline_ns,
            module(t.module),
            subs.join(",")
        );
    }
    s
}

/// The bus contract every module must share whatever topics it uses: bit rate, slots,
/// slot length, cycle-counter wrap, laxity encoding, guard and master (not the
/// hyperperiod: a calendar built for a divisor of it stays valid while the counter wraps
/// at a common multiple).
pub fn contract(plan: &Plan) -> String {
    let b = &plan.bus;
    format!(
        "bus {} {} {} wrap={} {:?} {} master={}",
        b.bitrate,
        b.slots_per_cycle,
        b.slot_ns,
        b.cycle_counter_wrap,
        b.laxity,
        b.guard_ns,
        plan.modules.get(b.master).map_or("", |m| m.name.as_str())
    )
}

/// Fingerprint of a plan. Without a lock: the whole canonical plan (any edit changes
/// it). With a robot.lock: its lineage and the bus contract, so images built from older
/// robot.toml of the same lock history keep the same fingerprint; the lock never reuses
/// an ID for another layout, so such images cannot misread each other's frames, and
/// `rtcan check --against` lists the modules whose topics disagree.
pub fn of(plan: &Plan) -> u32 {
    match plan.lineage {
        Some(l) => fnv1a32(format!("lineage {l:#010x}\n{}", contract(plan)).as_bytes()),
        None => fnv1a32(canonical(plan).as_bytes()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv_reference_values() {
        assert_eq!(fnv1a32(b""), 0x811c_9dc5);
        assert_eq!(fnv1a32(b"a"), 0xe40c_292c);
        assert_eq!(fnv1a32(b"foobar"), 0xbf9c_f968);
    }
}
