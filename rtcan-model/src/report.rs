//! Reports of a check: the `rtcan check` text (topics, load, filters, the cycle calendar
//! in the style of the RTCAN paper's Fig. 3) and the documented JSON form.
use crate::diag::Diagnostics;
use crate::filters::{BankPurpose, FilterBank};
use crate::plan::{Load, Plan, TopicPlan};
use crate::units::{fmt_hz, fmt_ns, trim_float};
use crate::{Analysis, Status};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::Class;
use serde_json::{json, Value};
use std::fmt::Write as _;

const LABELS: &[u8] = b"ABCDEFGHIJKLMNOPQRTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";

fn module_name(plan: &Plan, m: usize) -> &str {
    plan.modules.get(m).map_or("?", |x| x.name.as_str())
}

fn node_name(plan: &Plan, n: usize) -> &str {
    plan.nodes.get(n).map_or("?", |x| x.name.as_str())
}

/// `text` left-aligned in `width` characters. Written by hand: `format!("{:<w$}")`
/// panics for widths above `u16::MAX` (a 64 KiB name).
fn pad_to(out: &mut String, text: &str, width: usize) {
    out.push_str(text);
    let n = text.chars().count();
    out.extend(std::iter::repeat_n(' ', width.saturating_sub(n)));
}

/// Pads every column of `rows` to its widest cell.
fn table(rows: &[Vec<String>]) -> String {
    let cols = rows.iter().map(Vec::len).max().unwrap_or(0);
    let widths: Vec<usize> = (0..cols)
        .map(|c| {
            rows.iter()
                .filter_map(|r| r.get(c))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for r in rows {
        let mut line = String::from("  ");
        for (c, cell) in r.iter().enumerate() {
            let w = widths.get(c).copied().unwrap_or(0);
            pad_to(&mut line, cell, w);
            line.push_str("  ");
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

fn laxity(l: LaxityEncoding) -> String {
    match l {
        LaxityEncoding::Linear { unit_ns } => {
            format!("linear, {} per step", fmt_ns(f64::from(unit_ns)))
        }
        LaxityEncoding::Log { unit_ns } => format!("log, {} base unit", fmt_ns(f64::from(unit_ns))),
    }
}

/// The `rtcan check` text for an admissible plan.
pub fn text(plan: &Plan) -> String {
    let b = &plan.bus;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "{}: admissible, fingerprint {:#010x}",
        plan.file, plan.fingerprint
    );
    let _ = writeln!(
        o,
        "bus: {} bit/s, {} slots of {} (cycle {}, requested {}), guard {}, worst-case 8-byte frame {}",
        b.bitrate,
        b.slots_per_cycle,
        fmt_ns(b.slot_ns as f64),
        fmt_ns(b.cycle_ns as f64),
        fmt_ns(b.requested_cycle_ns as f64),
        fmt_ns(b.guard_ns as f64),
        fmt_ns(b.worst_frame_ns as f64)
    );
    let backups: Vec<&str> = b
        .backup_masters
        .iter()
        .map(|m| module_name(plan, *m))
        .collect();
    let _ = writeln!(
        o,
        "     master {}{}, hyperperiod {} cycle(s) = {} slots, cycle counter wraps at {}, laxity {}",
        module_name(plan, b.master),
        if backups.is_empty() { String::new() } else { format!(" (backups {})", backups.join(", ")) },
        b.hyperperiod_cycles,
        b.hyperperiod_slots,
        b.cycle_counter_wrap,
        laxity(b.laxity)
    );

    let on_bus = |c: Class| plan.topics.iter().filter(move |t| t.on_bus && t.class == c);
    let mut rows = vec![vec![
        "HRT topic".into(),
        "module".into(),
        "msg id".into(),
        "requested".into(),
        "actual".into(),
        "period".into(),
        "phase".into(),
        "frags".into(),
        "bytes".into(),
    ]];
    for t in on_bus(Class::Hrt) {
        let req = t.requested_period_ns.unwrap_or(0.0);
        let act = t.actual_period_ns(b).unwrap_or(0) as f64;
        rows.push(vec![
            t.name.clone(),
            module_name(plan, t.module).into(),
            format!("{:#06x}", t.msg_id.0),
            format!("{} ({})", fmt_hz(1e9 / req.max(1.0)), fmt_ns(req)),
            format!("{} ({})", fmt_hz(1e9 / act.max(1.0)), fmt_ns(act)),
            format!("{} slots", t.period_slots.unwrap_or(0)),
            t.phase_slot.map_or("-".into(), |p| p.to_string()),
            t.fragments.to_string(),
            t.size.to_string(),
        ]);
    }
    o.push('\n');
    o.push_str(&table(&rows));

    let mut rows = vec![vec![
        "SRT/NRT topic".into(),
        "class".into(),
        "module".into(),
        "msg id".into(),
        "deadline".into(),
        "avg rate".into(),
        "frags".into(),
        "bytes".into(),
    ]];
    for t in on_bus(Class::Srt).chain(on_bus(Class::Nrt)) {
        rows.push(vec![
            t.name.clone(),
            if t.class == Class::Srt {
                "srt".into()
            } else {
                "nrt".into()
            },
            module_name(plan, t.module).into(),
            format!("{:#06x}", t.msg_id.0),
            t.deadline_ns.map_or("-".into(), |d| fmt_ns(d as f64)),
            t.rate_hz.map_or("-".into(), fmt_hz),
            t.fragments.to_string(),
            t.size.to_string(),
        ]);
    }
    if rows.len() > 1 {
        o.push('\n');
        o.push_str(&table(&rows));
    }
    let local: Vec<&str> = plan
        .topics
        .iter()
        .filter(|t| !t.on_bus)
        .map(|t| t.name.as_str())
        .collect();
    if !local.is_empty() {
        let _ = writeln!(
            o,
            "\nlocal only (no subscriber on another module, never on the bus): {}",
            local.join(", ")
        );
    }

    let l = &plan.load;
    let _ = writeln!(
        o,
        "\nbus load (frames per cycle; capacity {} frames = {} kbit/s of payload):",
        trim_float(l.capacity),
        trim_float(Load::kbps(l.capacity, b))
    );
    let mut rows = Vec::new();
    for (name, v) in [
        ("HRT reserved", l.hrt),
        ("SRT average", l.srt),
        ("NRT average", l.nrt),
        ("total", l.hrt + l.srt + l.nrt),
    ] {
        rows.push(vec![
            name.to_string(),
            trim_float(v),
            format!("{}%", trim_float(100.0 * v / l.capacity)),
            format!("{} kbit/s", trim_float(Load::kbps(v, b))),
        ]);
    }
    rows.push(vec![
        "free windows".into(),
        trim_float(l.free()),
        format!("{}%", trim_float(100.0 * l.free() / l.capacity)),
        format!("{} kbit/s", trim_float(Load::kbps(l.free(), b))),
    ]);
    o.push_str(&table(&rows));
    if !l.uncounted.is_empty() {
        let names: Vec<&str> = l
            .uncounted
            .iter()
            .filter_map(|i| plan.topics.get(*i))
            .map(|t| t.name.as_str())
            .collect();
        let _ = writeln!(
            o,
            "  not counted (no `rate` declared): {}",
            names.join(", ")
        );
    }

    let _ = writeln!(o, "\nfilter banks:");
    let mut rows = vec![vec![
        "module".into(),
        "board".into(),
        "banks".into(),
        "tx".into(),
        "rx".into(),
        "filters".into(),
    ]];
    for m in &plan.modules {
        let filters: Vec<String> = m
            .banks
            .iter()
            .map(|bk| bank_text(plan, &bk.filter, &bk.purpose))
            .collect();
        rows.push(vec![
            format!("{}{}", m.name, if m.is_master { " (master)" } else { "" }),
            m.board.name().into(),
            format!("{}/{}", m.banks.len(), m.board.filter_banks()),
            m.tx.len().to_string(),
            m.rx.len().to_string(),
            filters.join("; "),
        ]);
    }
    o.push_str(&table(&rows));
    o.push('\n');
    o.push_str(&calendar(plan));
    o.push_str(&crate::timing::text(plan));
    o
}

fn bank_text(plan: &Plan, f: &FilterBank, p: &BankPurpose) -> String {
    let what = match p {
        BankPurpose::Sync => "sync".to_string(),
        BankPurpose::Heartbeat => "heartbeats".to_string(),
        BankPurpose::AcceptAll => "accept all".to_string(),
        BankPurpose::Topics(_) => {
            let names = p.topic_names(plan);
            if names.len() > 3 {
                format!("{} topics", names.len())
            } else {
                names.join(",")
            }
        }
    };
    match f {
        FilterBank::Mask { id, mask } => format!("{what} {id:#010x}/{mask:#010x}"),
        FilterBank::List { ids } => format!("{what} list {:#010x},{:#010x}", ids[0], ids[1]),
    }
}

fn padded(text: &str, width: usize) -> String {
    let mut s = String::new();
    pad_to(&mut s, text, width);
    s
}

/// The cycle calendar, one block per cycle of the hyperperiod, one row per module (like
/// the RTCAN paper's Fig. 3), then the reservation mask the master sends.
pub fn calendar(plan: &Plan) -> String {
    let b = &plan.bus;
    let n = usize::from(b.slots_per_cycle);
    let mut o = String::new();
    let _ = writeln!(
        o,
        "calendar ({} slots per cycle, {} cycle(s) per hyperperiod; S sync, letters = topic, . free):",
        n, b.hyperperiod_cycles
    );
    // Each module's tx topics are labelled A, B, C, ... (S is kept for the sync).
    let width = plan
        .modules
        .iter()
        .map(|m| m.name.len())
        .max()
        .unwrap_or(4)
        .max(4)
        + 2;
    let mut tens = String::new();
    let mut ones = String::new();
    for s in 0..n {
        tens.push(if s % 10 == 0 {
            char::from(b'0' + (s / 10 % 10) as u8)
        } else {
            ' '
        });
        ones.push(char::from(b'0' + (s % 10) as u8));
    }
    for c in 0..b.hyperperiod_cycles as usize {
        let _ = writeln!(o, "cycle {c}");
        let _ = writeln!(o, "  {}{tens}", padded("slot", width));
        let _ = writeln!(o, "  {}{ones}", padded("", width));
        for m in &plan.modules {
            let mut row: Vec<char> = vec!['.'; n];
            if m.is_master {
                if let Some(x) = row.first_mut() {
                    *x = 'S';
                }
            }
            for e in &m.calendar {
                let slot = e.slot as usize;
                if slot / n == c {
                    if let Some(x) = row.get_mut(slot % n) {
                        *x = LABELS
                            .get(usize::from(e.tx))
                            .map_or('#', |ch| char::from(*ch));
                    }
                }
            }
            if m.calendar.is_empty() && !m.is_master {
                continue;
            }
            let _ = writeln!(
                o,
                "  {}{}",
                padded(&m.name, width),
                row.iter().collect::<String>()
            );
        }
        let mask = plan.master_masks.get(c).copied().unwrap_or(1);
        let bits: String = (0..n)
            .map(|s| if mask >> s & 1 == 1 { '1' } else { '0' })
            .collect();
        let _ = writeln!(
            o,
            "  {}{bits}   {}/{} reserved",
            padded("mask", width),
            mask.count_ones(),
            n
        );
    }
    let _ = writeln!(o, "legend:");
    for m in plan.modules.iter().filter(|m| !m.calendar.is_empty()) {
        let items: Vec<String> =
            m.tx.iter()
                .enumerate()
                .filter_map(|(k, t)| plan.topics.get(*t).map(|t| (k, t)))
                .filter(|(_, t)| t.phase_slot.is_some())
                .map(|(k, t)| {
                    format!(
                        "{}={}",
                        LABELS.get(k).map_or('#', |ch| char::from(*ch)),
                        t.name
                    )
                })
                .collect();
        let _ = writeln!(o, "  {}{}", padded(&m.name, width), items.join(" "));
    }
    o
}

fn class_name(c: Class) -> &'static str {
    match c {
        Class::Hrt => "hrt",
        Class::Srt => "srt",
        Class::Nrt => "nrt",
    }
}

fn topic_json(plan: &Plan, t: &TopicPlan) -> Value {
    json!({
        "name": t.name,
        "class": class_name(t.class),
        "type": plan.types.get(t.ty).map_or("", |x| x.name.as_str()),
        "msg_id": t.msg_id.0,
        "module": module_name(plan, t.module),
        "publisher": node_name(plan, t.publisher),
        "size": t.size,
        "fragments": t.fragments,
        "on_bus": t.on_bus,
        "period_slots": t.period_slots,
        "phase_slot": t.phase_slot,
        "requested_period_ns": t.requested_period_ns,
        "deadline_ns": t.deadline_ns,
        "rate_hz": t.rate_hz,
        "subscribers": t.subscribers.iter().map(|s| json!({
            "node": node_name(plan, s.node),
            "module": module_name(plan, s.module),
            "queue": s.queue,
        })).collect::<Vec<_>>(),
    })
}

/// Diagnostics as JSON objects (`code`, `category`, `message`, `line`, `column`, `span`, `help`, `notes`).
pub fn diagnostics_json(d: &Diagnostics) -> Value {
    let index = d.index();
    Value::Array(
        d.items
            .iter()
            .map(|x| {
                let (line, col) = x.span.as_ref().map_or((None, None), |s| {
                    let (l, c) = index.line_col(&d.source, s.start);
                    (Some(l), Some(c))
                });
                json!({
                    "code": x.code.name(),
                    "category": match x.code.category() { crate::Category::Input => "input", crate::Category::Schedule => "schedule", crate::Category::Undecided => "undecided" },
                    "message": x.message,
                    "file": d.file,
                    "line": line,
                    "column": col,
                    "span": x.span.as_ref().map(|s| [s.start, s.end]),
                    "help": x.help,
                    "notes": x.notes,
                })
            })
            .collect(),
    )
}

/// The documented JSON of a check (docs/ROBOT_TOML.md, "rtcan check --json").
pub fn json(a: &Analysis) -> Value {
    let status = a.status();
    let status_name = status.name();
    let mut v = json!({
        "file": a.diagnostics.file,
        "admissible": status == Status::Admissible,
        "status": status_name,
        "diagnostics": diagnostics_json(&a.diagnostics),
        "hrt": [],
    });
    if let (Some(m), Some(obj)) = (&a.model, v.as_object_mut()) {
        obj.insert("slots_per_cycle".into(), json!(m.bus.slots));
        obj.insert("slot_ns".into(), json!(m.bus.slot_ns));
        obj.insert("bitrate".into(), json!(m.bus.bitrate));
    }
    let (Some(plan), Some(obj)) = (&a.plan, v.as_object_mut()) else {
        return v;
    };
    let b = &plan.bus;
    let hrt: Vec<Value> = plan
        .topics
        .iter()
        .filter(|t| t.on_bus && t.class == Class::Hrt)
        .filter_map(|t| {
            Some(json!({
                "topic": t.name,
                "module": module_name(plan, t.module),
                "msg_id": t.msg_id.0,
                "period_slots": t.period_slots?,
                "phase_slot": t.phase_slot?,
                "fragments": t.fragments,
                "requested_hz": t.requested_period_ns.map(|ns| 1e9 / ns),
                "actual_hz": t.actual_period_ns(b).map(|ns| 1e9 / ns as f64),
            }))
        })
        .collect();
    let fields = [
        ("cycle_ns", json!(b.cycle_ns)),
        ("hyperperiod_slots", json!(b.hyperperiod_slots)),
        ("hyperperiod_cycles", json!(b.hyperperiod_cycles)),
        ("cycle_counter_wrap", json!(b.cycle_counter_wrap)),
        ("guard_ns", json!(b.guard_ns)),
        ("master", json!(module_name(plan, b.master))),
        ("fingerprint", json!(format!("{:#010x}", plan.fingerprint))),
        ("reserved_slots", json!(plan.reserved_slots())),
        ("timing", crate::timing::json(plan)),
        ("hrt", Value::Array(hrt)),
        ("masks", json!(plan.master_masks.iter().map(|m| format!("{m:#018x}")).collect::<Vec<_>>())),
        ("topics", Value::Array(plan.topics.iter().map(|t| topic_json(plan, t)).collect())),
        (
            "load",
            json!({
                "capacity": plan.load.capacity,
                "hrt": plan.load.hrt,
                "srt": plan.load.srt,
                "nrt": plan.load.nrt,
                "free": plan.load.free(),
                "uncounted": plan.load.uncounted.iter().filter_map(|i| plan.topics.get(*i)).map(|t| t.name.clone()).collect::<Vec<_>>(),
            }),
        ),
        (
            "modules",
            Value::Array(
                plan.modules
                    .iter()
                    .map(|m| {
                        json!({
                            "name": m.name,
                            "index": m.index,
                            "board": m.board.name(),
                            "master": m.is_master,
                            "filters": match m.filter_mode { crate::FilterMode::Exact => "exact", crate::FilterMode::AcceptAll => "accept-all" },
                            "banks_used": m.banks.len(),
                            "banks_available": m.board.filter_banks(),
                            "banks": m.banks.iter().map(|bk| match bk.filter {
                                FilterBank::Mask { id, mask } => json!({"kind": "mask", "id": id, "mask": mask}),
                                FilterBank::List { ids } => json!({"kind": "list", "ids": ids}),
                            }).collect::<Vec<_>>(),
                            "tx": m.tx.iter().filter_map(|t| plan.topics.get(*t)).map(|t| t.name.clone()).collect::<Vec<_>>(),
                            "rx": m.rx.iter().filter_map(|t| plan.topics.get(*t)).map(|t| t.name.clone()).collect::<Vec<_>>(),
                            "calendar_slots": m.calendar.len(),
                        })
                    })
                    .collect(),
            ),
        ),
    ];
    for (k, val) in fields {
        obj.insert(k.into(), val);
    }
    v
}

/// [`json`] pretty-printed.
pub fn json_text(a: &Analysis) -> String {
    serde_json::to_string_pretty(&json(a)).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}
