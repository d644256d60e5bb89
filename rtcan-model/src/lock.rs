//! `robot.lock`: the allocation of a robot.toml, kept stable across edits (like
//! Cargo.lock). It records every topic's message ID and wire layout, every HRT phase,
//! every module's index and CAN filter banks, and the IDs of removed topics (never
//! reused, so an old image can never misread a new topic). Planning with a lock keeps all
//! of that and allocates only what is new into IDs and slots no existing module's
//! filters or calendar touch; when something must move (a topic's layout or period
//! changed, a new HRT topic does not fit around the locked phases, a module was inserted
//! before others) the move is reported with its reason (`Plan::moves`).
//!
//! Written by `rtcan check --update-lock`; read by build.rs, `rtcan::robot!`, the CLI and
//! the simulator through [`crate::read_analysis`] / [`crate::Robot::load`] (the lock is
//! the file next to robot.toml with the extension `.lock`). docs/ROBOT_TOML.md §robot.lock.
use crate::diag::{Code, Diagnostic};
use crate::filters::{Bank, BankPurpose, FilterBank, WireTopic, LAXITY_MASK, MSG_SHIFT};
use crate::model::Model;
use crate::plan::Plan;
use crate::schedule::{Admitted, HrtTopic};
use rtcan_core::admission::{self, AdmitStats, HrtRequest, Placement, MAX_HYPERPERIOD_SLOTS};
use rtcan_core::id::FIRST_TOPIC_MSG_ID;
use rtcan_core::Class;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Format version written in the first line.
pub const VERSION: u32 = 1;

/// One topic as locked.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LockedTopic {
    /// Topic name.
    pub name: String,
    /// Message ID.
    pub msg_id: u16,
    /// Wire layout (`Type{field:ty,..}/size/class/fragments`): what a receiver decodes.
    pub layout: String,
    /// HRT: period in slots.
    pub period: Option<u32>,
    /// HRT on the bus: phase slot.
    pub phase: Option<u32>,
}

/// A parsed robot.lock.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Lock {
    /// Identity of the allocation history: fixed when the lock is first written, carried
    /// (with the bus parameters) in the heartbeat fingerprint.
    pub lineage: u32,
    /// Module name → index.
    pub modules: BTreeMap<String, u8>,
    /// Topics by name.
    pub topics: BTreeMap<String, LockedTopic>,
    /// IDs of removed or re-laid-out topics: never handed out again.
    pub retired: BTreeSet<u16>,
    /// What a retired ID carried, where the lock recorded it (`retired ID NAME LAYOUT`;
    /// locks written before round 7 have bare IDs): the host tools name the topic of a
    /// stale image's frame by it.
    pub retired_topics: BTreeMap<u16, (String, String)>,
    /// Module name → filter banks in bank order.
    pub banks: BTreeMap<String, Vec<FilterBank>>,
}

/// A topic ID the lock retired, or that a plan made with the lock retires (a topic
/// removed or re-laid out since): only an image built before that change still sends it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Retired {
    /// The retired message ID.
    pub msg_id: u16,
    /// The topic that carried it (empty if the lock has the bare ID).
    pub name: String,
    /// Its wire layout then (empty if unknown).
    pub layout: String,
    /// The same topic in the plan: message ID and layout (`None`: removed).
    pub now: Option<(u16, String)>,
}

/// The IDs an image built from an older robot.toml of `lock`'s history may still send and
/// this plan's modules do not: the lock's retired IDs and the locked topics whose IDs the
/// plan (`topics`, laid out as `layout_of(i)`) no longer uses, each with the topic it
/// carried and that topic's ID and layout now.
pub fn retired_in_plan(
    lock: &Lock,
    topics: &[(String, u16)],
    layout_of: &dyn Fn(usize) -> String,
) -> Vec<Retired> {
    let mut out: BTreeMap<u16, (String, String)> = lock
        .retired
        .iter()
        .map(|&id| {
            (
                id,
                lock.retired_topics.get(&id).cloned().unwrap_or_default(),
            )
        })
        .collect();
    for t in lock.topics.values() {
        if !topics.iter().any(|(_, id)| *id == t.msg_id) {
            out.insert(t.msg_id, (t.name.clone(), t.layout.clone()));
        }
    }
    out.into_iter()
        .map(|(msg_id, (name, layout))| {
            let now = topics
                .iter()
                .position(|(n, _)| !name.is_empty() && *n == name)
                .and_then(|i| topics.get(i).map(|(_, id)| (*id, layout_of(i))));
            Retired {
                msg_id,
                name,
                layout,
                now,
            }
        })
        .collect()
}

/// Something the lock held that the new plan had to change.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Move {
    /// Topic or module name.
    pub subject: String,
    /// `msg_id`, `phase`, `filters` or `module-index`.
    pub what: &'static str,
    /// Locked value.
    pub from: String,
    /// New value.
    pub to: String,
    /// Why it had to move.
    pub reason: String,
}

/// The lock file of a robot description: same path, extension `.lock`.
pub fn path_for(toml: &Path) -> PathBuf {
    toml.with_extension("lock")
}

/// Wire layout of topic `i`: type with fields, payload size, class and fragment count.
pub fn layout(model: &Model, i: usize) -> String {
    let Some(t) = model.topics.get(i) else {
        return String::new();
    };
    let ty = model.types.get(t.ty);
    let fields: Vec<String> = ty
        .map(|ty| {
            ty.fields
                .iter()
                .map(|f| format!("{}:{}", f.name, f.ty.rust().replace(' ', "")))
                .collect()
        })
        .unwrap_or_default();
    let size = model.topic_size(t);
    format!(
        "{}{{{}}}/{size}/{}/{}",
        ty.map_or("?", |x| x.name.as_str()),
        fields.join(","),
        class_name(t.class),
        rtcan_core::fragment::fragment_count(size)
    )
}

fn class_name(c: Class) -> &'static str {
    match c {
        Class::Hrt => "hrt",
        Class::Srt => "srt",
        Class::Nrt => "nrt",
    }
}

fn parse_num(s: &str) -> Option<u64> {
    match s.strip_prefix("0x") {
        Some(h) => u64::from_str_radix(h, 16).ok(),
        None => s.parse().ok(),
    }
}

/// Parses robot.lock text; an error names `file:line:col` and says how to recover.
pub fn parse(file: &str, text: &str) -> Result<Lock, Diagnostic> {
    let mut lock = Lock::default();
    let mut version = None;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some(first) = words.first() else { continue };
        let col = raw.find(first).map_or(1, |c| c + 1);
        let bad = |what: &str| {
            Diagnostic::new(
                Code::LockInvalid,
                None,
                format!("{file}:{}:{col}: {what}: `{}`", n + 1, raw.trim()),
            )
            .help(format!(
                "`{file}` is written by `rtcan check --update-lock`; restore it from version control, or delete it to allocate afresh (every module image then changes)"
            ))
        };
        let word = |k: usize| words.get(k).copied().unwrap_or("");
        let num = |k: usize, max: u64| {
            words
                .get(k)
                .and_then(|w| parse_num(w))
                .filter(|v| *v <= max)
        };
        match (*first, words.len()) {
            ("version", 2) => match num(1, u64::from(u32::MAX)) {
                Some(v) if v == u64::from(VERSION) => version = Some(v),
                _ => return Err(bad("unsupported lock version")),
            },
            ("lineage", 2) => {
                lock.lineage = num(1, u64::from(u32::MAX)).ok_or_else(|| bad("bad lineage"))? as u32
            }
            ("module", 3) => {
                let i = num(2, 63).ok_or_else(|| bad("bad module index"))? as u8;
                lock.modules.insert(word(1).to_string(), i);
            }
            ("topic", 4..=6) => {
                let msg_id = num(2, 0xFFFF)
                    .filter(|v| *v >= u64::from(FIRST_TOPIC_MSG_ID))
                    .ok_or_else(|| bad("bad message ID (topics use 0x0140..=0xffff)"))?
                    as u16;
                let mut t = LockedTopic {
                    name: word(1).to_string(),
                    msg_id,
                    layout: word(3).to_string(),
                    period: None,
                    phase: None,
                };
                for w in words.iter().skip(4) {
                    let v = |p: &str| {
                        w.strip_prefix(p)
                            .and_then(parse_num)
                            .filter(|v| *v <= MAX_HYPERPERIOD_SLOTS)
                            .map(|v| v as u32)
                    };
                    match (v("period="), v("phase=")) {
                        (Some(p), _) => t.period = Some(p),
                        (_, Some(p)) => t.phase = Some(p),
                        _ => return Err(bad("bad topic attribute")),
                    }
                }
                if lock.topics.insert(t.name.clone(), t).is_some() {
                    return Err(bad("topic locked twice"));
                }
            }
            ("retired", 2 | 4) => {
                let id = num(1, 0xFFFF)
                    .filter(|v| *v >= u64::from(FIRST_TOPIC_MSG_ID))
                    .ok_or_else(|| bad("bad message ID (topics use 0x0140..=0xffff)"))?
                    as u16;
                if !lock.retired.insert(id) {
                    return Err(bad("ID retired twice"));
                }
                if words.len() == 4 {
                    lock.retired_topics
                        .insert(id, (word(2).to_string(), word(3).to_string()));
                }
            }
            ("bank", 5) => {
                let a = num(3, 0x1FFF_FFFF).ok_or_else(|| bad("bad identifier"))? as u32;
                let b = num(4, 0x1FFF_FFFF).ok_or_else(|| bad("bad identifier"))? as u32;
                let f = match word(2) {
                    "mask" => FilterBank::Mask { id: a, mask: b },
                    "list" => FilterBank::List { ids: [a, b] },
                    _ => return Err(bad("bank kind must be `mask` or `list`")),
                };
                lock.banks.entry(word(1).to_string()).or_default().push(f);
            }
            _ => return Err(bad("unknown line")),
        }
    }
    if version.is_none() {
        return Err(Diagnostic::new(
            Code::LockInvalid,
            None,
            format!("{file}:1:1: missing `version {VERSION}` line"),
        )
        .help("restore the lock from version control or delete it to allocate afresh"));
    }
    Ok(lock)
}

/// The lock that records `plan` (`model` is the model it was planned from). Retired IDs
/// of `prev` stay retired, and its locked topics that are gone are retired too.
pub fn render(model: &Model, plan: &Plan, prev: Option<&Lock>) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Allocation of {} (message IDs, HRT phases, module indices, CAN filters).\n# Written by `rtcan check --update-lock`; commit it. docs/ROBOT_TOML.md#robotlock",
        plan.file
    );
    let _ = writeln!(s, "version {VERSION}");
    let lineage = plan.lineage.unwrap_or(plan.fingerprint);
    let _ = writeln!(s, "lineage {lineage:#010x}");
    for m in &plan.modules {
        let _ = writeln!(s, "module {} {}", m.name, m.index);
    }
    for (i, t) in plan.topics.iter().enumerate() {
        let _ = write!(
            s,
            "topic {} {:#06x} {}",
            t.name,
            t.msg_id.0,
            layout(model, i)
        );
        if let Some(p) = t.period_slots {
            let _ = write!(s, " period={p}");
        }
        if let Some(p) = t.phase_slot {
            let _ = write!(s, " phase={p}");
        }
        s.push('\n');
    }
    // Each retired ID with the topic it carried, so the host tools can name the topic of
    // a stale image's frame (`rtcan monitor`, `rtcan decode`).
    let topics: Vec<(String, u16)> = plan
        .topics
        .iter()
        .map(|t| (t.name.clone(), t.msg_id.0))
        .collect();
    let retired = prev.map_or_else(Vec::new, |p| {
        retired_in_plan(p, &topics, &|_| String::new())
    });
    for r in retired {
        let _ = if r.name.is_empty() {
            writeln!(s, "retired {:#06x}", r.msg_id)
        } else {
            writeln!(s, "retired {:#06x} {} {}", r.msg_id, r.name, r.layout)
        };
    }
    for m in &plan.modules {
        for b in &m.banks {
            let _ = match b.filter {
                FilterBank::Mask { id, mask } => {
                    writeln!(s, "bank {} mask {id:#010x} {mask:#010x}", m.name)
                }
                FilterBank::List { ids: [a, b] } => {
                    writeln!(s, "bank {} list {a:#010x} {b:#010x}", m.name)
                }
            };
        }
    }
    s
}

fn fixed_laxity(w: &WireTopic) -> Option<u32> {
    w.fixed_id.map(|f| f & LAXITY_MASK)
}

/// Some frame of `w` passes `f`.
pub fn may_pass(f: &FilterBank, w: &WireTopic) -> bool {
    let msg = u32::from(w.msg_id) << MSG_SHIFT;
    match *f {
        FilterBank::Mask { id, mask } => {
            let lax = fixed_laxity(w).unwrap_or(id & LAXITY_MASK);
            ((msg | lax) & mask) == (id & mask)
        }
        FilterBank::List { ids } => ids
            .iter()
            .any(|x| (x & !LAXITY_MASK) >> MSG_SHIFT == u32::from(w.msg_id) && x & 0x7F == 0),
    }
}

/// Every frame of `w` passes `f`.
pub fn always_passes(f: &FilterBank, w: &WireTopic) -> bool {
    let msg = u32::from(w.msg_id) << MSG_SHIFT;
    match *f {
        FilterBank::Mask { id, mask } => match fixed_laxity(w) {
            Some(lax) => ((msg | lax) & mask) == (id & mask),
            None => mask & (LAXITY_MASK | 0x7F) == 0 && (msg & mask) == (id & mask),
        },
        FilterBank::List { ids } => w.fixed_id.is_some_and(|x| ids.contains(&x)),
    }
}

/// Locked banks of a module, if they still pass exactly `wanted` among `all`; `Err` with
/// the reason otherwise.
pub fn reuse_banks(
    locked: &[FilterBank],
    wanted: &[WireTopic],
    all: &[WireTopic],
    names: &dyn Fn(usize) -> String,
) -> Result<Vec<Bank>, String> {
    let is_wanted = |w: &WireTopic| wanted.iter().any(|x| x.topic == w.topic);
    for w in all {
        if is_wanted(w) && !locked.iter().any(|f| always_passes(f, w)) {
            return Err(format!("now receives `{}`", names(w.topic)));
        }
        if !is_wanted(w) && locked.iter().any(|f| may_pass(f, w)) {
            return Err(format!(
                "its filters would pass `{}`, which it does not receive",
                names(w.topic)
            ));
        }
    }
    let sync = crate::filters::sync_bank();
    let hb = crate::filters::heartbeat_bank();
    Ok(locked
        .iter()
        .map(|f| Bank {
            filter: *f,
            purpose: if *f == sync.filter {
                BankPurpose::Sync
            } else if *f == hb.filter {
                BankPurpose::Heartbeat
            } else {
                BankPurpose::Topics(
                    wanted
                        .iter()
                        .filter(|w| may_pass(f, w))
                        .map(|w| w.topic)
                        .collect(),
                )
            },
        })
        .collect())
}

/// Message IDs with a lock: locked topics with an unchanged layout keep their ID; the
/// others get the lowest free ID that no locked module's filters pass unless it receives
/// the topic (preferring one its receivers' filters already pass). `None` when the ID
/// space is exhausted.
pub fn assign_ids(model: &Model, lock: &Lock, moves: &mut Vec<Move>) -> Option<Vec<u16>> {
    let mut used: BTreeSet<u16> = lock.retired.clone();
    used.extend(lock.topics.values().map(|t| t.msg_id));
    let mut ids: Vec<Option<u16>> = vec![None; model.topics.len()];
    let mut kept: BTreeSet<u16> = BTreeSet::new();
    let mut relaid: Vec<(usize, &LockedTopic)> = Vec::new();
    for (i, t) in model.topics.iter().enumerate() {
        let Some(lt) = lock.topics.get(&t.name) else {
            continue;
        };
        if lt.layout == layout(model, i) && kept.insert(lt.msg_id) {
            if let Some(x) = ids.get_mut(i) {
                *x = Some(lt.msg_id);
            }
        } else {
            relaid.push((i, lt));
        }
    }
    let mut fresh: Vec<usize> = (0..model.topics.len())
        .filter(|i| ids.get(*i).is_some_and(|x| x.is_none()))
        .collect();
    fresh.sort_by_key(|i| {
        let t = model.topics.get(*i);
        (
            t.map_or(3, |t| t.class as u8),
            t.map_or("", |t| t.name.as_str()),
        )
    });
    let module_of = |name: &str| model.modules.iter().position(|m| m.name == name);
    let ceiling = used
        .iter()
        .next_back()
        .copied()
        .unwrap_or(FIRST_TOPIC_MSG_ID);
    for i in fresh {
        let t = model.topics.get(i)?;
        let on_bus = model.on_bus(t);
        let receivers: Vec<usize> = if on_bus {
            crate::ids::receivers(model, i)
        } else {
            Vec::new()
        };
        let frags = rtcan_core::fragment::fragment_count(model.topic_size(t));
        let wire = |msg_id: u16| WireTopic {
            topic: i,
            msg_id,
            fixed_id: match (t.class, frags) {
                (Class::Hrt, 1) => {
                    Some(crate::filters::fixed_id(rtcan_core::id::LAXITY_HRT, msg_id))
                }
                (Class::Nrt, 1) => {
                    Some(crate::filters::fixed_id(rtcan_core::id::LAXITY_NRT, msg_id))
                }
                _ => None,
            },
        };
        // (module index, banks) of locked modules still in the robot.
        let locked: Vec<(usize, &Vec<FilterBank>)> = lock
            .banks
            .iter()
            .filter_map(|(n, b)| module_of(n).map(|m| (m, b)))
            .collect();
        let clean = |id: u16, exact: bool| {
            let w = wire(id);
            locked.iter().all(|(m, banks)| {
                if receivers.contains(m) {
                    !exact || banks.iter().any(|f| always_passes(f, &w))
                } else {
                    !banks.iter().any(|f| may_pass(f, &w))
                }
            })
        };
        let candidates = || (FIRST_TOPIC_MSG_ID..=u16::MAX).filter(|id| !used.contains(id));
        let id = if receivers.is_empty() {
            candidates().find(|id| clean(*id, false))
        } else {
            candidates()
                .take_while(|id| *id <= ceiling)
                .find(|id| clean(*id, true))
                .or_else(|| candidates().find(|id| clean(*id, false)))
        }?;
        used.insert(id);
        *ids.get_mut(i)? = Some(id);
    }
    for (i, lt) in relaid {
        let new = ids.get(i).copied().flatten()?;
        let reason = if lt.layout != layout(model, i) {
            format!("layout changed: {} -> {}", lt.layout, layout(model, i))
        } else {
            format!("ID {:#06x} locked for two topics", lt.msg_id)
        };
        moves.push(Move {
            subject: lt.name.clone(),
            what: "msg_id",
            from: format!("{:#06x}", lt.msg_id),
            to: format!("{new:#06x}"),
            reason,
        });
    }
    ids.into_iter().collect()
}

fn masks_for(slots: u32, reqs: &[HrtRequest], pls: &[Placement]) -> Option<(u64, Vec<u64>)> {
    let hyper = admission::hyperperiod(slots, reqs)?;
    if hyper > MAX_HYPERPERIOD_SLOTS {
        return None;
    }
    let mut masks = vec![0u64; usize::try_from(hyper / u64::from(slots.max(1))).ok()?];
    let n = admission::build_masks(slots, reqs, pls, &mut masks).ok()?;
    masks.truncate(n);
    Some((hyper, masks))
}

/// HRT placement with a lock: topics that kept their ID and period keep their phase; the
/// others take the first phase free of every reservation. `None` when that fails (the
/// caller then runs the full admission and reports the phases that moved).
pub fn place(
    model: &Model,
    hrt: &[HrtTopic],
    names: &[&str],
    ids: &[u16],
    lock: &Lock,
) -> Option<Admitted> {
    let slots = u32::from(model.bus.slots);
    let mut reqs: Vec<HrtRequest> = Vec::new();
    let mut pls: Vec<Placement> = Vec::new();
    let mut order: Vec<usize> = Vec::new();
    let mut open: Vec<usize> = Vec::new();
    for (k, h) in hrt.iter().enumerate() {
        let name = names.get(h.topic).copied().unwrap_or("");
        let id = ids.get(h.topic).copied();
        match lock.topics.get(name) {
            Some(lt)
                if Some(lt.msg_id) == id
                    && lt.period == Some(h.request.period_slots)
                    && lt.phase.is_some_and(|p| p < h.request.period_slots) =>
            {
                reqs.push(h.request);
                pls.push(Placement {
                    phase_slot: lt.phase.unwrap_or(0),
                });
                order.push(k);
            }
            _ => open.push(k),
        }
    }
    masks_for(slots, &reqs, &pls)?;
    let mut steps = 0u64;
    for k in open {
        let h = hrt.get(k)?;
        reqs.push(h.request);
        pls.push(Placement::default());
        let mut placed = false;
        for phase in 0..h.request.period_slots {
            steps += 1;
            if let Some(p) = pls.last_mut() {
                p.phase_slot = phase;
            }
            if masks_for(slots, &reqs, &pls).is_some() {
                placed = true;
                break;
            }
        }
        if !placed {
            return None;
        }
        order.push(k);
    }
    let (hyper, masks) = masks_for(slots, &reqs, &pls)?;
    let mut placements = vec![Placement::default(); hrt.len()];
    for (k, p) in order.iter().zip(&pls) {
        *placements.get_mut(*k)? = *p;
    }
    let reserved = reqs
        .iter()
        .map(|r| u64::from(r.fragments) * (hyper / u64::from(r.period_slots.max(1))))
        .sum();
    Some(Admitted {
        placements,
        stats: AdmitStats {
            steps,
            hyperperiod_slots: hyper,
            reserved_slots: reserved,
        },
        masks,
    })
}

/// Text lines of the moves, for `rtcan check`.
pub fn text(moves: &[Move]) -> String {
    let mut s = format!("allocation moves against the lock: {}\n", moves.len());
    for m in moves {
        let _ = writeln!(
            s,
            "  {} {}: {} -> {} ({})",
            m.subject, m.what, m.from, m.to, m.reason
        );
    }
    s
}

/// JSON form: `[{"subject", "what", "from", "to", "reason"}]`.
pub fn json(moves: &[Move]) -> serde_json::Value {
    serde_json::Value::Array(
        moves
            .iter()
            .map(|m| {
                serde_json::json!({
                    "subject": m.subject, "what": m.what, "from": m.from,
                    "to": m.to, "reason": m.reason
                })
            })
            .collect(),
    )
}
