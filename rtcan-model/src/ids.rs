//! Message ID assignment. Topics on the bus are grouped by the set of modules that
//! receive them; each group gets an aligned power-of-two block of IDs from
//! `FIRST_TOPIC_MSG_ID`, so one mask filter covers a group exactly (unused IDs in a block
//! are never sent). Local-only topics get IDs after every block: they never reach the wire.
use crate::model::Model;
use rtcan_core::id::FIRST_TOPIC_MSG_ID;
use rtcan_core::Class;
use std::collections::BTreeMap;

/// Rank used to order topics inside a group (IDs also break arbitration ties).
fn class_rank(c: Class) -> u8 {
    match c {
        Class::Hrt => 0,
        Class::Srt => 1,
        Class::Nrt => 2,
    }
}

/// Receiving modules of a topic (subscriber modules other than the publisher's), sorted by name.
pub fn receivers(model: &Model, topic: usize) -> Vec<usize> {
    let Some(t) = model.topics.get(topic) else {
        return Vec::new();
    };
    let pm = model.node_module(t.publisher);
    let mut mods: Vec<usize> = t
        .subscribers
        .iter()
        .map(|s| model.node_module(s.node))
        .filter(|m| *m != pm)
        .collect();
    mods.sort_by(|a, b| module_name(model, *a).cmp(module_name(model, *b)));
    mods.dedup();
    mods
}

fn module_name(model: &Model, m: usize) -> &str {
    model.modules.get(m).map_or("", |x| x.name.as_str())
}

/// Message ID of every topic (indexed like `model.topics`), or `None` if they do not fit
/// in the 16-bit ID space. Service topics (`[services]`) are numbered after every
/// declared topic, local ones included, so adding a service moves no existing ID; the
/// module-state topics of a supervised robot after the services' ones, for the same reason.
pub fn assign(model: &Model) -> Option<Vec<u16>> {
    let mut ids = vec![0u16; model.topics.len()];
    let (state, rest): (Vec<usize>, Vec<usize>) =
        (0..model.topics.len()).partition(|i| model.is_module_state_topic(*i));
    let (declared, services): (Vec<usize>, Vec<usize>) =
        rest.into_iter().partition(|i| !model.is_service_topic(*i));
    let cursor = place(model, &declared, u32::from(FIRST_TOPIC_MSG_ID), &mut ids)?;
    let cursor = place(model, &services, cursor, &mut ids)?;
    place(model, &state, cursor, &mut ids)?;
    Some(ids)
}

/// Numbers `topics` from `cursor`: the bus groups in aligned blocks, then the local
/// topics; returns the next free ID.
fn place(model: &Model, topics: &[usize], mut cursor: u32, ids: &mut [u16]) -> Option<u32> {
    let mut groups: BTreeMap<Vec<&str>, Vec<usize>> = BTreeMap::new();
    let mut local = Vec::new();
    for &i in topics {
        let Some(t) = model.topics.get(i) else {
            continue;
        };
        if model.on_bus(t) {
            let key = receivers(model, i)
                .into_iter()
                .map(|m| module_name(model, m))
                .collect();
            groups.entry(key).or_default().push(i);
        } else {
            local.push(i);
        }
    }
    let order_key = |i: &usize| {
        let t = model.topics.get(*i);
        (
            t.map_or(3, |t| class_rank(t.class)),
            t.and_then(|t| t.period_slots.map(u64::from).or(t.deadline_ns))
                .unwrap_or(u64::MAX),
            t.map_or("", |t| t.name.as_str()),
        )
    };
    let mut groups: Vec<(Vec<&str>, Vec<usize>)> = groups.into_iter().collect();
    for (_, members) in &mut groups {
        members.sort_by_key(order_key);
    }
    // Largest blocks first: from a 64-aligned start, blocks of <= 64 IDs then need no padding.
    groups.sort_by(|a, b| {
        b.1.len()
            .next_power_of_two()
            .cmp(&a.1.len().next_power_of_two())
            .then(a.0.cmp(&b.0))
    });
    for (_, members) in &groups {
        let size = members.len().next_power_of_two() as u32;
        let base = cursor.div_ceil(size) * size;
        for (k, t) in members.iter().enumerate() {
            *ids.get_mut(*t)? = u16::try_from(base + k as u32).ok()?;
        }
        cursor = base + size;
    }
    local.sort_by_key(order_key);
    for t in local {
        *ids.get_mut(t)? = u16::try_from(cursor).ok()?;
        cursor += 1;
    }
    Some(cursor)
}
