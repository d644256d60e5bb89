//! Where an image keeps its engine's counters in RAM, found from the image's own DWARF
//! (the release images carry debug info, `examples/triskar2/Cargo.toml`), so that the
//! report of an emulated run shows the counters the engine itself kept — the same
//! `rtcan_core::counters::Counters` the simulator reports — read from emulated SRAM.
//!
//! The engine lives in the RTIC local resource `drv` (`src/module_app.rs`:
//! `Driver { engine, .. }` inside `RacyCell<MaybeUninit<..>>`). Its layout is rustc's
//! (fields reordered), so nothing here assumes an offset: the path from the resource's
//! static to the `Counters` struct and each counter's offset come from DWARF member
//! offsets, and the counters are matched by name.
use gimli::{AttributeValue, EndianSlice, LittleEndian, UnitOffset};
use rtcan_core::counters::Counters;

use crate::mcu::Mcu;

type R<'a> = EndianSlice<'a, LittleEndian>;

/// The static holding the module's engine (RTIC names local resources this way).
pub const DRIVER_STATIC: &str = "__rtic_internal_local_resource_drv";
/// The counters' type name in DWARF.
const COUNTERS_TYPE: &str = "Counters";
/// Bound on the type graph walked from the static (the engine is a few hundred DIEs).
const MAX_VISITS: usize = 100_000;

/// Each counter of an image: its field name and absolute SRAM address.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CountersAt {
    pub fields: Vec<(String, u32)>,
}

fn attr_name(
    dwarf: &gimli::Dwarf<R<'_>>,
    unit: &gimli::Unit<R<'_>>,
    e: &Die<'_, '_>,
) -> Option<String> {
    let v = e.attr_value(gimli::DW_AT_name).ok()??;
    let s = dwarf.attr_string(unit, v).ok()?;
    Some(s.to_string_lossy().into_owned())
}

type Die<'abbrev, 'unit> = gimli::DebuggingInformationEntry<'abbrev, 'unit, R<'unit>, usize>;

/// The DIE a `DW_AT_type` names, as (unit index, offset in that unit).
fn type_ref(
    units: &[gimli::Unit<R<'_>>],
    u: usize,
    e: &Die<'_, '_>,
) -> Option<(usize, UnitOffset)> {
    match e.attr_value(gimli::DW_AT_type).ok()?? {
        AttributeValue::UnitRef(o) => Some((u, o)),
        AttributeValue::DebugInfoRef(o) => units.iter().enumerate().find_map(|(i, unit)| {
            let off = o.to_unit_offset(&unit.header)?;
            Some((i, off))
        }),
        _ => None,
    }
}

fn member_offset(e: &Die<'_, '_>) -> Option<u32> {
    let v = e.attr_value(gimli::DW_AT_data_member_location).ok()??;
    v.udata_value().and_then(|x| u32::try_from(x).ok())
}

/// The address a variable's `DW_AT_location` gives when it is a plain `DW_OP_addr`.
fn static_address(e: &Die<'_, '_>) -> Option<u32> {
    let AttributeValue::Exprloc(expr) = e.attr_value(gimli::DW_AT_location).ok()?? else {
        return None;
    };
    let b = expr.0.slice();
    // DW_OP_addr (0x03) and a 4-byte address (32-bit target), nothing after it.
    match b {
        [0x03, a, b2, c, d] => Some(u32::from_le_bytes([*a, *b2, *c, *d])),
        _ => None,
    }
}

/// Finds the engine counters of an image from its DWARF.
pub fn locate(elf: &[u8]) -> Result<CountersAt, String> {
    let fields = find_struct(elf, DRIVER_STATIC, COUNTERS_TYPE, "tx_frames")?;
    Ok(CountersAt { fields })
}

/// The members (name, absolute address) of the first struct named `type_name` (with a
/// member `must_have`) found inside the static variable named `static_name`, walking
/// its type breadth-first through struct and union members (MaybeUninit, ManuallyDrop,
/// Driver, Engine...). Works for any static of the image, e.g. a topic's `TopicStats`.
/// A generic struct matches by its name without parameters (`PoolState` for
/// `PoolState<4>`).
pub fn find_struct(
    elf: &[u8],
    static_name: &str,
    type_name: &str,
    must_have: &str,
) -> Result<Vec<(String, u32)>, String> {
    let dwarf = gimli::Dwarf::load(|id| -> Result<R<'_>, gimli::Error> {
        let data = crate::elf::section(elf, id.name())
            .ok()
            .flatten()
            .unwrap_or(&[]);
        Ok(EndianSlice::new(data, LittleEndian))
    })
    .map_err(|e| format!("DWARF: {e}"))?;
    let mut units = Vec::new();
    let mut headers = dwarf.units();
    while let Some(h) = headers.next().map_err(|e| format!("DWARF: {e}"))? {
        units.push(dwarf.unit(h).map_err(|e| format!("DWARF: {e}"))?);
    }
    // The static and its type.
    let mut root = None;
    'units: for (u, unit) in units.iter().enumerate() {
        let mut cur = unit.entries();
        while let Ok(Some((_, e))) = cur.next_dfs() {
            if e.tag() == gimli::DW_TAG_variable
                && attr_name(&dwarf, unit, e).as_deref() == Some(static_name)
            {
                if let (Some(addr), Some(t)) = (static_address(e), type_ref(&units, u, e)) {
                    root = Some((addr, t));
                    break 'units;
                }
            }
        }
    }
    let (base, ty) = root.ok_or(format!(
        "no static `{static_name}` in the image's DWARF (built without debug info?)"
    ))?;
    let mut queue = std::collections::VecDeque::from([(base, ty)]);
    let mut visits = 0;
    while let Some((addr, (u, off))) = queue.pop_front() {
        visits += 1;
        if visits > MAX_VISITS {
            break;
        }
        let Some(unit) = units.get(u) else { continue };
        let Ok(mut tree) = unit.entries_tree(Some(off)) else {
            continue;
        };
        let Ok(node) = tree.root() else { continue };
        let e = node.entry().clone();
        match e.tag() {
            gimli::DW_TAG_typedef | gimli::DW_TAG_const_type | gimli::DW_TAG_volatile_type => {
                if let Some(t) = type_ref(&units, u, &e) {
                    queue.push_back((addr, t));
                }
                continue;
            }
            gimli::DW_TAG_structure_type | gimli::DW_TAG_union_type => {}
            _ => continue,
        }
        // A generic type's DWARF name carries its parameters (`PoolState<4>`).
        let wanted = attr_name(&dwarf, unit, &e).is_some_and(|n| {
            n == type_name
                || n.strip_prefix(type_name)
                    .is_some_and(|rest| rest.starts_with('<'))
        });
        let mut fields = Vec::new();
        let mut children = node.children();
        while let Ok(Some(child)) = children.next() {
            let c = child.entry();
            if c.tag() != gimli::DW_TAG_member {
                continue;
            }
            let Some(at) = member_offset(c) else { continue };
            if wanted {
                if let Some(name) = attr_name(&dwarf, unit, c) {
                    fields.push((name, addr + at));
                }
            } else if let Some(t) = type_ref(&units, u, c) {
                queue.push_back((addr + at, t));
            }
        }
        if wanted && fields.iter().any(|(n, _)| n == must_have) {
            fields.sort_by_key(|(_, a)| *a);
            return Ok(fields);
        }
    }
    Err(format!(
        "no `{type_name}` inside `{static_name}` in the image's DWARF"
    ))
}

/// Reads the u32 at `addr` of the MCU's memory.
pub fn read_u32(mcu: &Mcu, addr: u32) -> u32 {
    let b = mcu.read_mem(addr, 4);
    u32::from_le_bytes([
        b.first().copied().unwrap_or(0),
        b.get(1).copied().unwrap_or(0),
        b.get(2).copied().unwrap_or(0),
        b.get(3).copied().unwrap_or(0),
    ])
}

/// The counter of `c` named `name` (the fields of `rtcan_core::counters::Counters`).
fn field<'c>(c: &'c mut Counters, name: &str) -> Option<&'c mut u32> {
    Some(match name {
        "rx_unknown_id" => &mut c.rx_unknown_id,
        "rx_bad_dlc" => &mut c.rx_bad_dlc,
        "rx_out_of_order" => &mut c.rx_out_of_order,
        "rx_other_transfer" => &mut c.rx_other_transfer,
        "rx_incomplete" => &mut c.rx_incomplete,
        "rx_bad_size" => &mut c.rx_bad_size,
        "rx_bad_sync" => &mut c.rx_bad_sync,
        "rx_bad_heartbeat" => &mut c.rx_bad_heartbeat,
        "rx_overrun" => &mut c.rx_overrun,
        "rx_delivered" => &mut c.rx_delivered,
        "tx_frames" => &mut c.tx_frames,
        "tx_aborted" => &mut c.tx_aborted,
        "tx_failed" => &mut c.tx_failed,
        "deadline_missed" => &mut c.deadline_missed,
        "queue_full" => &mut c.queue_full,
        "hrt_empty" => &mut c.hrt_empty,
        "hrt_late" => &mut c.hrt_late,
        "sync_missed" => &mut c.sync_missed,
        "bus_off" => &mut c.bus_off,
        "cycles_skipped" => &mut c.cycles_skipped,
        "error_passive" => &mut c.error_passive,
        "master_yields" => &mut c.master_yields,
        _ => return None,
    })
}

impl CountersAt {
    /// The counters as the emulated MCU's RAM holds them now. Fails on a field this
    /// crate does not know (the image was built from another `Counters`).
    pub fn read(&self, mcu: &Mcu) -> Result<Counters, String> {
        let mut c = Counters::default();
        for (name, addr) in &self.fields {
            let v = read_u32(mcu, *addr);
            *field(&mut c, name).ok_or(format!("unknown counter `{name}` in the image"))? = v;
        }
        Ok(c)
    }
}
