//! Numbers with units as written in robot.toml: durations ("10ms", "166.67us"),
//! frequencies ("200Hz", "1.5kHz"), bit rates ("1Mbit/s") and percentages ("2%").
//! Each parser returns the value or the text of the error message.

/// Splits "12.5 ms" into (12.5, "ms"); the number is plain decimal (no sign, no exponent).
fn split_number(text: &str) -> Option<(f64, &str)> {
    let t = text.trim();
    let end = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(end);
    if num.is_empty() || num.starts_with('.') || num.ends_with('.') || num.matches('.').count() > 1
    {
        return None;
    }
    let v: f64 = num.parse().ok()?;
    v.is_finite().then_some((v, unit.trim()))
}

/// A duration in ns (rounded to the nearest ns); must be > 0 and at most 1000 s.
pub fn duration_ns(text: &str) -> Result<u64, String> {
    let bad = || {
        format!(
            "`{text}` is not a duration: write a number and a unit (s, ms, us, ns), e.g. \"10ms\""
        )
    };
    let (v, unit) = split_number(text).ok_or_else(bad)?;
    let scale = match unit {
        "s" => 1e9,
        "ms" => 1e6,
        "us" | "µs" => 1e3,
        "ns" => 1.0,
        _ => return Err(bad()),
    };
    let ns = (v * scale).round();
    if !(1.0..=1e12).contains(&ns) {
        return Err(format!(
            "duration `{text}` is out of range (1 ns to 1000 s)"
        ));
    }
    Ok(ns as u64)
}

/// A frequency in Hz; must be > 0 and at most 1 MHz.
pub fn frequency_hz(text: &str) -> Result<f64, String> {
    let bad = || {
        format!("`{text}` is not a frequency: write a number and a unit (Hz, kHz), e.g. \"200Hz\"")
    };
    let (v, unit) = split_number(text).ok_or_else(bad)?;
    let scale = match unit {
        "Hz" => 1.0,
        "kHz" => 1e3,
        "MHz" => 1e6,
        _ => return Err(bad()),
    };
    let hz = v * scale;
    if !(hz > 0.0 && hz <= 1e6) {
        return Err(format!(
            "frequency `{text}` is out of range (above 0, at most 1 MHz)"
        ));
    }
    Ok(hz)
}

/// A CAN bit rate in bit/s: "1Mbit/s", "500kbit/s", "250kbps" (integers are taken as bit/s).
pub fn bitrate(text: &str) -> Result<u64, String> {
    let bad =
        || format!("`{text}` is not a bit rate: write e.g. \"1Mbit/s\", \"500kbit/s\" or 1000000");
    let (v, unit) = split_number(text).ok_or_else(bad)?;
    let scale = match unit {
        "bit/s" | "bps" | "" => 1.0,
        "kbit/s" | "kbps" | "k" => 1e3,
        "Mbit/s" | "Mbps" | "M" => 1e6,
        _ => return Err(bad()),
    };
    let bps = v * scale;
    if !bps.is_finite() || bps < 0.0 {
        return Err(format!(
            "`{text}` is negative or not finite: classic CAN runs at 10 kbit/s to 1 Mbit/s"
        ));
    }
    Ok(bps.round().min(u64::MAX as f64) as u64)
}

/// A percentage as a fraction: "2%" → 0.02.
pub fn percent(text: &str) -> Result<f64, String> {
    let bad = || format!("`{text}` is not a percentage: write e.g. \"2%\"");
    let (v, unit) = split_number(text).ok_or_else(bad)?;
    if unit != "%" {
        return Err(bad());
    }
    Ok(v / 100.0)
}

/// Human form of a duration in ns: "10 ms", "166.667 us", "850 ns".
pub fn fmt_ns(ns: f64) -> String {
    let (v, unit) = if ns >= 1e9 {
        (ns / 1e9, "s")
    } else if ns >= 1e6 {
        (ns / 1e6, "ms")
    } else if ns >= 1e3 {
        (ns / 1e3, "us")
    } else {
        (ns, "ns")
    };
    format!("{} {unit}", trim_float(v))
}

/// Human form of a frequency: "200 Hz", "996.016 Hz".
pub fn fmt_hz(hz: f64) -> String {
    format!("{} Hz", trim_float(hz))
}

/// Up to three decimals, trailing zeros removed.
pub fn trim_float(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations() {
        assert_eq!(duration_ns("10ms"), Ok(10_000_000));
        assert_eq!(duration_ns("166.67us"), Ok(166_670));
        assert_eq!(duration_ns("5 us"), Ok(5_000));
        assert_eq!(duration_ns("1s"), Ok(1_000_000_000));
        assert!(duration_ns("10").is_err());
        assert!(duration_ns("ten ms").is_err());
        assert!(duration_ns("0ms").is_err());
        assert!(duration_ns("1.2.3ms").is_err());
        assert!(duration_ns("-1ms").is_err());
    }

    #[test]
    fn frequencies_and_rates() {
        assert_eq!(frequency_hz("200Hz"), Ok(200.0));
        assert_eq!(frequency_hz("1.5kHz"), Ok(1500.0));
        assert!(frequency_hz("200").is_err());
        assert!(frequency_hz("0Hz").is_err());
        assert_eq!(bitrate("1Mbit/s"), Ok(1_000_000));
        assert_eq!(bitrate("500kbit/s"), Ok(500_000));
        assert_eq!(bitrate("125kbps"), Ok(125_000));
        assert!(bitrate("fast").is_err());
        assert_eq!(percent("2%"), Ok(0.02));
    }

    #[test]
    fn formatting() {
        assert_eq!(fmt_ns(10_000_000.0), "10 ms");
        assert_eq!(fmt_ns(166_666.0), "166.666 us");
        assert_eq!(fmt_hz(1000.004), "1000.004 Hz");
        assert_eq!(fmt_hz(200.0), "200 Hz");
    }
}
