//! A bus guardian for one node (docs/SIM.md, Bus guardian): an independent device
//! between the controller and the transceiver that lets a frame onto the bus only if the
//! node may send it, and otherwise cuts the node's TX line for good (fail-silent: a
//! babbling idiot becomes a silent node, which the protocol already survives).
//!
//! What it checks, at each start of frame the node attempts:
//! - the message ID is one the node owns (its topics from rtcan-model, its heartbeat,
//!   the sync range if it is master-capable), so a node cannot impersonate another;
//! - the node's frames in the current guardian cycle (its own oscillator, one bus cycle
//!   long) stay within its budget: what its schedule can send in a cycle (HRT fragments,
//!   SRT/NRT frames at their declared rates, heartbeat, sync) with a margin for
//!   retransmissions, so a node flooding with its own IDs is cut too.
//!
//! It needs no clock synchronisation (a time-window guardian, as in TTP/C, would): a
//! babbler is cut within one cycle, before the others' HRT topics miss more than one
//! period. Frames already on the wire complete. The cut is latched for the run.
use rtcan_core::{CanId, Nanos};

/// Guardian of one node.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Guardian {
    /// Message IDs the node owns, sorted.
    owned: Vec<u16>,
    /// May send the sync (message IDs below `SYNC_MSG_ID_END`).
    sync: bool,
    /// Frames per guardian cycle.
    budget: u32,
    cycle_ns: Nanos,
    /// Start of the current guardian cycle and frames sent in it.
    window: (Nanos, u32),
    /// When the guardian cut the node off, and why.
    pub tripped: Option<(Nanos, Trip)>,
}

/// Why a guardian cut its node off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Trip {
    /// A frame with a message ID the node does not own (raw identifier).
    ForeignId(u32),
    /// More frames than its budget within one guardian cycle.
    OverBudget,
}

impl Guardian {
    /// A guardian letting the node send `owned` message IDs (and the sync if `sync`), at
    /// most `budget` frames per `cycle_ns`.
    pub fn new(mut owned: Vec<u16>, sync: bool, budget: u32, cycle_ns: Nanos) -> Self {
        owned.sort_unstable();
        owned.dedup();
        Guardian {
            owned,
            sync,
            budget: budget.max(1),
            cycle_ns: cycle_ns.max(1),
            window: (0, 0),
            tripped: None,
        }
    }

    /// The node's TX is cut.
    pub fn is_tripped(&self) -> bool {
        self.tripped.is_some()
    }

    /// The node wants to start `id` at global time `now`: true if the guardian lets it
    /// (it then counts it), false if it cuts the node (latched).
    pub fn admit(&mut self, now: Nanos, id: CanId) -> bool {
        if self.tripped.is_some() {
            return false;
        }
        let msg = id.msg_id().0;
        let owned = if id.is_sync() {
            self.sync
        } else {
            self.owned.binary_search(&msg).is_ok()
        };
        if !owned {
            self.tripped = Some((now, Trip::ForeignId(id.raw())));
            return false;
        }
        if now >= self.window.0 + self.cycle_ns {
            // Guardian cycles are aligned to its own time base, not to the bus's.
            self.window = (now - now % self.cycle_ns, 0);
        }
        if self.window.1 >= self.budget {
            self.tripped = Some((now, Trip::OverBudget));
            return false;
        }
        true
    }

    /// The admitted frame went on the wire (it won arbitration).
    pub fn sent(&mut self) {
        self.window.1 = self.window.1.saturating_add(1);
    }
}

/// One guardian per node of `sc`, from the robot's tables (rtcan-model): the node's
/// topics, its heartbeat, the sync if `master_capable(node)`; budget per bus cycle =
/// 2 x (HRT and window frames its topics can send in a cycle at their periods, plus one
/// heartbeat and one sync) + 4, the margin for retransmissions after errors.
pub fn for_scenario(
    sc: &crate::run::Scenario,
    master_capable: impl Fn(usize) -> bool,
) -> Vec<Guardian> {
    let cycle_ns = sc.bus().map_or(10_000_000, |b| b.cycle_ns()).max(1);
    (0..sc.tables.len())
        .map(|n| {
            let mine = sc.topics.iter().filter(|t| t.node == n);
            let mut owned: Vec<u16> = mine.clone().map(|t| t.msg_id.0).collect();
            owned.extend(
                u8::try_from(n)
                    .ok()
                    .and_then(rtcan_core::heartbeat::heartbeat_msg_id)
                    .map(|m| m.0),
            );
            let frames: u64 = mine
                .map(|t| {
                    let per_cycle = cycle_ns.div_ceil(t.period_ns.max(1));
                    rtcan_core::fragment::fragment_count(t.size) as u64 * per_cycle
                })
                .sum();
            let budget = u32::try_from(2 * (frames + 2) + 4).unwrap_or(u32::MAX);
            Guardian::new(owned, master_capable(n), budget, cycle_ns)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtcan_core::MsgId;

    fn id(laxity: u8, msg: u16) -> CanId {
        CanId::new(laxity, MsgId(msg), 0).unwrap()
    }

    #[test]
    fn foreign_ids_cut_the_node_for_good() {
        let mut g = Guardian::new(vec![0x150, 0x101], false, 10, 10_000_000);
        assert!(g.admit(0, id(0, 0x150)));
        g.sent();
        assert!(g.admit(100, id(63, 0x101)));
        g.sent();
        // The sync is not this node's.
        assert!(!g.admit(200, CanId::from_raw(0).unwrap()));
        assert_eq!(g.tripped, Some((200, Trip::ForeignId(0))));
        // Latched: its own IDs no longer pass either.
        assert!(!g.admit(300, id(0, 0x150)));
        let mut h = Guardian::new(vec![0x150], true, 10, 10_000_000);
        assert!(h.admit(0, CanId::from_raw(0).unwrap()));
        assert!(!h.admit(1, id(0, 0x151)));
        assert_eq!(
            h.tripped.map(|t| t.1),
            Some(Trip::ForeignId(id(0, 0x151).raw()))
        );
    }

    #[test]
    fn budget_per_cycle_with_own_ids() {
        let mut g = Guardian::new(vec![0x150], false, 3, 10_000_000);
        // Offered and lost arbitration (no `sent`): not counted.
        assert!(g.admit(0, id(0, 0x150)));
        for t in [1_000, 2_000, 3_000] {
            assert!(g.admit(t, id(0, 0x150)));
            g.sent();
        }
        // A new cycle: the budget is back.
        for t in [10_000_000, 10_001_000, 10_002_000] {
            assert!(g.admit(t, id(0, 0x150)));
            g.sent();
        }
        assert!(g.tripped.is_none());
        assert!(!g.admit(19_999_999, id(0, 0x150)));
        assert_eq!(g.tripped, Some((19_999_999, Trip::OverBudget)));
    }
}
