//! Scripted faults: what happens to which module when, as `rtcan sim --fault` and the
//! campaign give them (`motor2:reset@3.2s`, `gateway:dies@2s`, `gateway:returns@5s`,
//! ...). Parsing is strict: an unknown module, kind or time is an
//! error naming the accepted forms, never a fault silently ignored.
use rtcan_core::Nanos;

/// What happens to a module.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaultKind {
    /// Power loss: the module stops executing, its controller's mailboxes and FIFOs are
    /// lost (a frame already on the wire completes).
    Dies,
    /// Power returns after `Dies`: the module boots again (statics, engine, host and app
    /// back to power-on), and its engine listens before it sends (`Engine::listen_first`).
    Returns,
    /// A watchdog or software reset: `Dies` and `Returns` at the same instant.
    Reset,
    /// A babbling idiot: the module's software stops following the schedule and keeps
    /// every transmit mailbox loaded with a top-priority data frame (`BABBLE_RAW`), so
    /// its controller floods the bus at line rate. No bus guardian.
    Babble,
}

/// Identifier of the babbling idiot's frames: laxity 0 and the first message ID above
/// the sync range — above the sync frame, below every HRT topic.
pub const BABBLE_RAW: u32 = (rtcan_core::id::SYNC_MSG_ID_END as u32) << 7;

/// One scripted fault.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fault {
    /// Module name as in robot.toml.
    pub module: usize,
    /// What happens.
    pub kind: FaultKind,
    /// Global (bus) time, ns.
    pub at: Nanos,
}

/// The accepted forms, for error messages and `--help`.
pub const FORMS: &str =
    "MODULE:dies@T, MODULE:returns@T, MODULE:reset@T, MODULE:babble@T (T: a number with unit s, ms or us, e.g. 3.2s)";

/// A duration such as `3.2s`, `1ms`, `250us` in ns.
pub fn parse_duration(s: &str) -> Result<Nanos, String> {
    let (num, scale) = if let Some(n) = s.strip_suffix("ms") {
        (n, 1e6)
    } else if let Some(n) = s.strip_suffix("us") {
        (n, 1e3)
    } else if let Some(n) = s.strip_suffix('s') {
        (n, 1e9)
    } else {
        return Err(format!("`{s}` has no unit (s, ms or us)"));
    };
    let v: f64 = num
        .parse()
        .map_err(|_| format!("`{s}` is not a number with a unit"))?;
    if !v.is_finite() || v < 0.0 || v * scale > 1e18 {
        return Err(format!("`{s}` is out of range (0 to 1e9 s)"));
    }
    Ok((v * scale).round() as Nanos)
}

/// Parses `MODULE:KIND@TIME`; `modules` are the robot's module names in bus order.
pub fn parse(spec: &str, modules: &[&str]) -> Result<Fault, String> {
    let bad = |why: String| format!("bad --fault `{spec}`: {why}; accepted: {FORMS}");
    let (module, rest) = spec
        .split_once(':')
        .ok_or_else(|| bad("no `:` after the module".into()))?;
    let (kind, at) = rest
        .split_once('@')
        .ok_or_else(|| bad("no `@TIME`".into()))?;
    let m = modules.iter().position(|&n| n == module).ok_or_else(|| {
        bad(format!(
            "no module `{module}` (modules: {})",
            modules.join(", ")
        ))
    })?;
    let at = parse_duration(at).map_err(bad)?;
    let kind = match kind {
        "dies" => FaultKind::Dies,
        "returns" => FaultKind::Returns,
        "reset" => FaultKind::Reset,
        "babble" => FaultKind::Babble,
        k => return Err(bad(format!("unknown fault `{k}`"))),
    };
    Ok(Fault {
        module: m,
        kind,
        at,
    })
}

/// The intervals in which a module is down, from its faults (`Dies`/`Returns`/`Reset`),
/// in time order: `[from, to)`, `to` = `Nanos::MAX` when it never returns. A `Returns`
/// without an earlier `Dies` and a second `Dies` while down are errors: a script that
/// cannot happen is reported, not reinterpreted.
pub fn down_intervals(faults: &[Fault], module: usize) -> Result<Vec<(Nanos, Nanos)>, String> {
    let mut own: Vec<&Fault> = faults
        .iter()
        .filter(|f| f.module == module && f.kind != FaultKind::Babble)
        .collect();
    own.sort_by_key(|f| f.at);
    let mut out: Vec<(Nanos, Nanos)> = Vec::new();
    let mut down: Option<Nanos> = None;
    for f in own {
        match (f.kind, down) {
            (FaultKind::Dies, None) => down = Some(f.at),
            (FaultKind::Returns, Some(from)) => {
                out.push((from, f.at));
                down = None;
            }
            (FaultKind::Reset, None) => out.push((f.at, f.at)),
            (FaultKind::Dies | FaultKind::Reset, Some(from)) => {
                return Err(format!(
                    "module {module} is already down since {:.3} s at {:.3} s",
                    from as f64 / 1e9,
                    f.at as f64 / 1e9
                ))
            }
            (FaultKind::Returns, None) => {
                return Err(format!(
                    "module {module} returns at {:.3} s but did not die before",
                    f.at as f64 / 1e9
                ))
            }
            // Filtered out above: babbling is not being down.
            (FaultKind::Babble, _) => {}
        }
    }
    if let Some(from) = down {
        out.push((from, Nanos::MAX));
    }
    Ok(out)
}

/// When `module` starts babbling, if it does (the earliest such fault).
pub fn babble_from(faults: &[Fault], module: usize) -> Option<Nanos> {
    faults
        .iter()
        .filter(|f| f.module == module && f.kind == FaultKind::Babble)
        .map(|f| f.at)
        .min()
}

#[cfg(test)]
mod tests {
    use super::*;

    const M: [&str; 3] = ["gateway", "motor1", "motor2"];

    #[test]
    fn parses_every_form() {
        assert_eq!(
            parse("motor2:reset@3.2s", &M),
            Ok(Fault {
                module: 2,
                kind: FaultKind::Reset,
                at: 3_200_000_000
            })
        );
        assert_eq!(
            parse("gateway:dies@2s", &M).map(|f| f.kind),
            Ok(FaultKind::Dies)
        );
        assert_eq!(
            parse("gateway:returns@5000ms", &M).map(|f| (f.kind, f.at)),
            Ok((FaultKind::Returns, 5_000_000_000))
        );
        assert_eq!(parse("motor1:dies@250us", &M).map(|f| f.at), Ok(250_000));
    }

    #[test]
    fn rejects_what_it_cannot_do() {
        for bad in [
            "motor9:dies@1s",
            "gateway:explodes@1s",
            "gateway:dies",
            "gateway dies@1s",
            "gateway:dies@1",
            "gateway:dies@-1s",
            "gateway:dies@xs",
            "gateway:dies@1e300s",
            "gateway:step+1ms@1s",
        ] {
            let e = parse(bad, &M).unwrap_err();
            assert!(e.contains(bad) && e.contains("accepted"), "{bad}: {e}");
        }
    }

    #[test]
    fn down_intervals_follow_the_script() {
        let f = |s: &str| parse(s, &M).unwrap();
        let script = [
            f("gateway:returns@5s"),
            f("gateway:dies@2s"),
            f("motor2:reset@3s"),
            f("gateway:dies@7s"),
        ];
        assert_eq!(
            down_intervals(&script, 0),
            Ok(vec![
                (2_000_000_000, 5_000_000_000),
                (7_000_000_000, Nanos::MAX)
            ])
        );
        assert_eq!(
            down_intervals(&script, 2),
            Ok(vec![(3_000_000_000, 3_000_000_000)])
        );
        assert_eq!(down_intervals(&script, 1), Ok(vec![]));
        let b = [f("motor1:babble@1s"), f("motor1:babble@3s")];
        assert_eq!(down_intervals(&b, 1), Ok(vec![]));
        assert_eq!(babble_from(&b, 1), Some(1_000_000_000));
        assert_eq!(babble_from(&b, 0), None);
        assert!(down_intervals(&[f("gateway:returns@1s")], 0).is_err());
        assert!(down_intervals(&[f("gateway:dies@1s"), f("gateway:reset@2s")], 0).is_err());
    }
}
