//! Real epochs for candump logs (`rtcan record --log-epoch`, `rtcan sim --log-epoch`).
//! can-utils' `log2asc` takes the first frame's time as the start of the recording: a
//! log whose times start at 0 gets a `date` header per frame for its first seconds and
//! every one of those frames stamped 0.000000, so logs meant for other tools start at a
//! real time (seconds since 1970).
use std::io::{BufRead, Write};
use std::path::Path;

/// `SECONDS` since 1970 (a fraction allowed) or `now`, as ns (clap value parser).
pub fn parse(v: &str) -> Result<u64, String> {
    if v == "now" {
        return std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos() as u64)
            .map_err(|e| e.to_string());
    }
    // Exact decimal: an f64 holds 1700000000.25 s only to ~256 ns.
    let bad = || "give seconds since 1970 (e.g. 1700000000 or 1700000000.25) or `now`".to_string();
    let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
    let (whole, frac) = match v.split_once('.') {
        Some((w, f)) if digits(f) && f.len() <= 9 => (w, f),
        Some(_) => return Err(bad()),
        None => (v, ""),
    };
    if !digits(whole) || whole.len() > 11 {
        return Err(bad());
    }
    let s: u64 = whole.parse().map_err(|_| bad())?;
    let ns: u64 = format!("{frac:0<9}").parse().map_err(|_| bad())?;
    if s >= 100_000_000_000 {
        return Err(bad());
    }
    Ok(s * 1_000_000_000 + ns)
}

/// The line with `epoch_ns` added to its `(SECONDS.MICROS)` time; other lines as they are.
pub fn shift_line(line: &str, epoch_ns: u64) -> String {
    let shifted = (|| {
        let rest = line.strip_prefix('(')?;
        let (time, tail) = rest.split_once(')')?;
        let (s, us) = time.split_once('.')?;
        if us.len() != 6 {
            return None;
        }
        let ns = s.parse::<u64>().ok()? * 1_000_000_000 + us.parse::<u64>().ok()? * 1_000;
        let t = ns.checked_add(epoch_ns)?;
        Some(format!(
            "({}.{:06}){tail}",
            t / 1_000_000_000,
            (t % 1_000_000_000) / 1_000
        ))
    })();
    shifted.unwrap_or_else(|| line.to_string())
}

/// Rewrites the log at `path` with every time moved by `epoch_ns`, line by line
/// (memory does not grow with the log).
pub fn shift_file(path: &Path, epoch_ns: u64) -> Result<(), String> {
    let err = |e: std::io::Error| format!("{}: {e}", path.display());
    let tmp = path.with_extension("log.tmp");
    {
        let input = std::io::BufReader::new(std::fs::File::open(path).map_err(err)?);
        let mut out = std::io::BufWriter::new(std::fs::File::create(&tmp).map_err(err)?);
        for line in input.lines() {
            writeln!(out, "{}", shift_line(&line.map_err(err)?, epoch_ns)).map_err(err)?;
        }
        out.flush().map_err(err)?;
    }
    std::fs::rename(&tmp, path).map_err(err)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;

    #[test]
    fn lines_move_by_the_epoch_exactly() {
        let e = parse("1700000000").unwrap();
        assert_eq!(e, 1_700_000_000_000_000_000);
        assert_eq!(
            shift_line("(0.000100) can0 1F808180#EFBEADDE01", e),
            "(1700000000.000100) can0 1F808180#EFBEADDE01"
        );
        assert_eq!(
            shift_line("(1.999999) can0 00014000#", parse("1700000000.5").unwrap()),
            "(1700000002.499999) can0 00014000#"
        );
        // Not a frame line: left alone.
        assert_eq!(shift_line("garbage", e), "garbage");
        assert_eq!(shift_line("(0.1) can0 1#", e), "(0.1) can0 1#");
        assert_eq!(parse("1700000000.25"), Ok(1_700_000_000_250_000_000));
        assert_eq!(parse("0.000000001"), Ok(1));
        for bad in [
            "-1",
            "x",
            "1e12",
            "",
            ".5",
            "1.",
            "1.0000000001",
            "100000000000",
        ] {
            assert!(parse(bad).is_err(), "{bad}");
        }
        let now = parse("now").unwrap();
        assert!(now > 1_700_000_000_000_000_000, "{now}");
    }
}
