//! The fault campaign (`rtcan sim --campaign`): the Triskar2 robot and the RTCAN paper's
//! benchmark under bit errors, a dying and returning master, a master absent from
//! start-up, module resets and large clock drift, each run measured the same way.
//!
//! Every run streams its figures (memory bounded by the robot, not the run's length).
//! What each column means is in `Row`; what the campaign does not (yet) inject — a bus
//! guardian against the babbling idiot, a stuck-dominant node, clock steps, partitions —
//! it does not list.
use rtcan_core::engine::Policy;
use rtcan_model::Plan;

use crate::fault;
use crate::paper;
use crate::policy::PolicyKind;
use crate::run::{run_engine, SimConfig};
use crate::triskar::{self, TriskarConfig, MODULES};

/// One campaign case.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Short name (stable: the JSON key `case`).
    pub name: &'static str,
    /// `triskar2` or `rtcan-paper`.
    pub scenario: &'static str,
    /// Bit error rate.
    pub ber: f64,
    /// Largest slave clock drift, ppm.
    pub drift_ppm: f64,
    /// Scripted faults (triskar2), `fault::parse` syntax.
    pub faults: &'static [&'static str],
    /// The robot must be in its safe state at the end (its command source is gone).
    pub safe_expected: bool,
}

/// The cases, in table order.
pub fn cases() -> Vec<Case> {
    let t = |name, ber, drift_ppm, faults, safe_expected| Case {
        name,
        scenario: "triskar2",
        ber,
        drift_ppm,
        faults,
        safe_expected,
    };
    let p = |name, ber| Case {
        name,
        scenario: "rtcan-paper",
        ber,
        drift_ppm: 50.0,
        faults: &[],
        safe_expected: false,
    };
    vec![
        t("nominal", 0.0, 50.0, &[], false),
        t("ber-1e-6", 1e-6, 50.0, &[], false),
        t("ber-1e-5", 1e-5, 50.0, &[], false),
        t("ber-1e-4", 1e-4, 50.0, &[], false),
        t("ber-1e-3", 1e-3, 50.0, &[], false),
        t(
            "master-dies-2s-returns-5s",
            0.0,
            50.0,
            &["gateway:dies@2s", "gateway:returns@5s"],
            false,
        ),
        t("master-dies-2s", 0.0, 50.0, &["gateway:dies@2s"], true),
        // The backup takes over and every module leaves the start-up safe state (no
        // sync); the robot never got a command, so it stands still with motors enabled.
        t(
            "master-absent-from-start",
            0.0,
            50.0,
            &["gateway:dies@10ms"],
            false,
        ),
        t(
            "backup-dies-during-takeover",
            0.0,
            50.0,
            &["gateway:dies@2s", "motor1:dies@2030ms"],
            true,
        ),
        t(
            "babbling-idiot-from-1s",
            0.0,
            50.0,
            &["motor3:babble@1s"],
            true,
        ),
        t("module-reset", 0.0, 50.0, &["motor2:reset@3200ms"], false),
        t("master-reset", 0.0, 50.0, &["gateway:reset@3200ms"], false),
        t("drift-1000ppm", 0.0, 1000.0, &[], false),
        p("paper-nominal", 0.0),
        p("paper-ber-1e-6", 1e-6),
        p("paper-ber-1e-5", 1e-5),
        p("paper-ber-1e-4", 1e-4),
        p("paper-ber-1e-3", 1e-3),
    ]
}

/// Figures of one case.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub case: Case,
    /// Simulated seconds.
    pub seconds: f64,
    /// HRT frames seen and occurrences without a frame (all topics); per topic in
    /// `hrt_topics` as (name, frames, missed).
    pub hrt_frames: u64,
    pub hrt_missed: u64,
    pub hrt_topics: Vec<(String, u64, u64)>,
    /// SRT messages measured and deadline misses.
    pub srt_count: u64,
    pub srt_misses: u64,
    /// Delivered messages whose content did not check (rtcan-paper: identity payloads;
    /// `None` where payloads carry no identity, triskar2).
    pub bad_deliveries: Option<u64>,
    /// Transfers the engines dropped as incomplete or mixed (`rx_incomplete` +
    /// `rx_other_transfer`).
    pub transfers_dropped: u64,
    /// Error frames on the bus.
    pub error_frames: u64,
    /// Bus-off entries over every engine.
    pub bus_off: u64,
    /// Cycles with two syncs (`sync_watch`; triskar2 only, the paper runner does not
    /// watch the wire).
    pub doubled_syncs: Option<u64>,
    /// Frames outside their slot or window as the sync on the wire places them, whoever
    /// the master (`sync_watch::SlotCheck`; triskar2).
    pub slot_violations: Option<u64>,
    /// Longest time without a sync, ms (the outage of a takeover: detection + recovery).
    pub longest_sync_gap_ms: Option<f64>,
    /// Modules sending the sync at the end (triskar2).
    pub masters_at_end: Vec<&'static str>,
    /// Safe-state entries over every module, and modules in safe state at the end.
    pub safe_trips: u32,
    pub safe_at_end: u32,
    /// The safe state matched `case.safe_expected` at the end (triskar2).
    pub safe_as_expected: Option<bool>,
}

/// Runs one case with `base`'s length, seed and CPU model.
pub fn run_case(plan: &Plan, case: &Case, base: &SimConfig) -> Result<Row, String> {
    let seconds = base.seconds;
    let sim = SimConfig {
        bit_error_rate: case.ber,
        drift_ppm: case.drift_ppm,
        record_wire: false,
        wire_log: None,
        ..base.clone()
    };
    if case.scenario == "rtcan-paper" {
        let sc = paper::scenario(paper::our_laxity(), 1.0)?;
        let run = run_engine(&sc, &sim, PolicyKind::Ours, Policy::OURS)?;
        let f = &run.figures;
        return Ok(Row {
            case: case.clone(),
            seconds,
            hrt_frames: f.hrt.iter().map(|h| h.count).sum(),
            hrt_missed: f.hrt.iter().map(|h| h.misses).sum(),
            hrt_topics: f
                .hrt
                .iter()
                .map(|h| (h.name.clone(), h.count, h.misses))
                .collect(),
            srt_count: f.srt.iter().map(|s| s.count).sum(),
            srt_misses: f.srt.iter().map(|s| s.misses).sum(),
            bad_deliveries: Some(run.rx_bad),
            transfers_dropped: run
                .counters
                .iter()
                .map(|c| u64::from(c.rx_incomplete) + u64::from(c.rx_other_transfer))
                .sum(),
            error_frames: run.bus.error_frames,
            bus_off: run.counters.iter().map(|c| u64::from(c.bus_off)).sum(),
            doubled_syncs: None,
            slot_violations: None,
            longest_sync_gap_ms: None,
            masters_at_end: Vec::new(),
            safe_trips: 0,
            safe_at_end: 0,
            safe_as_expected: None,
        });
    }
    let cfg = TriskarConfig {
        sim,
        faults: case
            .faults
            .iter()
            .map(|f| fault::parse(f, &MODULES))
            .collect::<Result<_, _>>()?,
        ..TriskarConfig::default()
    };
    let r = triskar::run(plan, &cfg)?;
    let f = &r.run.figures;
    let safe_at_end = r.modules.iter().filter(|m| m.safe_now).count() as u32;
    Ok(Row {
        case: case.clone(),
        seconds,
        hrt_frames: f.hrt.iter().map(|h| h.count).sum(),
        hrt_missed: f.hrt.iter().map(|h| h.misses).sum(),
        hrt_topics: f
            .hrt
            .iter()
            .map(|h| (h.name.clone(), h.count, h.misses))
            .collect(),
        srt_count: f.srt.iter().map(|s| s.count).sum(),
        srt_misses: f.srt.iter().map(|s| s.misses).sum(),
        bad_deliveries: None,
        transfers_dropped: r
            .modules
            .iter()
            .map(|m| u64::from(m.counters.rx_incomplete) + u64::from(m.counters.rx_other_transfer))
            .sum(),
        error_frames: r.run.bus.error_frames,
        bus_off: r
            .modules
            .iter()
            .map(|m| u64::from(m.counters.bus_off))
            .sum(),
        doubled_syncs: Some(r.syncs.doubled),
        slot_violations: Some(r.slots_live.0),
        longest_sync_gap_ms: Some(r.syncs.longest_gap.0 as f64 / 1e6),
        masters_at_end: r
            .modules
            .iter()
            .filter(|m| m.master)
            .map(|m| m.name)
            .collect(),
        safe_trips: r.modules.iter().map(|m| m.safe_trips).sum(),
        safe_at_end,
        safe_as_expected: Some((safe_at_end > 0) == case.safe_expected),
    })
}

/// Runs every case; `progress(done, total)` after each.
pub fn run(
    plan: &Plan,
    base: &SimConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<Row>, String> {
    let all = cases();
    let mut out = Vec::with_capacity(all.len());
    for (k, c) in all.iter().enumerate() {
        out.push(run_case(plan, c, base)?);
        progress(k + 1, all.len());
    }
    Ok(out)
}

/// The campaign as a Markdown table.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| case | scenario | HRT frames / missed | SRT msgs / misses | bad deliveries | transfers dropped | error frames | bus-off | cycles with 2 syncs | slot violations | longest sync gap [ms] | masters at end | safe trips / safe at end (as expected) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} / {} | {} / {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.case.name,
            r.case.scenario,
            r.hrt_frames,
            r.hrt_missed,
            r.srt_count,
            r.srt_misses,
            r.bad_deliveries.map_or("n/a".into(), |b| b.to_string()),
            r.transfers_dropped,
            r.error_frames,
            r.bus_off,
            r.doubled_syncs.map_or("n/a".into(), |d| d.to_string()),
            r.slot_violations.map_or("n/a".into(), |d| d.to_string()),
            r.longest_sync_gap_ms
                .map_or("n/a".into(), |g| format!("{g:.1}")),
            if r.masters_at_end.is_empty() {
                "-".to_string()
            } else {
                r.masters_at_end.join(" ")
            },
            match r.safe_as_expected {
                Some(ok) => format!(
                    "{} / {} ({})",
                    r.safe_trips,
                    r.safe_at_end,
                    if ok { "yes" } else { "NO" }
                ),
                None => "-".into(),
            },
        ));
    }
    s
}

fn esc(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"")
}

/// The campaign as JSON (one object per case).
pub fn json(rows: &[Row]) -> String {
    let items: Vec<String> = rows
        .iter()
        .map(|r| {
            let topics: Vec<String> = r
                .hrt_topics
                .iter()
                .map(|(n, c, m)| {
                    format!("{{\"name\":\"{}\",\"frames\":{c},\"missed\":{m}}}", esc(n))
                })
                .collect();
            format!(
                "{{\"case\":\"{}\",\"scenario\":\"{}\",\"seconds\":{},\"ber\":{},\"drift_ppm\":{},\"faults\":[{}],\"hrt_frames\":{},\"hrt_missed\":{},\"hrt\":[{}],\"srt_count\":{},\"srt_misses\":{},\"bad_deliveries\":{},\"transfers_dropped\":{},\"error_frames\":{},\"bus_off\":{},\"doubled_syncs\":{},\"slot_violations\":{},\"longest_sync_gap_ms\":{},\"masters_at_end\":[{}],\"safe_trips\":{},\"safe_at_end\":{},\"safe_as_expected\":{}}}",
                r.case.name,
                r.case.scenario,
                r.seconds,
                r.case.ber,
                r.case.drift_ppm,
                r.case.faults.iter().map(|f| format!("\"{}\"", esc(f))).collect::<Vec<_>>().join(","),
                r.hrt_frames,
                r.hrt_missed,
                topics.join(","),
                r.srt_count,
                r.srt_misses,
                r.bad_deliveries.map_or("null".into(), |b| b.to_string()),
                r.transfers_dropped,
                r.error_frames,
                r.bus_off,
                r.doubled_syncs.map_or("null".into(), |d| d.to_string()),
                r.slot_violations.map_or("null".into(), |d| d.to_string()),
                r.longest_sync_gap_ms.map_or("null".into(), |g| format!("{g:.3}")),
                r.masters_at_end.iter().map(|m| format!("\"{m}\"")).collect::<Vec<_>>().join(","),
                r.safe_trips,
                r.safe_at_end,
                r.safe_as_expected.map_or("null".into(), |b| b.to_string()),
            )
        })
        .collect();
    format!("{{\"campaign\":[{}]}}\n", items.join(","))
}
