//! HRT admission and phase assignment (exact search) plus the paper's rule as a named
//! baseline. Runs at build time in rtcan-model; no_std, no allocation: all scratch lives
//! in fixed tables on the stack (`MAX_HRT` entries, and one counter per slot of the
//! longest hyperperiod for the capacity bound: about 60 KiB).
//!
//! # Model
//! Slots are counted from slot 0 of cycle 0. Request `i` with period `p`, `f` fragments
//! and phase `φ` (`0 <= φ < p`) occupies slots `φ + k·p + j` for `k >= 0`, `j < f`. Slot 0
//! of every cycle (`slot ≡ 0 mod slots_per_cycle`) is the sync slot; it is treated as a
//! pre-placed message with period `slots_per_cycle`, one fragment and phase 0.
//!
//! # Collision test (no slot enumeration)
//! Runs `i` and `j` share a slot iff `φi + a + m·pi = φj + b + n·pj` for some integers
//! `m, n` and `a < fi`, `b < fj`. By Bézout, `m·pi − n·pj` ranges over exactly the
//! multiples of `g = gcd(pi, pj)`, so they collide iff `φj − φi ≡ a − b (mod g)` for some
//! `a − b ∈ [−(fj−1), fi−1]`. With `δ = (φj − φi) mod g` the covered residues are
//! `[0, fi−1] ∪ [g−fj+1, g−1]`, hence
//!
//! ```text
//! no collision  <=>  fi <= δ <= g − fj        (impossible when fi + fj > g)
//! ```
//!
//! The schedule repeats every hyperperiod `H = lcm(slots_per_cycle, periods)`; a run
//! that crosses `H` would cover slot `H ≡ 0`, a sync slot, so the test above (applied
//! against the sync) also keeps every run inside one hyperperiod.
//!
//! # Search
//! Exact backtracking with conflict-directed backjumping (CBJ):
//! - phase `φi` only matters modulo `gcd(pi, pj)` for every other `j` (and the sync), so
//!   the domain is `[0, Gi)` with `Gi = lcm_j gcd(pi, pj)`, a divisor of `pi`;
//! - variables are ordered most constrained first: utilisation `f/p` descending (the
//!   "largest item first" of bin packing), then short period first;
//! - values are tried in increasing order (first fit); a conflict with run `k` jumps
//!   straight past every value that still collides with `k`;
//! - identical requests are interchangeable, so their phases are forced to increase
//!   (symmetry breaking; any placement can be permuted into that form);
//! - a dead end jumps back to the latest variable that caused a rejection (CBJ). The
//!   variables used by the refutation are tracked, so "infeasible" comes with a core,
//!   which a deletion filter then shrinks;
//! - a capacity bound per residue class prunes where CBJ alone would enumerate
//!   permutations: with `m` the gcd of the periods still to place, every remaining run
//!   stays in fixed classes mod `m`; placed runs whose periods share a divisor `g | m`
//!   with a remaining kind forbid it whole classes; the slots still needed must fit in
//!   the free slots of the classes still usable (per kind and in total). It decides,
//!   e.g., `robots/hrt200.toml` with one period changed to 12 slots (a quarter of the
//!   classes lost to 199 harmonic messages), which plain CBJ gave up on after 20 M
//!   steps;
//! - a set the first order cannot decide in 1/16 of the budget is retried with the
//!   smallest phase domain first, then the most inharmonic period first, then the first
//!   order again (see `ATTEMPTS`); the first order keeps the phases robots got before.
//!   Running out of budget is `TooHard` ("undecided"), never "infeasible".
//!
//! The 2014 C code accepted only harmonic periods and first-fit single-slot phases and
//! was never called (original-rtcan-code.md §4); the paper's rule ("periods not
//! relatively prime") is kept as [`paper_rule`] for comparison only.
/// One HRT message to place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HrtRequest {
    /// Period in slots.
    pub period_slots: u32,
    /// Frames per message; they go in consecutive slots.
    pub fragments: u8,
}

/// Where a request was placed: its first slot, counted from slot 0 of cycle 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Placement {
    /// First slot of the first occurrence, `0 <= phase_slot < period_slots`.
    pub phase_slot: u32,
}

/// Most HRT requests in one admission.
pub const MAX_HRT: usize = 256;
/// Longest hyperperiod accepted (the master keeps one mask per cycle of it).
pub const MAX_HYPERPERIOD_SLOTS: u64 = 10_000;
/// Most fragments of one message (7-bit fragment counter).
pub const MAX_FRAGMENTS: u8 = 128;
/// Most request indices reported by [`AdmissionError::Infeasible`].
pub const MAX_CONFLICT: usize = 8;
/// Search budget per candidate period in [`suggest_periods`].
pub const SUGGEST_BUDGET: u64 = 200_000;
/// Most candidate periods [`suggest_periods`] runs the full search on.
pub const SUGGEST_MAX_TRIES: usize = 256;

/// Why a set of HRT requests was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AdmissionError {
    /// More than `MAX_HRT` requests, or `out` shorter than `requests`.
    TooMany {
        /// Number of requests.
        count: usize,
    },
    /// Period 0, fragments 0 or > 128, fragments > period, or a run that hits a sync slot
    /// at every phase (`fragments >= gcd(period, slots_per_cycle)`, e.g. a period
    /// relatively prime to the cycle).
    InvalidRequest {
        /// Index of the first bad request.
        index: usize,
    },
    /// `lcm(slots_per_cycle, periods) > MAX_HYPERPERIOD_SLOTS` (`slots` is the first
    /// partial lcm past the limit; `u64::MAX` when `slots_per_cycle` is 0).
    HyperperiodTooLong {
        /// Hyperperiod (or a lower bound of it) in slots.
        slots: u64,
    },
    /// More slots requested per hyperperiod than there are non-sync slots.
    OverCapacity {
        /// Slots requested per hyperperiod.
        reserved: u64,
        /// Non-sync slots per hyperperiod.
        available: u64,
    },
    /// No placement exists; `conflict[..len]` are request indices (ascending) that cannot
    /// be placed together. Truncated to `MAX_CONFLICT` if the core found is larger.
    Infeasible {
        /// Request indices.
        conflict: [u16; MAX_CONFLICT],
        /// Number of valid entries in `conflict`.
        len: u8,
        /// Requests in the core found (`> len` when `conflict` is truncated, e.g. a
        /// capacity argument over many requests).
        size: u16,
    },
    /// Undecided: the search budget ran out before an answer (neither a placement nor
    /// a proof that none exists). `stuck[..len]` are request indices: `stuck[0]` the
    /// request the search was placing when it stopped, then the requests its
    /// rejections came from, latest choice first.
    TooHard {
        /// Steps spent.
        steps: u64,
        /// Request indices.
        stuck: [u16; MAX_CONFLICT],
        /// Number of valid entries in `stuck`.
        len: u8,
    },
}

/// What an admission cost and produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AdmitStats {
    /// Search steps (candidate phases examined).
    pub steps: u64,
    /// Hyperperiod in slots.
    pub hyperperiod_slots: u64,
    /// Slots reserved per hyperperiod (sync slots not counted).
    pub reserved_slots: u64,
}

/// Greatest common divisor (`gcd(0, b) = b`).
pub const fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

/// Least common multiple; `None` on overflow or if either is 0.
pub const fn lcm(a: u64, b: u64) -> Option<u64> {
    if a == 0 || b == 0 {
        return None;
    }
    (a / gcd(a, b)).checked_mul(b)
}

/// `lcm(slots_per_cycle, all periods)`; `None` if `slots_per_cycle` or a period is 0, or
/// on overflow.
pub fn hyperperiod(slots_per_cycle: u32, requests: &[HrtRequest]) -> Option<u64> {
    let mut h = u64::from(slots_per_cycle);
    if h == 0 {
        return None;
    }
    for r in requests {
        h = lcm(h, u64::from(r.period_slots))?;
    }
    Some(h)
}

/// True if a message with request `p` placed at `pl` occupies `slot` (counted from slot 0
/// of cycle 0).
pub fn occupies(p: &HrtRequest, pl: Placement, slot: u64) -> bool {
    let period = u64::from(p.period_slots);
    let phase = u64::from(pl.phase_slot);
    if period == 0 || slot < phase {
        return false;
    }
    (slot - phase) % period < u64::from(p.fragments)
}

/// The paper's admission test (§3.3): every pair of periods must not be relatively
/// prime. `Err((i, j))` names the first coprime pair. A baseline only: it is necessary
/// (coprime periods collide at every phase) but far from sufficient (it ignores
/// capacity, fragments and the sync slot).
pub fn paper_rule(requests: &[HrtRequest]) -> Result<(), (usize, usize)> {
    for (i, a) in requests.iter().enumerate() {
        for (j, b) in requests.iter().enumerate().skip(i + 1) {
            if gcd(u64::from(a.period_slots), u64::from(b.period_slots)) == 1 {
                return Err((i, j));
            }
        }
    }
    Ok(())
}

/// The 2014 C code's test (`calendar_check`): every pair of periods must be harmonic
/// (one divides the other). `Err((i, j))` names the first non-harmonic pair.
pub fn harmonic_rule(requests: &[HrtRequest]) -> Result<(), (usize, usize)> {
    for (i, a) in requests.iter().enumerate() {
        for (j, b) in requests.iter().enumerate().skip(i + 1) {
            let (x, y) = (a.period_slots, b.period_slots);
            let harmonic = x != 0 && y != 0 && (x % y == 0 || y % x == 0);
            if !harmonic {
                return Err((i, j));
            }
        }
    }
    Ok(())
}

/// Admits `requests` on a bus with `slots_per_cycle` slots per cycle and writes each
/// request's phase to `out[i]`. Exact: fails with `Infeasible` only if no placement
/// exists; deterministic; at most about `budget` steps (candidate phases examined).
pub fn admit(
    slots_per_cycle: u32,
    requests: &[HrtRequest],
    out: &mut [Placement],
    budget: u64,
) -> Result<AdmitStats, AdmissionError> {
    admit_with(slots_per_cycle, requests, out, budget, true)
}

/// [`admit`]; `shrink`: minimise the core of an infeasible set (a deletion filter of up
/// to `n` more searches, which [`suggest_periods`] does not need).
fn admit_with(
    slots_per_cycle: u32,
    requests: &[HrtRequest],
    out: &mut [Placement],
    budget: u64,
    shrink: bool,
) -> Result<AdmitStats, AdmissionError> {
    let n = requests.len();
    if n > MAX_HRT || out.len() < n {
        return Err(AdmissionError::TooMany { count: n });
    }
    let (hyper, reserved) = precheck(slots_per_cycle, requests)?;
    let mut all = Set::EMPTY;
    for i in 0..n {
        all.insert(i);
    }
    let mut phases = Tab::<u32>::new();
    let mut steps = 0u64;
    match search(
        slots_per_cycle,
        requests,
        &all,
        &mut phases,
        &mut steps,
        budget,
    ) {
        Outcome::Found => {
            for (i, o) in out.iter_mut().enumerate().take(n) {
                *o = Placement {
                    phase_slot: phases.at(i),
                };
            }
            Ok(AdmitStats {
                steps,
                hyperperiod_slots: hyper,
                reserved_slots: reserved,
            })
        }
        Outcome::TooHard(stuck, len) => Err(AdmissionError::TooHard { steps, stuck, len }),
        Outcome::Infeasible(core) => {
            let core = if shrink {
                shrink_core(slots_per_cycle, requests, core, &mut steps, budget)
            } else {
                core
            };
            Err(infeasible(&core, requests))
        }
    }
}

/// Validity, hyperperiod and capacity checks; returns (hyperperiod, reserved slots).
fn precheck(slots_per_cycle: u32, requests: &[HrtRequest]) -> Result<(u64, u64), AdmissionError> {
    let s = u64::from(slots_per_cycle);
    for (index, r) in requests.iter().enumerate() {
        let (p, f) = (u64::from(r.period_slots), u64::from(r.fragments));
        let bad = p == 0 || f == 0 || r.fragments > MAX_FRAGMENTS || f > p;
        // The sync is a run of period S, one fragment, phase 0: the pair test with
        // g = gcd(p, S) needs f + 1 <= g for some phase to exist.
        if bad || (s != 0 && f >= gcd(p, s)) {
            return Err(AdmissionError::InvalidRequest { index });
        }
    }
    if s == 0 {
        return Err(AdmissionError::HyperperiodTooLong { slots: u64::MAX });
    }
    let mut hyper = s;
    for r in requests {
        hyper = match lcm(hyper, u64::from(r.period_slots)) {
            Some(h) if h <= MAX_HYPERPERIOD_SLOTS => h,
            Some(h) => return Err(AdmissionError::HyperperiodTooLong { slots: h }),
            None => return Err(AdmissionError::HyperperiodTooLong { slots: u64::MAX }),
        };
    }
    // Periods divide hyper <= 10_000 and n <= 256, so nothing here can overflow.
    let reserved: u64 = requests
        .iter()
        .map(|r| u64::from(r.fragments) * (hyper / u64::from(r.period_slots)))
        .sum();
    let available = hyper - hyper / s;
    if reserved > available {
        return Err(AdmissionError::OverCapacity {
            reserved,
            available,
        });
    }
    Ok((hyper, reserved))
}

/// `Infeasible` for `core`. A core larger than `MAX_CONFLICT` (a capacity argument) is
/// represented by its most demanding members (utilisation `f/p`, then index), which
/// are the ones worth changing.
fn infeasible(core: &Set, requests: &[HrtRequest]) -> AdmissionError {
    let mut shown = *core;
    while shown.len() > MAX_CONFLICT {
        // Drop the least demanding member (latest index on ties).
        let util = |i: usize| {
            requests.get(i).map_or((0, 1), |r| {
                (u64::from(r.fragments), u64::from(r.period_slots))
            })
        };
        let least = shown.iter().fold(None::<usize>, |best, i| match best {
            None => Some(i),
            Some(b) => {
                let ((fi, pi), (fb, pb)) = (util(i), util(b));
                // i <= b in utilisation: fi / pi <= fb / pb.
                if fi * pb <= fb * pi {
                    Some(i)
                } else {
                    Some(b)
                }
            }
        });
        match least {
            Some(i) => shown.remove(i),
            None => break,
        }
    }
    let (conflict, len) = indices(&shown);
    let size = u16::try_from(core.len()).unwrap_or(u16::MAX);
    AdmissionError::Infeasible {
        conflict,
        len,
        size,
    }
}

/// The first `MAX_CONFLICT` members of `set`, ascending.
fn indices(set: &Set) -> ([u16; MAX_CONFLICT], u8) {
    let mut out = [0u16; MAX_CONFLICT];
    let mut len = 0u8;
    for (slot, i) in out.iter_mut().zip(set.iter()) {
        *slot = u16::try_from(i).unwrap_or(u16::MAX);
        len += 1;
    }
    (out, len)
}

/// Deletion filter: drops every member whose removal leaves the rest infeasible (the
/// sub-search's own core replaces the current one). Stops quietly when the budget runs
/// out; the core found so far is still a valid (if larger) core.
fn shrink_core(
    slots_per_cycle: u32,
    requests: &[HrtRequest],
    mut core: Set,
    steps: &mut u64,
    budget: u64,
) -> Set {
    if core.len() <= 2 {
        // Every single request is placeable on its own (precheck), so a pair is minimal.
        return core;
    }
    let mut phases = Tab::<u32>::new();
    for m in 0..requests.len() {
        if !core.contains(m) {
            continue;
        }
        let mut trial = core;
        trial.remove(m);
        match search(
            slots_per_cycle,
            requests,
            &trial,
            &mut phases,
            steps,
            budget,
        ) {
            Outcome::Infeasible(smaller) => core = smaller,
            Outcome::Found => {}
            Outcome::TooHard(..) => break,
        }
    }
    core
}

enum Outcome {
    Found,
    Infeasible(Set),
    /// Budget exhausted; the requests the search was stuck on (`AdmissionError::TooHard`).
    TooHard([u16; MAX_CONFLICT], u8),
}

/// Exact CBJ search over the requests in `members`; phases land in `phases[index]`.
/// Variable orders the search tries in turn (see [`search`]).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Order {
    /// Utilisation `f/p` descending (largest item first), then period, then index.
    Utilisation,
    /// Smallest phase domain first (the request whose period shares the smallest
    /// divisors with the others: fewest distinct phases), then as `Utilisation`.
    Domain,
    /// Most inharmonic first: the request whose period neither divides nor is a
    /// multiple of the most other periods, then as `Utilisation`.
    Inharmonic,
}

/// Share of the budget (in 1/16) the search may have used when each attempt ends: the
/// first order keeps the phases every robot got so far; a set it cannot decide
/// quickly is retried smallest-domain-first (a period that breaks the harmony of the
/// others, placed first, stops hundreds of permutations of the harmonic ones), then
/// with the first order again for the rest of the budget.
const ATTEMPTS: [(Order, u64); 4] = [
    (Order::Utilisation, 1),
    (Order::Domain, 6),
    (Order::Inharmonic, 11),
    (Order::Utilisation, 16),
];

/// Exact search over `members` with [`ATTEMPTS`]; `TooHard` only when the whole
/// budget is spent.
fn search(
    slots_per_cycle: u32,
    requests: &[HrtRequest],
    members: &Set,
    phases: &mut Tab<u32>,
    steps: &mut u64,
    budget: u64,
) -> Outcome {
    let mut last = Outcome::TooHard([0; MAX_CONFLICT], 0);
    for (order, sixteenths) in ATTEMPTS {
        let cap = if sixteenths >= 16 {
            budget
        } else {
            budget / 16 * sixteenths
        };
        if *steps > cap {
            continue;
        }
        last = search_order(
            slots_per_cycle,
            requests,
            members,
            phases,
            steps,
            cap,
            order,
        );
        if !matches!(last, Outcome::TooHard(..)) {
            return last;
        }
    }
    last
}

/// Exact CBJ search over `members` in one static variable order; gives up once
/// `steps` exceeds `budget`.
fn search_order(
    slots_per_cycle: u32,
    requests: &[HrtRequest],
    members: &Set,
    phases: &mut Tab<u32>,
    steps: &mut u64,
    budget: u64,
    by: Order,
) -> Outcome {
    let s = u64::from(slots_per_cycle);
    // Static order: most constrained first (see module docs).
    let mut order = Tab::<u16>::new();
    let mut n = 0usize;
    for i in members.iter() {
        order.set(n, u16::try_from(i).unwrap_or(u16::MAX));
        n += 1;
    }
    let req = |i: usize| {
        requests.get(i).copied().unwrap_or(HrtRequest {
            period_slots: 1,
            fragments: 1,
        })
    };
    // Phase domain of each member: lcm of its gcds with the sync and every other member.
    let mut domain_of = Tab::<u64>::new();
    if by == Order::Inharmonic {
        // Key: members whose period is not harmonic with this one (ascending sort key:
        // MAX_HRT minus that count).
        for i in members.iter() {
            let p = req(i).period_slots;
            let mut count = 0u64;
            for k in members.iter() {
                let q = req(k).period_slots;
                if p != 0 && q != 0 && p % q != 0 && q % p != 0 {
                    count += 1;
                }
            }
            domain_of.set(i, MAX_HRT as u64 - count.min(MAX_HRT as u64));
        }
    }
    if by == Order::Domain {
        for i in members.iter() {
            let p = u64::from(req(i).period_slots);
            let mut g_all = gcd(p, s);
            for k in members.iter() {
                if k != i && g_all != p {
                    g_all = lcm(g_all, gcd(p, u64::from(req(k).period_slots))).unwrap_or(p);
                }
            }
            domain_of.set(i, g_all);
        }
    }
    order.as_mut_slice(n).sort_unstable_by(|&a, &b| {
        let (ra, rb) = (req(usize::from(a)), req(usize::from(b)));
        // Utilisation f/p descending, then period ascending, then index.
        let ua = u64::from(ra.fragments) * u64::from(rb.period_slots);
        let ub = u64::from(rb.fragments) * u64::from(ra.period_slots);
        let first = match by {
            Order::Utilisation => core::cmp::Ordering::Equal,
            Order::Domain | Order::Inharmonic => domain_of
                .at(usize::from(a))
                .cmp(&domain_of.at(usize::from(b))),
        };
        first
            .then(ub.cmp(&ua))
            .then(ra.period_slots.cmp(&rb.period_slots))
            .then(a.cmp(&b))
    });

    // Per depth: period, fragments, domain size, sync gcd, "same as previous depth".
    let mut per = Tab::<u64>::new();
    let mut frag = Tab::<u64>::new();
    let mut dom = Tab::<u64>::new();
    let mut sync_g = Tab::<u64>::new();
    let mut same_prev = Tab::<bool>::new();
    for d in 0..n {
        let r = req(usize::from(order.at(d)));
        let p = u64::from(r.period_slots);
        per.set(d, p);
        frag.set(d, u64::from(r.fragments));
        sync_g.set(d, gcd(p, s));
        if d > 0 {
            let q = req(usize::from(order.at(d - 1)));
            same_prev.set(d, q == r);
        }
    }
    for d in 0..n {
        let p = per.at(d);
        let mut g_all = sync_g.at(d);
        for k in 0..n {
            if k != d && g_all != p {
                g_all = lcm(g_all, gcd(p, per.at(k))).unwrap_or(p);
            }
        }
        dom.set(d, g_all);
    }

    let mut phase = Tab::<u64>::new();
    let mut next = Tab::<u64>::new();
    let mut conf = Tab::<Set>::new();
    let mut inv = Tab::<Set>::new();
    // gcd(per[row_depth], per[k]) for k < row_depth, recomputed when the depth changes.
    let mut row = Tab::<u64>::new();
    let mut row_depth = usize::MAX;

    let enter = |d: usize,
                 phase: &Tab<u64>,
                 next: &mut Tab<u64>,
                 conf: &mut Tab<Set>,
                 inv: &mut Tab<Set>,
                 same: bool| {
        let mut c = Set::EMPTY;
        let mut v = Set::EMPTY;
        v.insert(d);
        let mut start = 0;
        if same && d > 0 {
            // Symmetry breaking: phases of identical requests increase along the order;
            // values up to the previous one's phase are excluded "by" it.
            start = phase.at(d - 1) + 1;
            c.insert(d - 1);
            v.insert(d - 1);
        }
        next.set(d, start);
        conf.set(d, c);
        inv.set(d, v);
    };

    // Hyperperiod of this subset (precheck bounded the whole set's by MAX_HYPERPERIOD_SLOTS).
    let mut hyper = s.max(1);
    for k in 0..n {
        hyper = lcm(hyper, per.at(k)).unwrap_or(hyper);
    }
    let mut scratch = Classes::new();
    let start = Placed {
        slots_per_cycle: s,
        hyper,
        n,
        per: &per,
        frag: &frag,
        phase: &phase,
        same_prev: &same_prev,
    };
    if n > 0 && !start.room_for_rest(0, &mut scratch, steps) {
        return Outcome::Infeasible(*members);
    }

    let mut d = 0usize;
    if n > 0 {
        enter(0, &phase, &mut next, &mut conf, &mut inv, false);
    }
    while d < n {
        if row_depth != d {
            let p = per.at(d);
            for k in 0..d {
                row.set(k, gcd(p, per.at(k)));
            }
            row_depth = d;
        }
        let (f, g_sync, domain) = (frag.at(d), sync_g.at(d), dom.at(d));
        let mut v = next.at(d);
        let mut found = false;
        while v < domain {
            *steps += 1;
            if *steps > budget {
                // The request being placed, then its culprits, latest choice first.
                let mut stuck = [order.at(d); MAX_CONFLICT];
                let mut len = 1u8;
                let culprits = conf.at(d);
                for k in (0..d).rev().filter(|&k| culprits.contains(k)) {
                    match stuck.get_mut(usize::from(len)) {
                        Some(slot) => *slot = order.at(k),
                        None => break,
                    }
                    len += 1;
                }
                for slot in stuck.iter_mut().skip(usize::from(len)) {
                    *slot = 0;
                }
                return Outcome::TooHard(stuck, len);
            }
            // Against the sync (phase 0, one fragment): need 1 <= v mod g <= g - f.
            let r = v % g_sync;
            if r == 0 {
                v += 1;
                continue;
            }
            if r + f > g_sync {
                v += g_sync - r + 1;
                continue;
            }
            // Against every placed run, earliest first (earliest culprit keeps the
            // conflict sets, hence the backjumps, as far back as possible).
            let mut clash = None;
            for k in 0..d {
                let g = row.at(k);
                let fk = frag.at(k);
                if f + fk > g {
                    // Collide at every phase.
                    clash = Some((k, domain - v));
                    break;
                }
                let delta = (phase.at(k) % g + g - v % g) % g;
                if delta < f {
                    clash = Some((k, delta + fk));
                    break;
                }
                if delta > g - fk {
                    clash = Some((k, delta + fk - g));
                    break;
                }
            }
            match clash {
                None => {
                    found = true;
                    break;
                }
                Some((k, jump)) => {
                    if let Some(c) = conf.at_mut(d) {
                        c.insert(k);
                    }
                    if let Some(c) = inv.at_mut(d) {
                        c.insert(k);
                    }
                    v += jump;
                }
            }
        }
        if found {
            phase.set(d, v);
            next.set(d, v + 1);
            let view = Placed {
                slots_per_cycle: s,
                hyper,
                n,
                per: &per,
                frag: &frag,
                phase: &phase,
                same_prev: &same_prev,
            };
            if d + 1 < n && !same_prev.at(d + 1) && !view.room_for_rest(d + 1, &mut scratch, steps)
            {
                // This value leaves the requests after it too few usable slots: reject
                // it like a collision. The reason involves every earlier choice and
                // every request still to place.
                if let Some(c) = conf.at_mut(d) {
                    for k in 0..d {
                        c.insert(k);
                    }
                }
                if let Some(c) = inv.at_mut(d) {
                    for k in 0..n {
                        c.insert(k);
                    }
                }
                continue;
            }
            d += 1;
            if d < n {
                enter(d, &phase, &mut next, &mut conf, &mut inv, same_prev.at(d));
            }
            continue;
        }
        // Dead end: jump back to the latest culprit, handing it our reasons.
        let mut c = conf.at(d);
        let Some(h) = c.max() else {
            let mut core = Set::EMPTY;
            for k in inv.at(d).iter() {
                core.insert(usize::from(order.at(k)));
            }
            return Outcome::Infeasible(core);
        };
        c.remove(h);
        let reasons = inv.at(d);
        if let Some(ch) = conf.at_mut(h) {
            ch.union_with(&c);
        }
        if let Some(ih) = inv.at_mut(h) {
            ih.union_with(&reasons);
        }
        d = h;
    }
    for k in 0..n {
        phases.set(
            usize::from(order.at(k)),
            u32::try_from(phase.at(k)).unwrap_or(u32::MAX),
        );
    }
    Outcome::Found
}

/// Most work units (class × placed run × request kind) one capacity bound may cost; a
/// bigger bound is skipped (not pruning is always sound).
const MAX_BOUND_WORK: u64 = 4_000_000;
/// Work units of the capacity bound counted as one search step against the budget.
const BOUND_WORK_PER_STEP: u64 = 16;

/// Slots per hyperperiod as a bit set / counters indexed by residue class.
struct Classes {
    /// Free slots of each residue class (after the sync and the placed runs).
    free: [u16; MAX_HYPERPERIOD_SLOTS as usize],
    /// Start classes refused for the request kind being examined.
    bad: Bits,
    /// Slot classes the request kind being examined can occupy.
    usable: Bits,
    /// Union of `usable` over every kind still to place.
    any: Bits,
}

impl Classes {
    fn new() -> Self {
        Classes {
            free: [0; MAX_HYPERPERIOD_SLOTS as usize],
            bad: Bits::EMPTY,
            usable: Bits::EMPTY,
            any: Bits::EMPTY,
        }
    }
}

/// The search state the capacity bound reads: depths `< d` are placed.
struct Placed<'a> {
    slots_per_cycle: u64,
    hyper: u64,
    n: usize,
    per: &'a Tab<u64>,
    frag: &'a Tab<u64>,
    phase: &'a Tab<u64>,
    same_prev: &'a Tab<bool>,
}

impl Placed<'_> {
    /// Capacity bound per residue class (sound, never refuses a feasible state):
    /// with `m = gcd` of the periods still to place, each of those runs stays in fixed
    /// residue classes mod `m`. A placed run (or the sync) whose period shares a
    /// divisor `g | m` with a request kind forbids whole start classes to it. The slots
    /// the unplaced requests need per hyperperiod must fit in the free slots of the
    /// classes they can still reach, per kind and all together. Catches, e.g., one
    /// period-12 message on a 64-slot cycle that makes a quarter of all classes
    /// unusable for 199 period-64/512/1024 messages, which plain backtracking would
    /// only refute by enumerating their permutations.
    fn room_for_rest(&self, d: usize, cl: &mut Classes, steps: &mut u64) -> bool {
        let (s, hyper, n) = (self.slots_per_cycle, self.hyper, self.n);
        let mut m = 0u64;
        let mut kinds = 0u64;
        for e in d..n {
            m = gcd(m, self.per.at(e));
            if e == d || !self.same_prev.at(e) {
                kinds += 1;
            }
        }
        let mu = usize::try_from(m).unwrap_or(usize::MAX);
        if m == 0 || s == 0 || hyper % m != 0 || mu > cl.free.len() {
            return true;
        }
        // Upper bound of the work below (each placed run marks at most m classes).
        let work = kinds * (d as u64 + 1) * m + hyper;
        if work > MAX_BOUND_WORK {
            return true;
        }
        *steps += (hyper + kinds * m) / BOUND_WORK_PER_STEP;
        let per_class = u16::try_from(hyper / m).unwrap_or(u16::MAX);
        let free = cl.free.get_mut(..mu).unwrap_or(&mut []);
        free.fill(per_class);
        let mut take = |slot: u64| {
            if let Some(f) = free.get_mut(((slot % hyper) % m) as usize) {
                *f = f.saturating_sub(1);
            }
        };
        let mut slot = 0;
        while slot < hyper {
            take(slot);
            slot += s;
        }
        for k in 0..d {
            let (p, f, ph) = (self.per.at(k), self.frag.at(k), self.phase.at(k));
            let mut start = ph;
            while p > 0 && start < hyper {
                for j in 0..f {
                    take(start + j);
                }
                start += p;
            }
        }
        let mut total = 0u64;
        cl.any.clear(mu);
        let mut first = true;
        let mut e = d;
        while e < n {
            let (q, f) = (self.per.at(e), self.frag.at(e));
            let mut count = 1u64;
            while e + (count as usize) < n && self.same_prev.at(e + count as usize) {
                count += 1;
            }
            e += count as usize;
            let demand = count * f * (hyper / q.max(1));
            total += demand;
            // Start classes this kind cannot use, against the sync and each placed run.
            cl.bad.clear(mu);
            // Run `other` (phase, fragments) forbids the start residues mod g (g | m)
            // `other_phase - (f - 1) ..= other_phase + other_f - 1`: f + other_f - 1
            // consecutive residues, each standing for m / g classes mod m.
            let mut marked = 0u64;
            let mut blocked = |g: u64, other_phase: u64, other_f: u64, bad: &mut Bits| {
                if g == 0 || !m.is_multiple_of(g) {
                    return;
                }
                let width = f + other_f - 1;
                if width >= g {
                    bad.fill(mu);
                    marked += m;
                    return;
                }
                let first = (other_phase % g + g - (f - 1) % g) % g;
                for r in 0..width {
                    let mut c = (first + r) % g;
                    while c < m {
                        bad.insert(c as usize);
                        c += g;
                    }
                }
                marked += width * (m / g);
            };
            blocked(gcd(q, s), 0, 1, &mut cl.bad);
            for k in 0..d {
                blocked(
                    gcd(q, self.per.at(k)),
                    self.phase.at(k),
                    self.frag.at(k),
                    &mut cl.bad,
                );
            }
            *steps += marked / BOUND_WORK_PER_STEP;
            cl.usable.clear(mu);
            for c in 0..mu {
                if !cl.bad.contains(c) {
                    for j in 0..f as usize {
                        cl.usable.insert((c + j) % mu);
                    }
                }
            }
            let room: u64 = (0..mu)
                .filter(|&c| cl.usable.contains(c))
                .map(|c| u64::from(cl.free.get(c).copied().unwrap_or(0)))
                .sum();
            if demand > room {
                // When the very next request has no room at all (or is alone of its
                // kind), the search itself refutes it at the next depth with precise
                // conflict sets: its backjump skips the placements that did not
                // matter, where a prune here would blame every earlier choice and
                // backtrack chronologically. A pigeonhole over several identical
                // requests (39 period-64 messages in 31 usable classes) is pruned:
                // the search would enumerate their placements.
                return first && (room == 0 || count == 1);
            }
            first = false;
            cl.any.union_with(&cl.usable, mu);
        }
        let room: u64 = (0..mu)
            .filter(|&c| cl.any.contains(c))
            .map(|c| u64::from(cl.free.get(c).copied().unwrap_or(0)))
            .sum();
        total <= room
    }
}

/// A bit set over residue classes `0..MAX_HYPERPERIOD_SLOTS`.
struct Bits([u64; (MAX_HYPERPERIOD_SLOTS as usize).div_ceil(64)]);

impl Bits {
    const EMPTY: Bits = Bits([0; (MAX_HYPERPERIOD_SLOTS as usize).div_ceil(64)]);
    /// Clears the bits `0..len`.
    fn clear(&mut self, len: usize) {
        let words = len.div_ceil(64).min(self.0.len());
        if let Some(w) = self.0.get_mut(..words) {
            w.fill(0);
        }
    }
    fn insert(&mut self, i: usize) {
        if let Some(w) = self.0.get_mut(i / 64) {
            *w |= 1 << (i % 64);
        }
    }
    fn contains(&self, i: usize) -> bool {
        self.0.get(i / 64).is_some_and(|w| w & (1 << (i % 64)) != 0)
    }
    /// Sets the bits `0..len` (and possibly a few above, in the last word).
    fn fill(&mut self, len: usize) {
        let words = len.div_ceil(64).min(self.0.len());
        if let Some(w) = self.0.get_mut(..words) {
            w.fill(u64::MAX);
        }
    }
    fn union_with(&mut self, other: &Bits, len: usize) {
        let words = len.div_ceil(64);
        for (a, b) in self.0.iter_mut().zip(other.0.iter()).take(words) {
            *a |= *b;
        }
    }
}

/// Admissible alternative periods for request `index`, the others unchanged, written to
/// `out` nearest to the requested period first (shorter first at equal distance); the
/// requested period itself is not listed. Candidates range over `1..=2·period`; at most
/// `SUGGEST_MAX_TRIES` of them get a full search (budget `SUGGEST_BUDGET` each), the
/// others are refused by the cheap checks (validity, hyperperiod, capacity) first.
pub fn suggest_periods(
    slots_per_cycle: u32,
    requests: &[HrtRequest],
    index: usize,
    out: &mut [u32],
) -> usize {
    let n = requests.len();
    let Some(orig) = requests.get(index).copied() else {
        return 0;
    };
    if n > MAX_HRT {
        return 0;
    }
    let mut trial = [HrtRequest {
        period_slots: 1,
        fragments: 1,
    }; MAX_HRT];
    for (t, r) in trial.iter_mut().zip(requests) {
        *t = *r;
    }
    let mut place = [Placement::default(); MAX_HRT];
    let p0 = orig.period_slots;
    let mut written = 0usize;
    let mut tries = 0usize;
    let mut dist = 1u32;
    while written < out.len() && tries < SUGGEST_MAX_TRIES && dist <= p0 {
        for cand in [p0.checked_sub(dist), p0.checked_add(dist)]
            .into_iter()
            .flatten()
        {
            if cand == 0 || written >= out.len() || tries >= SUGGEST_MAX_TRIES {
                continue;
            }
            if let Some(t) = trial.get_mut(index) {
                t.period_slots = cand;
            }
            let Some(set) = trial.get(..n) else {
                return written;
            };
            if precheck(slots_per_cycle, set).is_err() {
                continue;
            }
            tries += 1;
            if admit_with(slots_per_cycle, set, &mut place, SUGGEST_BUDGET, false).is_ok() {
                if let Some(o) = out.get_mut(written) {
                    *o = cand;
                    written += 1;
                }
            }
        }
        dist += 1;
    }
    written
}

/// Builds the master's reservation mask of every cycle of the hyperperiod into `out`
/// (bit k = slot k of that cycle; bit 0, the sync, always set) and returns the number
/// of cycles. Also validates the placements: a collision or a sync hit is reported as
/// `Infeasible` naming the requests involved (one index for a sync hit), a phase not
/// below its period (or bad fragments) as `InvalidRequest`. `TooMany { count }` if
/// `out` holds fewer than `count` cycles or `placements` is shorter than `requests`;
/// `HyperperiodTooLong` also when `slots_per_cycle` is not in 1..=64.
pub fn build_masks(
    slots_per_cycle: u32,
    requests: &[HrtRequest],
    placements: &[Placement],
    out: &mut [u64],
) -> Result<usize, AdmissionError> {
    let s = u64::from(slots_per_cycle);
    let hyper = match hyperperiod(slots_per_cycle, requests) {
        Some(h) if h <= MAX_HYPERPERIOD_SLOTS && (1..=64).contains(&s) => h,
        Some(h) => return Err(AdmissionError::HyperperiodTooLong { slots: h }),
        None => return Err(AdmissionError::HyperperiodTooLong { slots: u64::MAX }),
    };
    let cycles = usize::try_from(hyper / s).unwrap_or(usize::MAX);
    if placements.len() < requests.len() {
        return Err(AdmissionError::TooMany {
            count: requests.len(),
        });
    }
    let Some(masks) = out.get_mut(..cycles) else {
        return Err(AdmissionError::TooMany { count: cycles });
    };
    masks.fill(1);
    // Owner of every slot (u16::MAX = free) to name both parties of a collision.
    let mut owner = [u16::MAX; MAX_HYPERPERIOD_SLOTS as usize];
    let sync_owner = u16::MAX - 1;
    for c in 0..cycles {
        if let Some(o) = owner.get_mut(c * slots_per_cycle as usize) {
            *o = sync_owner;
        }
    }
    for (i, (r, pl)) in requests.iter().zip(placements).enumerate() {
        let me = u16::try_from(i).unwrap_or(u16::MAX);
        let (p, f, phase) = (
            u64::from(r.period_slots),
            u64::from(r.fragments),
            u64::from(pl.phase_slot),
        );
        if phase >= p || f == 0 || f > p {
            return Err(AdmissionError::InvalidRequest { index: i });
        }
        let mut start = phase;
        while start < hyper {
            for j in 0..f {
                // Runs are cyclic over the hyperperiod (the table repeats).
                let slot = (start + j) % hyper;
                let Some(o) = owner.get_mut(slot as usize) else {
                    continue;
                };
                if *o != u16::MAX {
                    let mut conflict = [0u16; MAX_CONFLICT];
                    conflict[0] = me;
                    let mut len = 1;
                    if *o != sync_owner {
                        conflict[0] = (*o).min(me);
                        conflict[1] = (*o).max(me);
                        len = 2;
                    }
                    return Err(AdmissionError::Infeasible {
                        conflict,
                        len,
                        size: u16::from(len),
                    });
                }
                *o = me;
                if let Some(m) = masks.get_mut((slot / s) as usize) {
                    *m |= 1u64 << (slot % s);
                }
            }
            start += p;
        }
    }
    Ok(cycles)
}

/// Bit set over request indices / search depths (`MAX_HRT` bits).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Set([u64; MAX_HRT / 64]);

impl Set {
    const EMPTY: Set = Set([0; MAX_HRT / 64]);
    fn insert(&mut self, i: usize) {
        if let Some(w) = self.0.get_mut(i / 64) {
            *w |= 1 << (i % 64);
        }
    }
    fn remove(&mut self, i: usize) {
        if let Some(w) = self.0.get_mut(i / 64) {
            *w &= !(1 << (i % 64));
        }
    }
    fn contains(&self, i: usize) -> bool {
        self.0.get(i / 64).is_some_and(|w| w & (1 << (i % 64)) != 0)
    }
    fn union_with(&mut self, other: &Set) {
        for (a, b) in self.0.iter_mut().zip(other.0.iter()) {
            *a |= *b;
        }
    }
    fn len(&self) -> usize {
        self.0.iter().map(|w| w.count_ones() as usize).sum()
    }
    fn max(&self) -> Option<usize> {
        self.0
            .iter()
            .enumerate()
            .rev()
            .find(|(_, w)| **w != 0)
            .map(|(k, w)| k * 64 + 63 - w.leading_zeros() as usize)
    }
    fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        (0..MAX_HRT).filter(move |&i| self.contains(i))
    }
}

/// A `MAX_HRT`-entry table indexed by request index or search depth. Every index used
/// is below `requests.len() <= MAX_HRT`; out-of-range reads give the default and
/// writes are dropped instead of panicking.
struct Tab<T: Copy + Default>([T; MAX_HRT]);

impl<T: Copy + Default> Tab<T> {
    fn new() -> Self {
        Tab([T::default(); MAX_HRT])
    }
    fn at(&self, i: usize) -> T {
        self.0.get(i).copied().unwrap_or_default()
    }
    fn at_mut(&mut self, i: usize) -> Option<&mut T> {
        self.0.get_mut(i)
    }
    fn set(&mut self, i: usize, v: T) {
        if let Some(x) = self.0.get_mut(i) {
            *x = v;
        }
    }
    fn as_mut_slice(&mut self, n: usize) -> &mut [T] {
        let n = n.min(MAX_HRT);
        self.0.get_mut(..n).unwrap_or(&mut [])
    }
}
