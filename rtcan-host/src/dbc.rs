//! The bus as a DBC file (Vector's CAN database format, read by cantools, SavvyCAN,
//! python-can and most CAN tools), from the plan: every message whose CAN identifier is
//! fixed, with its fields as signals.
//!
//! Which messages have a fixed identifier: an RTCAN identifier is laxity, message ID and
//! fragment field (docs/PROTOCOL.md §2). HRT frames always carry laxity 0 and NRT frames
//! laxity 63, and a one-frame message has fragment field 0; so single-frame HRT and NRT
//! topics and every module's heartbeat (§9) have one identifier each. SRT frames carry a
//! laxity that shrinks as the deadline nears, and a multi-frame message a transfer ID and
//! counter: a DBC, one identifier per message, cannot describe them (`rtcan decode` does).
//!
//! Layout: fields are little-endian and packed (Intel byte order, `@1`); an array field
//! becomes one signal per element (`name_0`, `name_1`, ...); a bool is a byte 0/1;
//! f32/f64 signals are declared IEEE floats with `SIG_VALTYPE_`. Extended identifiers are
//! written with bit 31 set, as the format requires.
use std::fmt::Write as _;

use rtcan_core::fragment::fragment_count;
use rtcan_core::heartbeat::heartbeat_msg_id;
use rtcan_core::id::{LAXITY_HRT, LAXITY_NRT};
use rtcan_core::{CanId, Class};
use rtcan_model::{Plan, Prim};

/// Bit 31 of a DBC message ID: the identifier is extended (29 bits).
const EXTENDED: u32 = 0x8000_0000;
/// The DBC name of "no node".
const NO_NODE: &str = "Vector__XXX";

/// One signal: name, start bit, length, signed, float kind (0 integer, 1 f32, 2 f64),
/// minimum, maximum.
struct Signal {
    name: String,
    start: usize,
    bits: usize,
    signed: bool,
    float: u8,
    range: (String, String),
}

fn range(p: Prim) -> (String, String) {
    let (lo, hi) = match p {
        Prim::U8 => (0.0, 255.0),
        Prim::U16 => (0.0, 65535.0),
        Prim::U32 => (0.0, 4294967295.0),
        Prim::I8 => (-128.0, 127.0),
        Prim::I16 => (-32768.0, 32767.0),
        Prim::I32 => (-2147483648.0, 2147483647.0),
        Prim::Bool => (0.0, 1.0),
        // 64-bit integers and floats: no range is given (DBC's convention, [0|0]).
        Prim::U64 | Prim::I64 | Prim::F32 | Prim::F64 => (0.0, 0.0),
    };
    (format!("{lo}"), format!("{hi}"))
}

fn signals(plan: &Plan, ty: usize) -> Vec<Signal> {
    let mut out = Vec::new();
    let Some(t) = plan.types.get(ty) else {
        return out;
    };
    for f in &t.fields {
        let p = f.ty.prim;
        let size = p.size();
        let one = |name: String, offset: usize| Signal {
            name,
            start: offset * 8,
            bits: size * 8,
            signed: matches!(p, Prim::I8 | Prim::I16 | Prim::I32 | Prim::I64),
            float: match p {
                Prim::F32 => 1,
                Prim::F64 => 2,
                _ => 0,
            },
            range: range(p),
        };
        match f.ty.len {
            None => out.push(one(f.name.clone(), f.offset)),
            Some(n) => {
                for k in 0..usize::from(n) {
                    out.push(one(format!("{}_{k}", f.name), f.offset + k * size));
                }
            }
        }
    }
    out
}

/// One `BO_` block and the float declarations it needs.
struct Message {
    id: u32,
    name: String,
    dlc: usize,
    sender: String,
    receivers: Vec<String>,
    signals: Vec<Signal>,
    comment: String,
}

/// The class as robot.toml and the docs write it.
fn class_name(c: Class) -> &'static str {
    match c {
        Class::Hrt => "HRT",
        Class::Srt => "SRT",
        Class::Nrt => "NRT",
    }
}

fn messages(plan: &Plan) -> Vec<Message> {
    let module = |i: usize| {
        plan.modules
            .get(i)
            .map_or_else(|| NO_NODE.to_string(), |m| m.name.clone())
    };
    let mut out = Vec::new();
    for t in plan.topics.iter().filter(|t| t.on_bus) {
        let laxity = match t.class {
            Class::Hrt => LAXITY_HRT,
            Class::Nrt => LAXITY_NRT,
            Class::Srt => continue,
        };
        if fragment_count(usize::from(t.size)) != 1 {
            continue;
        }
        let Some(id) = CanId::new(laxity, t.msg_id, 0) else {
            continue;
        };
        let mut receivers: Vec<String> = t
            .subscribers
            .iter()
            .filter(|s| s.module != t.module)
            .map(|s| module(s.module))
            .collect();
        receivers.sort();
        receivers.dedup();
        let ty = plan.types.get(t.ty).map_or("?", |ty| ty.name.as_str());
        out.push(Message {
            id: id.raw() | EXTENDED,
            name: t.name.clone(),
            dlc: usize::from(t.size),
            sender: module(t.module),
            receivers,
            signals: signals(plan, t.ty),
            comment: format!("{} topic {}, type {ty}", class_name(t.class), t.name),
        });
    }
    for m in &plan.modules {
        let Some(id) = heartbeat_msg_id(m.index).and_then(|msg| CanId::new(LAXITY_NRT, msg, 0))
        else {
            continue;
        };
        let sig = |name: &str, start, bits, hi: &str| Signal {
            name: name.to_string(),
            start,
            bits,
            signed: false,
            float: 0,
            range: ("0".into(), hi.into()),
        };
        out.push(Message {
            id: id.raw() | EXTENDED,
            name: format!("heartbeat_{}", m.name),
            dlc: 5,
            sender: m.name.clone(),
            receivers: Vec::new(),
            signals: vec![
                sig("fingerprint", 0, 32, "4294967295"),
                sig("state", 32, 8, "255"),
            ],
            comment: format!(
                "heartbeat of module {} (index {}): robot fingerprint, state",
                m.name, m.index
            ),
        });
    }
    out
}

/// The DBC text of the bus of `plan`.
pub fn dbc(plan: &Plan) -> String {
    let msgs = messages(plan);
    let mut s = String::new();
    let _ = writeln!(s, "VERSION \"\"\n");
    let _ = writeln!(s, "NS_ :\n\tCM_\n\tSIG_VALTYPE_\n");
    let _ = writeln!(s, "BS_:\n");
    let nodes: Vec<&str> = plan.modules.iter().map(|m| m.name.as_str()).collect();
    let _ = writeln!(s, "BU_: {}\n", nodes.join(" "));
    for m in &msgs {
        let _ = writeln!(s, "BO_ {} {}: {} {}", m.id, m.name, m.dlc, m.sender);
        let rx = if m.receivers.is_empty() {
            NO_NODE.to_string()
        } else {
            m.receivers.join(",")
        };
        for g in &m.signals {
            let _ = writeln!(
                s,
                " SG_ {} : {}|{}@1{} (1,0) [{}|{}] \"\" {rx}",
                g.name,
                g.start,
                g.bits,
                if g.signed { '-' } else { '+' },
                g.range.0,
                g.range.1
            );
        }
        s.push('\n');
    }
    for m in &msgs {
        let _ = writeln!(s, "CM_ BO_ {} \"{}\";", m.id, m.comment);
    }
    for m in &msgs {
        for g in m.signals.iter().filter(|g| g.float != 0) {
            let _ = writeln!(s, "SIG_VALTYPE_ {} {} : {};", m.id, g.name, g.float);
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three modules; one topic of each kind a DBC can and cannot hold.
    const ROBOT: &str = r#"
[bus]
bitrate = "1Mbit/s"
cycle = "2ms"
slots = 10
laxity = "linear"
laxity_unit = "100us"
guard = "10us"
master = "m"
[types.Pose]
x = "f32"
ok = "bool"
[types.Ranges]
r = "[i16; 2]"
n = "u8"
[types.Big]
a = "f64"
b = "u32"
[modules.m]
board = "qemu"
[modules.a]
board = "qemu"
[modules.b]
board = "qemu"
[nodes.nm]
module = "m"
[nodes.na]
module = "a"
[nodes.nb]
module = "b"
[topics.pose]
type = "Pose"
publisher = "na"
class = "hrt"
period_slots = 10
subscribers = ["nm", "nb"]
[topics.ranges]
type = "Ranges"
publisher = "nb"
class = "nrt"
rate = "10Hz"
subscribers = ["nm"]
[topics.big]
type = "Big"
publisher = "na"
class = "hrt"
period_slots = 10
subscribers = ["nm"]
[topics.cmd]
type = "Pose"
publisher = "nm"
class = "srt"
deadline = "2ms"
rate = "100Hz"
subscribers = ["na"]
"#;

    fn plan(text: &str) -> Plan {
        let a = rtcan_model::analyze("t.toml", text);
        assert!(a.diagnostics.is_empty(), "{}", a.diagnostics.render());
        a.plan.unwrap()
    }

    #[test]
    fn exact_text() {
        let p = plan(ROBOT);
        // pose: HRT, message 0x143, laxity 0: 0x143 << 7 | 1 << 31 = 2147524992.
        // ranges: NRT, message 0x141, laxity 63: 0x1F80A080 | 1 << 31 = 2676007040.
        // big (two frames) and cmd (SRT) have no fixed identifier: left out.
        // Heartbeats: 0x1F808000 + index << 7, bit 31 set.
        let want = r#"VERSION ""

NS_ :
	CM_
	SIG_VALTYPE_

BS_:

BU_: m a b

BO_ 2147524992 pose: 5 a
 SG_ x : 0|32@1+ (1,0) [0|0] "" b,m
 SG_ ok : 32|8@1+ (1,0) [0|1] "" b,m

BO_ 2676007040 ranges: 5 b
 SG_ r_0 : 0|16@1- (1,0) [-32768|32767] "" m
 SG_ r_1 : 16|16@1- (1,0) [-32768|32767] "" m
 SG_ n : 32|8@1+ (1,0) [0|255] "" m

BO_ 2675998720 heartbeat_m: 5 m
 SG_ fingerprint : 0|32@1+ (1,0) [0|4294967295] "" Vector__XXX
 SG_ state : 32|8@1+ (1,0) [0|255] "" Vector__XXX

BO_ 2675998848 heartbeat_a: 5 a
 SG_ fingerprint : 0|32@1+ (1,0) [0|4294967295] "" Vector__XXX
 SG_ state : 32|8@1+ (1,0) [0|255] "" Vector__XXX

BO_ 2675998976 heartbeat_b: 5 b
 SG_ fingerprint : 0|32@1+ (1,0) [0|4294967295] "" Vector__XXX
 SG_ state : 32|8@1+ (1,0) [0|255] "" Vector__XXX

CM_ BO_ 2147524992 "HRT topic pose, type Pose";
CM_ BO_ 2676007040 "NRT topic ranges, type Ranges";
CM_ BO_ 2675998720 "heartbeat of module m (index 0): robot fingerprint, state";
CM_ BO_ 2675998848 "heartbeat of module a (index 1): robot fingerprint, state";
CM_ BO_ 2675998976 "heartbeat of module b (index 2): robot fingerprint, state";
SIG_VALTYPE_ 2147524992 x : 1;
"#;
        assert_eq!(dbc(&p), want);
        let msg = |name: &str| p.topics.iter().find(|t| t.name == name).unwrap().msg_id.0;
        assert_eq!((msg("pose"), msg("ranges")), (0x143, 0x141));
    }
}
