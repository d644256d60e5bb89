//! TDMA checks and free-window arithmetic in bus time (slot 0 of cycle 0 = bus time 0).
use rtcan_core::tables::BusConfig;
use rtcan_core::Nanos;

use crate::bus::WireFrame;

/// Reservation mask of absolute cycle `cycle`.
fn mask_of(masks: &[u64], cycle: u64) -> u64 {
    if masks.is_empty() {
        return 1;
    }
    masks
        .get((cycle % masks.len() as u64) as usize)
        .copied()
        .unwrap_or(u64::MAX)
        | 1
}

fn reserved(bus: &BusConfig, masks: &[u64], abs_slot: u64) -> bool {
    let spc = u64::from(bus.slots_per_cycle.max(1));
    mask_of(masks, abs_slot / spc) & (1u64 << (abs_slot % spc)) != 0
}

/// Frames that break temporal isolation: an HRT or sync frame not contained in one
/// reserved slot, or any other frame touching a reserved slot. `to_bus` maps global
/// time to bus time (the master's slot clock); frames before bus time 0 are ignored.
pub fn overlaps(
    wire: &[WireFrame],
    bus: &BusConfig,
    masks: &[u64],
    to_bus: impl Fn(Nanos) -> Option<Nanos>,
) -> u64 {
    let slot = bus.slot_ns.max(1);
    let mut bad = 0;
    for w in wire {
        let (Some(s), Some(e)) = (to_bus(w.sof), to_bus(w.end)) else {
            continue;
        };
        let first = s / slot;
        let last = e.saturating_sub(1) / slot;
        let tdma = w.frame.id().laxity() == 0;
        let ok = if tdma {
            first == last && reserved(bus, masks, first)
        } else {
            (first..=last).all(|k| !reserved(bus, masks, k))
        };
        if !ok {
            bad += 1;
        }
    }
    bad
}

/// Free windows of one hyperperiod as (start, length) in bus time, guard not applied.
pub fn free_windows(bus: &BusConfig, masks: &[u64]) -> Vec<(Nanos, Nanos)> {
    let spc = u64::from(bus.slots_per_cycle.max(1));
    let cycles = masks.len().max(1) as u64;
    let mut out: Vec<(Nanos, Nanos)> = Vec::new();
    let mut open: Option<u64> = None;
    for k in 0..cycles * spc {
        let free = !reserved(bus, masks, k);
        match (free, open) {
            (true, None) => open = Some(k),
            (false, Some(o)) => {
                out.push((o * bus.slot_ns, (k - o) * bus.slot_ns));
                open = None;
            }
            _ => {}
        }
    }
    if let Some(o) = open {
        // Runs to the end of the hyperperiod: the next cycle starts with the sync slot.
        out.push((o * bus.slot_ns, (cycles * spc - o) * bus.slot_ns));
    }
    out
}
