//! HRT admission: the paper's benchmark calendar, exactness against brute force, the
//! error cases, the paper/C baselines and period suggestions.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use proptest::prelude::*;
use rtcan_core::admission::{
    admit, build_masks, harmonic_rule, hyperperiod, occupies, paper_rule, suggest_periods,
    AdmissionError, HrtRequest, Placement, MAX_HRT,
};

const BIG: u64 = 10_000_000;

fn req(period_slots: u32, fragments: u8) -> HrtRequest {
    HrtRequest {
        period_slots,
        fragments,
    }
}

/// Checks a placement by the definition alone (`occupies` over two hyperperiods): every
/// phase below its period, no slot shared, no sync slot used.
fn assert_valid(s: u32, reqs: &[HrtRequest], pl: &[Placement]) {
    let h = hyperperiod(s, reqs).unwrap();
    for (r, p) in reqs.iter().zip(pl) {
        assert!(p.phase_slot < r.period_slots, "{r:?} at {p:?}");
    }
    for slot in 0..2 * h {
        let owners: Vec<usize> = (0..reqs.len())
            .filter(|&i| occupies(&reqs[i], pl[i], slot))
            .collect();
        assert!(owners.len() <= 1, "slot {slot} shared by {owners:?}");
        if slot % u64::from(s) == 0 {
            assert!(owners.is_empty(), "sync slot {slot} given to {owners:?}");
        }
    }
}

/// Exhaustive search over every phase of every request (no gcd reasoning): a slot
/// bitmap over one hyperperiod, runs taken cyclically (the calendar repeats).
fn brute(s: u32, reqs: &[HrtRequest]) -> Option<Vec<u32>> {
    fn dfs(i: usize, reqs: &[HrtRequest], h: usize, occ: &mut [bool], ph: &mut Vec<u32>) -> bool {
        let Some(r) = reqs.get(i) else { return true };
        let (p, f) = (r.period_slots as usize, r.fragments as usize);
        if p == 0 || f == 0 || f > p {
            return false;
        }
        let slots =
            |phi: usize| (0..h / p).flat_map(move |k| (0..f).map(move |j| (phi + k * p + j) % h));
        for phi in 0..p {
            if slots(phi).any(|x| occ[x]) {
                continue;
            }
            slots(phi).for_each(|x| occ[x] = true);
            ph.push(phi as u32);
            if dfs(i + 1, reqs, h, occ, ph) {
                return true;
            }
            ph.pop();
            slots(phi).for_each(|x| occ[x] = false);
        }
        false
    }
    let h = hyperperiod(s, reqs)? as usize;
    let mut occ = vec![false; h];
    for c in (0..h).step_by(s as usize) {
        occ[c] = true;
    }
    let mut ph = Vec::new();
    dfs(0, reqs, h, &mut occ, &mut ph).then_some(ph)
}

fn conflict_of(e: AdmissionError) -> Vec<usize> {
    match e {
        AdmissionError::Infeasible { conflict, len, .. } => conflict[..len as usize]
            .iter()
            .map(|&i| i as usize)
            .collect(),
        other => panic!("expected Infeasible, got {other:?}"),
    }
}

/// The paper's benchmark (§4, Table 1, Fig. 3): 60 slots per cycle (10 ms), three nodes
/// each sending H_A every 6 slots (1 ms), H_B every 30 (5 ms), H_C every 60 (10 ms), one
/// 8-byte frame each. The calendar found (S = sync, a/b/c = H_A/H_B/H_C of node 1..3):
///
/// ```text
/// slot  0         1         2         3         4         5
///       012345678901234567890123456789012345678901234567890123456789
///       SAAABBBAAACCCAAA---AAA---AAA---AAABBBAAA---AAA---AAA---AAA--
/// node   123123123123123   123   123   123123123   123   123   123
/// mask  0x038e38ff_8e38ffff  (40 of 60 bits: sync + 39 HRT slots)
/// ```
///
/// It is exactly the mask the 2014 C code's `hrt_test_1x1k_1x200_1x100` hand-computed
/// ({0x8e38ffff, 0x038e38ff}, original-rtcan-code.md §4).
#[test]
fn paper_benchmark_calendar_matches_fig3() {
    let node = [req(6, 1), req(30, 1), req(60, 1)];
    let reqs: Vec<HrtRequest> = node.iter().cycle().take(9).copied().collect();
    let mut pl = [Placement::default(); 9];
    let stats = admit(60, &reqs, &mut pl, BIG).unwrap();
    assert_eq!(stats.hyperperiod_slots, 60);
    assert_eq!(stats.reserved_slots, 39);
    let phases: Vec<u32> = pl.iter().map(|p| p.phase_slot).collect();
    // Node k's H_A at k, H_B at 3+k, H_C at 9+k.
    assert_eq!(phases, [1, 4, 10, 2, 5, 11, 3, 6, 12]);
    assert_valid(60, &reqs, &pl);
    let mut masks = [0u64; 4];
    assert_eq!(build_masks(60, &reqs, &pl, &mut masks), Ok(1));
    assert_eq!(masks[0], 0x038e_38ff_8e38_ffff);
    assert_eq!(masks[0].count_ones(), 40);
    let drawn: String = (0..60)
        .map(
            |slot| match (0..9).find(|&i| occupies(&reqs[i], pl[i], slot)) {
                None if slot == 0 => 'S',
                None => '-',
                Some(i) => ['A', 'B', 'C'][i % 3],
            },
        )
        .collect();
    assert_eq!(
        drawn,
        "SAAABBBAAACCCAAA---AAA---AAA---AAABBBAAA---AAA---AAA---AAA--"
    );
    assert!(paper_rule(&reqs).is_ok());
    assert!(harmonic_rule(&reqs).is_ok());
}

#[test]
fn identical_calls_give_identical_results() {
    let reqs = [req(12, 2), req(6, 1), req(24, 3), req(8, 1), req(12, 2)];
    let (mut a, mut b) = ([Placement::default(); 5], [Placement::default(); 5]);
    let sa = admit(24, &reqs, &mut a, BIG).unwrap();
    let sb = admit(24, &reqs, &mut b, BIG).unwrap();
    assert_eq!((sa, a), (sb, b));
    assert_valid(24, &reqs, &a);
}

#[test]
fn fragments_take_consecutive_slots() {
    // Two 3-frame messages every 10 slots, cycle of 10: 6 of 9 free slots.
    let reqs = [req(10, 3), req(10, 3), req(20, 3)];
    let mut pl = [Placement::default(); 3];
    admit(10, &reqs, &mut pl, BIG).unwrap();
    assert_eq!(pl.map(|p| p.phase_slot), [1, 4, 7]);
    assert_valid(10, &reqs, &pl);
    let mut masks = [0u64; 2];
    assert_eq!(build_masks(10, &reqs, &pl, &mut masks), Ok(2));
    assert_eq!(masks, [0b11_1111_1111, 0b00_0111_1111]);
}

#[test]
fn paper_rule_accepts_what_admit_rejects() {
    // Pairwise gcd 2 everywhere, so the paper's rule passes, and capacity is fine
    // (31 of 59 slots), but three phases cannot differ pairwise by odd amounts.
    let reqs = [req(4, 1), req(6, 1), req(10, 1)];
    assert_eq!(paper_rule(&reqs), Ok(()));
    let mut pl = [Placement::default(); 3];
    assert_eq!(
        conflict_of(admit(60, &reqs, &mut pl, BIG).unwrap_err()),
        [0, 1, 2]
    );
    assert!(brute(60, &reqs).is_none());
    // Coprime periods: both rules reject (collide at every phase).
    let coprime = [req(4, 1), req(9, 1)];
    assert_eq!(paper_rule(&coprime), Err((0, 1)));
    assert_eq!(
        conflict_of(admit(36, &coprime, &mut pl, BIG).unwrap_err()),
        [0, 1]
    );
}

#[test]
fn admit_accepts_what_the_2014_harmonic_rule_rejects() {
    // The C code required harmonic periods; 6 and 10 slots are fine with phases 1, 2.
    let reqs = [req(6, 1), req(10, 1)];
    assert_eq!(harmonic_rule(&reqs), Err((0, 1)));
    let mut pl = [Placement::default(); 2];
    admit(60, &reqs, &mut pl, BIG).unwrap();
    assert_eq!(pl.map(|p| p.phase_slot), [1, 2]);
    assert_valid(60, &reqs, &pl);
}

#[test]
fn infeasible_names_the_conflicting_requests_only() {
    // 1, 3, 4 are the parity triple above; 0 and 2 are innocent bystanders.
    let reqs = [req(60, 1), req(4, 1), req(30, 2), req(6, 1), req(10, 1)];
    let mut pl = [Placement::default(); 5];
    assert_eq!(
        conflict_of(admit(60, &reqs, &mut pl, BIG).unwrap_err()),
        [1, 3, 4]
    );
    // A pair whose runs cover every residue of gcd(6, 4) = 2.
    let reqs = [req(12, 1), req(6, 2), req(60, 3), req(4, 1)];
    assert_eq!(
        conflict_of(admit(60, &reqs, &mut pl, BIG).unwrap_err()),
        [1, 3]
    );
}

#[test]
fn over_capacity() {
    let reqs = [req(2, 1); 5];
    let mut pl = [Placement::default(); 5];
    assert_eq!(
        admit(10, &reqs, &mut pl, BIG),
        Err(AdmissionError::OverCapacity {
            reserved: 25,
            available: 9
        })
    );
    // 59 single-slot messages every cycle fill a 60-slot cycle exactly.
    let full = [req(60, 1); 59];
    let mut pl = [Placement::default(); 59];
    let stats = admit(60, &full, &mut pl, BIG).unwrap();
    assert_eq!(stats.reserved_slots, 59);
    assert_valid(60, &full, &pl);
    let mut over = full.to_vec();
    over.push(req(120, 1));
    over.push(req(120, 1));
    let mut pl = [Placement::default(); 61];
    assert_eq!(
        admit(60, &over, &mut pl, BIG),
        Err(AdmissionError::OverCapacity {
            reserved: 120,
            available: 118
        })
    );
}

#[test]
fn hyperperiod_too_long() {
    // 194 = 2·97 and 178 = 2·89 share 2 with the cycle: valid, but lcm is 517,980.
    let reqs = [req(194, 1), req(178, 1)];
    let mut pl = [Placement::default(); 2];
    assert_eq!(
        admit(60, &reqs, &mut pl, BIG),
        Err(AdmissionError::HyperperiodTooLong { slots: 517_980 })
    );
    assert_eq!(hyperperiod(60, &reqs), Some(517_980));
    assert_eq!(hyperperiod(0, &reqs), None);
    assert_eq!(hyperperiod(60, &[]), Some(60));
}

#[test]
fn too_hard_with_a_tiny_budget() {
    let node = [req(6, 1), req(30, 1), req(60, 1)];
    let reqs: Vec<HrtRequest> = node.iter().cycle().take(9).copied().collect();
    let mut pl = [Placement::default(); 9];
    // Undecided, naming the request being placed and the one its rejection came from.
    match admit(60, &reqs, &mut pl, 3) {
        Err(AdmissionError::TooHard { steps, stuck, len }) => {
            // Each order stops at its first step past its share.
            assert!((4..=6).contains(&steps), "{steps}");
            assert!(len >= 1);
            assert!(stuck[..usize::from(len)]
                .iter()
                .all(|&i| usize::from(i) < reqs.len()));
        }
        other => panic!("expected TooHard, got {other:?}"),
    }
    // The first order gets 1/16 of the budget: with 16 times what it needs the result
    // (and the phases) are those of the first order alone.
    let steps = admit(60, &reqs, &mut pl, BIG).unwrap().steps;
    let first = pl;
    assert_eq!(
        admit(60, &reqs, &mut pl, 16 * steps).map(|s| s.steps),
        Ok(steps)
    );
    assert_eq!(pl, first);
    assert!(matches!(
        admit(60, &reqs, &mut pl, steps / 2),
        Err(AdmissionError::TooHard { .. })
    ));
}

/// One period that breaks the harmony of 199 others (hrt200 with a period of 96 slots
/// where 64 was): undecided after 20 M steps when the harmonic ones went first; the
/// smallest-domain-first order places it first and admits the set.
#[test]
fn one_inharmonic_period_among_200_is_decided() {
    let mut reqs: Vec<HrtRequest> = (0..200u32)
        .map(|i| match i {
            0..40 => req(64, 1),
            40..120 => req(512, 1),
            _ => req(1024, 1),
        })
        .collect();
    reqs[4] = req(96, 1);
    let mut pl = vec![Placement::default(); reqs.len()];
    let stats = admit(64, &reqs, &mut pl, 20_000_000).unwrap();
    assert_valid(64, &reqs, &pl);
    assert!(stats.steps < 2_000_000, "{stats:?}");
    // With period 12 (or 10, 14, 18: odd classes only for the other 199, a pigeonhole
    // of 39 period-64 messages in 31 classes) no placement exists: refuted by the
    // capacity bound, with that request among the named core. Each ended "gave up
    // after 20000001 steps" before the bound.
    for period in [12, 10, 14, 18] {
        reqs[4] = req(period, 1);
        match admit(64, &reqs, &mut pl, 20_000_000) {
            Err(AdmissionError::Infeasible {
                conflict,
                len,
                size,
            }) => {
                assert!(conflict[..len as usize].contains(&4), "{period}");
                assert!(usize::from(size) > usize::from(len), "{period}");
            }
            other => panic!("period {period}: expected Infeasible, got {other:?}"),
        }
    }
}

#[test]
fn invalid_requests_and_too_many() {
    let mut pl = [Placement::default(); MAX_HRT + 1];
    let bad = |r: HrtRequest| admit(60, &[req(60, 1), r], &mut [Placement::default(); 2], BIG);
    let invalid = Err(AdmissionError::InvalidRequest { index: 1 });
    assert_eq!(bad(req(0, 1)), invalid);
    assert_eq!(bad(req(12, 0)), invalid);
    assert_eq!(bad(req(600, 129)), invalid);
    assert_eq!(bad(req(2, 3)), invalid);
    // Relatively prime to the cycle: hits a sync slot at every phase.
    assert_eq!(bad(req(7, 1)), invalid);
    // gcd(8, 60) = 4: a 4-frame run always covers a slot ≡ 0 (mod 4), hence a sync.
    assert_eq!(bad(req(8, 4)), invalid);
    assert!(bad(req(8, 3)).is_ok());
    assert_eq!(
        admit(60, &[req(60, 1); MAX_HRT + 1], &mut pl, BIG),
        Err(AdmissionError::TooMany { count: MAX_HRT + 1 })
    );
    assert_eq!(
        admit(60, &[req(60, 1); 3], &mut pl[..2], BIG),
        Err(AdmissionError::TooMany { count: 3 })
    );
    assert_eq!(admit(60, &[], &mut pl, 0).map(|s| s.reserved_slots), Ok(0));
}

#[test]
fn occupies_by_definition() {
    let r = req(10, 3);
    let p = Placement { phase_slot: 8 };
    let hits: Vec<u64> = (0..40).filter(|&s| occupies(&r, p, s)).collect();
    assert_eq!(hits, [8, 9, 10, 18, 19, 20, 28, 29, 30, 38, 39]);
    assert!(!occupies(&req(0, 1), p, 8));
}

#[test]
fn build_masks_rejects_colliding_placements_and_short_buffers() {
    let reqs = [req(6, 1), req(30, 2), req(60, 1)];
    let pl = [
        Placement { phase_slot: 1 },
        Placement { phase_slot: 12 },
        Placement { phase_slot: 13 },
    ];
    let mut masks = [0u64; 1];
    assert_eq!(
        conflict_of(build_masks(60, &reqs, &pl, &mut masks).unwrap_err()),
        [0, 1]
    );
    let pl = [
        Placement { phase_slot: 1 },
        Placement { phase_slot: 2 },
        Placement { phase_slot: 0 },
    ];
    assert_eq!(
        conflict_of(build_masks(60, &reqs, &pl, &mut masks).unwrap_err()),
        [2]
    );
    let reqs = [req(120, 1)];
    let pl = [Placement { phase_slot: 61 }];
    assert_eq!(
        build_masks(60, &reqs, &pl, &mut masks),
        Err(AdmissionError::TooMany { count: 2 })
    );
    let mut masks = [0u64; 2];
    assert_eq!(build_masks(60, &reqs, &pl, &mut masks), Ok(2));
    assert_eq!(masks, [1, 0b11]);
}

#[test]
fn suggested_periods_are_admissible_nearest_first() {
    // The paper's set plus a request every 7 slots (relatively prime to 60: invalid).
    let node = [req(6, 1), req(30, 1), req(60, 1)];
    let mut reqs: Vec<HrtRequest> = node.iter().cycle().take(9).copied().collect();
    reqs.push(req(7, 1));
    let mut pl = [Placement::default(); 10];
    assert_eq!(
        admit(60, &reqs, &mut pl, BIG),
        Err(AdmissionError::InvalidRequest { index: 9 })
    );
    let mut out = [0u32; 4];
    let n = suggest_periods(60, &reqs, 9, &mut out);
    assert_eq!(n, 4);
    for &p in &out[..n] {
        let mut trial = reqs.clone();
        trial[9].period_slots = p;
        assert!(admit(60, &trial, &mut pl, BIG).is_ok(), "period {p}");
    }
    // Every period nearer than the last suggestion that is not suggested is refused.
    let reach = out[..n].iter().map(|&p| p.abs_diff(7)).max().unwrap();
    for p in 7 - reach.min(6)..=7 + reach {
        let mut trial = reqs.clone();
        trial[9].period_slots = p;
        let ok = admit(60, &trial, &mut pl, BIG).is_ok();
        assert_eq!(ok, out[..n].contains(&p), "period {p}");
    }
    // Ordered by distance, shorter first on ties.
    let key = |p: u32| (p.abs_diff(7), p > 7);
    assert!(
        out[..n].windows(2).all(|w| key(w[0]) < key(w[1])),
        "{out:?}"
    );
    // 9 works with H_A at 2, 3, 5 and H_B at 6, 12, 18 (all clear of 9k + 1).
    assert_eq!(out, [6, 9, 10, 3]);
    assert_eq!(suggest_periods(60, &reqs, 10, &mut out), 0);
}

/// 200 harmonic topics on a 64-slot cycle, 476 of 504 slots per hyperperiod (the bench's set).
#[test]
fn harmonic_200_topics_on_64_slots() {
    let reqs: Vec<HrtRequest> = (0..200u32)
        .map(|i| match i {
            0..8 => req(64, 2),
            8..24 => req(128, 1),
            24..64 => req(256, 1),
            _ => req(512, 1 + (i % 2) as u8),
        })
        .collect();
    let mut pl = vec![Placement::default(); 200];
    let stats = admit(64, &reqs, &mut pl, BIG).unwrap();
    assert_valid(64, &reqs, &pl);
    let mut masks = [0u64; 8];
    assert_eq!(build_masks(64, &reqs, &pl, &mut masks), Ok(8));
    let reserved: u32 = masks.iter().map(|m| m.count_ones() - 1).sum();
    assert_eq!(u64::from(reserved), stats.reserved_slots);
}

/// Small instances: a fifth fully random (mostly invalid: periods prime to the cycle),
/// the rest with periods sharing a factor with the cycle so that most are valid and
/// the interesting cases (tight, fragmented, infeasible) are common.
fn small_instance() -> impl Strategy<Value = (u32, Vec<HrtRequest>)> {
    let random = {
        let r = (1u32..=12, 1u8..=3).prop_map(|(p, f)| req(p, f));
        (2u32..=8, prop::collection::vec(r, 1..=5))
    };
    let related = (
        prop::sample::select(vec![4u32, 6, 8, 9, 10, 12]),
        prop::collection::vec((0usize..8, 1u32..=4, 1u8..=3), 2..=6),
    )
        .prop_map(|(s, v)| {
            let divisors: Vec<u32> = (2..=s).filter(|d| s % d == 0).collect();
            let reqs = v
                .into_iter()
                .map(|(d, m, f)| req(divisors[d % divisors.len()] * m, f))
                .collect();
            (s, reqs)
        });
    prop_oneof![1 => random, 4 => related]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, max_global_rejects: 100_000, ..ProptestConfig::default() })]

    /// Both ways against brute force: an admitted set is valid, a refused set has no
    /// placement at all, and the reported conflict is itself infeasible and minimal.
    #[test]
    fn admit_agrees_with_brute_force((s, reqs) in small_instance()) {
        prop_assume!(hyperperiod(s, &reqs).is_some_and(|h| h <= 5000));
        let mut pl = vec![Placement::default(); reqs.len()];
        let truth = brute(s, &reqs);
        match admit(s, &reqs, &mut pl, BIG) {
            Ok(stats) => {
                prop_assert!(truth.is_some());
                assert_valid(s, &reqs, &pl);
                prop_assert!(stats.steps <= BIG);
                // Necessary condition the paper states: never violated by an admitted set.
                prop_assert_eq!(paper_rule(&reqs), Ok(()));
            }
            Err(AdmissionError::Infeasible { conflict, len, .. }) => {
                prop_assert!(truth.is_none());
                let core: Vec<HrtRequest> = conflict[..len as usize].iter().map(|&i| reqs[i as usize]).collect();
                prop_assert!(core.len() >= 2);
                prop_assert!(brute(s, &core).is_none(), "core {:?} is feasible", core);
                for skip in 0..core.len() {
                    let mut sub = core.clone();
                    sub.remove(skip);
                    prop_assert!(brute(s, &sub).is_some(), "core {:?} not minimal", core);
                }
            }
            Err(AdmissionError::InvalidRequest { index }) => {
                prop_assert!(truth.is_none());
                prop_assert!(brute(s, &reqs[index..=index]).is_none());
            }
            Err(AdmissionError::OverCapacity { reserved, available }) => {
                prop_assert!(truth.is_none());
                prop_assert!(reserved > available);
            }
            Err(e) => prop_assert!(false, "unexpected {:?}", e),
        }
    }
}

/// The random instances above exercise every outcome, not just the easy ones.
#[test]
fn random_instances_cover_every_outcome() {
    use proptest::strategy::ValueTree;
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let mut seen = [0u32; 4]; // ok, infeasible, invalid, over capacity
    for _ in 0..1000 {
        let (s, reqs) = small_instance().new_tree(&mut runner).unwrap().current();
        if hyperperiod(s, &reqs).is_none_or(|h| h > 5000) {
            continue;
        }
        let mut pl = vec![Placement::default(); reqs.len()];
        match admit(s, &reqs, &mut pl, BIG) {
            Ok(_) => seen[0] += 1,
            Err(AdmissionError::Infeasible { .. }) => seen[1] += 1,
            Err(AdmissionError::InvalidRequest { .. }) => seen[2] += 1,
            Err(AdmissionError::OverCapacity { .. }) => seen[3] += 1,
            Err(e) => panic!("unexpected {e:?}"),
        }
    }
    eprintln!("ok/infeasible/invalid/over-capacity: {seen:?}");
    assert!(seen.iter().all(|&n| n >= 30), "{seen:?}");
}
