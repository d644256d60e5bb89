//! The policies compared side by side on one event trace.

/// An SRT scheduling policy (or a baseline without RTCAN).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PolicyKind {
    /// (a) The RTCAN paper as published: linear 6-bit laxity in 1 ms units, EDF head
    /// only, messages dropped only once their deadline has passed.
    Paper,
    /// (b) Ours: the engine as configured by the plan (log laxity, window-end fitting,
    /// hopeless messages dropped early).
    Ours,
    /// (c) Non-preemptive EDF with global knowledge over the same free windows: a
    /// centralised reference, not an upper bound (greedy EDF with drops is not optimal;
    /// `Ours` beats it at some loads).
    IdealEdf,
    /// (d) Plain CAN, fixed priorities, no TDMA.
    FixedPriority,
}

impl PolicyKind {
    /// All four, in report order.
    pub const ALL: [PolicyKind; 4] = [
        PolicyKind::Paper,
        PolicyKind::Ours,
        PolicyKind::IdealEdf,
        PolicyKind::FixedPriority,
    ];

    /// Short name used in tables and JSON.
    pub fn name(self) -> &'static str {
        match self {
            PolicyKind::Paper => "paper",
            PolicyKind::Ours => "ours",
            PolicyKind::IdealEdf => "ideal-edf",
            PolicyKind::FixedPriority => "fixed-priority",
        }
    }
}
