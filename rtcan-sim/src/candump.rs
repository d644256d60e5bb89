//! candump log format (`candump -l`): `(seconds.micros) can0 1ABCDEF0#0011223344556677`,
//! extended identifiers as 8 hex digits, data as hex bytes. Readable by can-utils
//! (`canplayer`, `log2asc`) and SavvyCAN.
use std::fmt::Write as _;

use rtcan_core::{CanId, Frame, Nanos};

use crate::bus::WireFrame;

/// One log line.
pub fn line(time_ns: Nanos, iface: &str, frame: &Frame) -> String {
    let mut s = format!(
        "({}.{:06}) {} {:08X}#",
        time_ns / 1_000_000_000,
        (time_ns % 1_000_000_000) / 1_000,
        iface,
        frame.id().raw()
    );
    for b in frame.data() {
        let _ = write!(s, "{b:02X}");
    }
    s
}

/// The log of the frames that completed on the wire, stamped with their start of
/// frame (global time); destroyed frames are not logged (a sniffer never receives them).
pub fn log(wire: &[WireFrame], iface: &str) -> String {
    let mut out = String::new();
    for w in wire.iter().filter(|w| w.ok) {
        out.push_str(&line(w.sof, iface, &w.frame));
        out.push('\n');
    }
    out
}

/// Appends the frames that completed on the wire to `out` (as `log`).
pub fn write(
    out: &mut impl std::io::Write,
    wire: &[WireFrame],
    iface: &str,
) -> std::io::Result<()> {
    for w in wire.iter().filter(|w| w.ok) {
        writeln!(out, "{}", line(w.sof, iface, &w.frame))?;
    }
    Ok(())
}

/// A parsed log line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry {
    /// Timestamp, ns.
    pub time_ns: Nanos,
    /// Interface name.
    pub iface: String,
    /// The frame.
    pub frame: Frame,
    /// The identifier was written with 3 hex digits (standard frame: not RTCAN).
    pub standard: bool,
}

/// Why a line did not parse.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    /// 1-based line number.
    pub line: usize,
    /// What was wrong.
    pub what: &'static str,
}

/// What a well-formed log line holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Line {
    /// A classic data frame.
    Frame(Entry),
    /// Blank or `#` comment.
    Blank,
    /// A frame RTCAN never sends (remote, error or CAN FD frame): skipped and counted.
    Skipped(&'static str),
}

/// `candump` marks error frames with this identifier bit (SocketCAN `CAN_ERR_FLAG`).
const CAN_ERR_FLAG: u32 = 0x2000_0000;

/// Parses one line (blank lines and `#` comments give `Ok(None)`; remote, error and FD
/// frames are errors here, see `classify`).
pub fn parse_line(text: &str) -> Result<Option<Entry>, &'static str> {
    match classify(text)? {
        Line::Frame(e) => Ok(Some(e)),
        Line::Blank => Ok(None),
        Line::Skipped(what) => Err(what),
    }
}

/// Parses one line, telling frames RTCAN never sends apart from malformed lines.
pub fn classify(text: &str) -> Result<Line, &'static str> {
    let text = text.trim();
    if text.is_empty() || text.starts_with('#') {
        return Ok(Line::Blank);
    }
    let mut parts = text.split_whitespace();
    let stamp = parts.next().ok_or("missing timestamp")?;
    let iface = parts.next().ok_or("missing interface")?;
    let body = parts.next().ok_or("missing frame")?;
    let stamp = stamp
        .strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .ok_or("timestamp not in parentheses")?;
    let (secs, frac) = stamp.split_once('.').ok_or("timestamp without fraction")?;
    let secs: u64 = secs.parse().map_err(|_| "bad seconds")?;
    if frac.is_empty() || frac.len() > 9 || !frac.bytes().all(|b| b.is_ascii_digit()) {
        return Err("bad fraction");
    }
    let frac_ns: u64 = format!("{frac:0<9}").parse().map_err(|_| "bad fraction")?;
    let (id, data) = body.split_once('#').ok_or("frame without '#'")?;
    if data.starts_with('R') {
        return Ok(Line::Skipped("remote frame"));
    }
    if data.starts_with('#') {
        return Ok(Line::Skipped("CAN FD frame"));
    }
    let raw = u32::from_str_radix(id, 16).map_err(|_| "bad identifier")?;
    if id.len() == 8 && raw & CAN_ERR_FLAG != 0 && raw < 2 * CAN_ERR_FLAG {
        return Ok(Line::Skipped("error frame"));
    }
    let standard = id.len() == 3;
    if !(standard || id.len() == 8) {
        return Err("identifier neither 3 nor 8 hex digits");
    }
    if data.len() % 2 != 0 || data.len() > 16 {
        return Err("bad data length");
    }
    let mut bytes = [0u8; 8];
    for (i, b) in bytes.iter_mut().enumerate().take(data.len() / 2) {
        let hex = data.get(2 * i..2 * i + 2).ok_or("bad data")?;
        *b = u8::from_str_radix(hex, 16).map_err(|_| "bad data")?;
    }
    let can_id = CanId::from_raw(raw).ok_or("identifier above 29 bits")?;
    let frame =
        Frame::from_parts(can_id, (data.len() / 2) as u8, bytes).ok_or("bad data length")?;
    Ok(Line::Frame(Entry {
        time_ns: secs.saturating_mul(1_000_000_000).saturating_add(frac_ns),
        iface: iface.to_string(),
        frame,
        standard,
    }))
}

/// Parses a whole log; stops at the first malformed line.
pub fn parse(text: &str) -> Result<Vec<Entry>, ParseError> {
    let mut out = Vec::new();
    for (i, l) in text.lines().enumerate() {
        match parse_line(l) {
            Ok(Some(e)) => out.push(e),
            Ok(None) => {}
            Err(what) => return Err(ParseError { line: i + 1, what }),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_extended_ids_with_eight_digits() {
        let f = Frame::new(
            CanId::from_raw(0x1ABC_DEF0).unwrap(),
            &[0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77],
        )
        .unwrap();
        assert_eq!(
            line(1_234_567_891, "can0", &f),
            "(1.234567) can0 1ABCDEF0#0011223344556677"
        );
        let e = Frame::new(CanId::from_raw(0x5).unwrap(), &[]).unwrap();
        assert_eq!(line(0, "can0", &e), "(0.000000) can0 00000005#");
    }

    #[test]
    fn parses_what_it_writes_and_rejects_garbage() {
        let e = parse_line("(12.000034) vcan1 00800A01#DEAD")
            .unwrap()
            .unwrap();
        assert_eq!(e.time_ns, 12_000_034_000);
        assert_eq!(e.iface, "vcan1");
        assert_eq!(e.frame.id().raw(), 0x0080_0A01);
        assert_eq!(e.frame.data(), &[0xDE, 0xAD]);
        assert!(!e.standard);
        assert!(parse_line("(1.5) can0 123#01").unwrap().unwrap().standard);
        assert_eq!(parse_line("  ").unwrap(), None);
        assert_eq!(
            parse_line("(1.0) can0 40000000#").unwrap_err(),
            "identifier above 29 bits"
        );
        assert_eq!(
            classify("(1.0) can0 20000080#0000080000000000").unwrap(),
            Line::Skipped("error frame")
        );
        assert_eq!(
            classify("(1.0) can0 00000123##1AABB").unwrap(),
            Line::Skipped("CAN FD frame")
        );
        assert_eq!(
            classify("(1.0) can0 00000123#R").unwrap(),
            Line::Skipped("remote frame")
        );
        assert_eq!(
            parse_line("(1.0) can0 00000001#0").unwrap_err(),
            "bad data length"
        );
        assert_eq!(
            parse_line("(1.0) can0 00000001#R").unwrap_err(),
            "remote frame"
        );
        assert_eq!(
            parse_line("1.0 can0 00000001#").unwrap_err(),
            "timestamp not in parentheses"
        );
        assert_eq!(
            parse("(0.1) can0 00000001#\nxx").unwrap_err(),
            ParseError {
                line: 2,
                what: "missing interface"
            }
        );
    }
}
