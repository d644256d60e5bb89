//! Scripted faults: what happens to which module when, as `rtcan sim --fault` and the
//! campaign give them (`motor2:reset@3.2s`, `gateway:dies@2s`, `gateway:returns@5s`,
//! `motor3:stuck@1s`, `motor2:stall=5ms@3s`, `psu:step=-1ms@2s`, ...). Parsing is
//! strict: an unknown module, kind, argument or time is an error naming the accepted
//! forms, never a fault silently ignored.
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
    /// its controller floods the bus at line rate (stopped only by a bus guardian,
    /// `guardian.rs`, if the run has one).
    Babble,
    /// The module's transceiver holds the bus dominant (a shorted TXD) until `Release`:
    /// no frame can start; a frame on the wire is destroyed; every controller sees
    /// dominant bits after its error flag (REC +8 per 8 bits: error-passive), the one
    /// transmitting at that moment TEC +8 per 8 bits (bus-off).
    Stuck,
    /// Ends `Stuck`.
    Release,
    /// The module's bus stub is cut: it neither receives nor is heard until `Rejoin`;
    /// alone on its stub its frames get no acknowledgement (TEC to error-passive).
    Partition,
    /// Ends `Partition`.
    Rejoin,
    /// The module's CPU runs with interrupts masked for this long (ns): its receive
    /// FIFOs fill and overrun (FIFO-locked mode, RFLM = 1, as the firmware configures),
    /// its timer and transmit interrupts wait.
    Stall(Nanos),
    /// The module's local clock jumps by this many ns (a time base corrected by
    /// software, a counter glitch): +1 ms, -1 ms.
    Step(i64),
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

impl Fault {
    /// The fault in `parse` syntax (times in µs, so it parses back to itself).
    pub fn spec(&self, modules: &[&str]) -> String {
        let m = modules.get(self.module).copied().unwrap_or("?");
        let kind = match self.kind {
            FaultKind::Dies => "dies".to_string(),
            FaultKind::Returns => "returns".into(),
            FaultKind::Reset => "reset".into(),
            FaultKind::Babble => "babble".into(),
            FaultKind::Stuck => "stuck".into(),
            FaultKind::Release => "release".into(),
            FaultKind::Partition => "partition".into(),
            FaultKind::Rejoin => "rejoin".into(),
            FaultKind::Stall(d) => format!("stall={}us", d as f64 / 1e3),
            FaultKind::Step(d) => format!(
                "step={}{}us",
                if d < 0 { '-' } else { '+' },
                d.unsigned_abs() as f64 / 1e3
            ),
        };
        format!("{m}:{kind}@{}us", self.at as f64 / 1e3)
    }
}

/// The accepted forms, for error messages and `--help`.
pub const FORMS: &str =
    "MODULE:dies@T, MODULE:returns@T, MODULE:reset@T, MODULE:babble@T, MODULE:stuck@T, MODULE:release@T, MODULE:partition@T, MODULE:rejoin@T, MODULE:stall=D@T, MODULE:step=+D@T or step=-D@T (T, D: a number with unit s, ms or us, e.g. 3.2s)";

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
    let (kind, arg) = match kind.split_once('=') {
        Some((k, a)) => (k, Some(a)),
        None => (kind, None),
    };
    let kind = match (kind, arg) {
        ("dies", None) => FaultKind::Dies,
        ("returns", None) => FaultKind::Returns,
        ("reset", None) => FaultKind::Reset,
        ("babble", None) => FaultKind::Babble,
        ("stuck", None) => FaultKind::Stuck,
        ("release", None) => FaultKind::Release,
        ("partition", None) => FaultKind::Partition,
        ("rejoin", None) => FaultKind::Rejoin,
        ("stall", Some(d)) => {
            let d = parse_duration(d).map_err(bad)?;
            if d == 0 {
                return Err(bad("a stall of 0".into()));
            }
            FaultKind::Stall(d)
        }
        ("step", Some(d)) => {
            let (sign, mag) = match d.as_bytes().first() {
                Some(b'+') => (1, d.get(1..).unwrap_or("")),
                Some(b'-') => (-1, d.get(1..).unwrap_or("")),
                _ => return Err(bad(format!("step `{d}` needs a sign (+1ms or -1ms)"))),
            };
            let m = parse_duration(mag).map_err(bad)?;
            let m = i64::try_from(m)
                .ok()
                .filter(|&m| m > 0 && m <= 1_000_000_000)
                .ok_or_else(|| bad(format!("step `{d}` must be within 1 ns and 1 s")))?;
            FaultKind::Step(sign * m)
        }
        ("stall" | "step", None) => {
            return Err(bad(format!("`{kind}` needs a duration, `{kind}=...`")))
        }
        (k, Some(_)) if !matches!(k, "stall" | "step") => {
            return Err(bad(format!("`{k}` takes no `=` argument")))
        }
        (k, _) => return Err(bad(format!("unknown fault `{k}`"))),
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
        .filter(|f| {
            f.module == module
                && matches!(
                    f.kind,
                    FaultKind::Dies | FaultKind::Returns | FaultKind::Reset
                )
        })
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
            // Filtered out above: the bus-level faults are not being down.
            _ => {}
        }
    }
    if let Some(from) = down {
        out.push((from, Nanos::MAX));
    }
    Ok(out)
}

/// The bus-level faults (`Stuck` … `Step`) in time order; a `Release` without `Stuck`, a
/// `Rejoin` without `Partition` (or a second one while in force) is an error.
pub fn bus_actions(faults: &[Fault]) -> Result<Vec<Fault>, String> {
    let mut out: Vec<Fault> = faults
        .iter()
        .filter(|f| {
            matches!(
                f.kind,
                FaultKind::Stuck
                    | FaultKind::Release
                    | FaultKind::Partition
                    | FaultKind::Rejoin
                    | FaultKind::Stall(_)
                    | FaultKind::Step(_)
            )
        })
        .copied()
        .collect();
    out.sort_by_key(|f| f.at);
    let mut stuck: Vec<usize> = Vec::new();
    let mut cut: Vec<usize> = Vec::new();
    for f in &out {
        let t = f.at as f64 / 1e9;
        let (set, on, name) = match f.kind {
            FaultKind::Stuck => (&mut stuck, true, "stuck"),
            FaultKind::Release => (&mut stuck, false, "stuck"),
            FaultKind::Partition => (&mut cut, true, "partitioned"),
            FaultKind::Rejoin => (&mut cut, false, "partitioned"),
            _ => continue,
        };
        let was = set.contains(&f.module);
        if was == on {
            return Err(format!(
                "module {} is {}{name} at {t:.3} s",
                f.module,
                if on { "already " } else { "not " }
            ));
        }
        if on {
            set.push(f.module);
        } else {
            set.retain(|&m| m != f.module);
        }
    }
    Ok(out)
}

/// Applies a bus-level fault to `bus` now: `Stuck`, `Release`, `Partition`, `Rejoin`,
/// `Stall`. Returns false for the others (module faults; `Step`, which also needs the
/// module's own copy of its clock).
pub fn apply_bus<M: crate::bus::Module>(bus: &mut crate::bus::Bus<M>, f: &Fault) -> bool {
    let m = f.module;
    match f.kind {
        FaultKind::Stuck => bus.set_stuck(m, true),
        FaultKind::Release => bus.set_stuck(m, false),
        FaultKind::Partition => bus.set_partitioned(m, true),
        FaultKind::Rejoin => bus.set_partitioned(m, false),
        FaultKind::Stall(d) => bus.stall(m, f.at.saturating_add(d)),
        FaultKind::Dies
        | FaultKind::Returns
        | FaultKind::Reset
        | FaultKind::Babble
        | FaultKind::Step(_) => return false,
    }
    true
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
            "gateway:step=1ms@1s",
            "gateway:step=+0ms@1s",
            "gateway:step=+2s@1s",
            "gateway:stall@1s",
            "gateway:stall=0ms@1s",
            "gateway:dies=1ms@1s",
            "gateway:stuck=1ms@1s",
        ] {
            let e = parse(bad, &M).unwrap_err();
            assert!(e.contains(bad) && e.contains("accepted"), "{bad}: {e}");
        }
    }

    #[test]
    fn spec_parses_back() {
        for s in [
            "motor2:reset@3.2s",
            "gateway:returns@5000ms",
            "motor2:stall=5ms@3s",
            "motor2:step=-1ms@2s",
            "motor1:step=+250us@1.5s",
            "motor1:partition@1s",
        ] {
            let f = parse(s, &M).unwrap();
            assert_eq!(parse(&f.spec(&M), &M), Ok(f), "{s} -> {}", f.spec(&M));
        }
    }

    #[test]
    fn parses_the_bus_level_faults() {
        let k = |s: &str| parse(s, &M).map(|f| f.kind);
        assert_eq!(k("motor1:stuck@1s"), Ok(FaultKind::Stuck));
        assert_eq!(k("motor1:release@2s"), Ok(FaultKind::Release));
        assert_eq!(k("motor2:partition@1s"), Ok(FaultKind::Partition));
        assert_eq!(k("motor2:rejoin@1s"), Ok(FaultKind::Rejoin));
        assert_eq!(k("motor2:stall=5ms@3s"), Ok(FaultKind::Stall(5_000_000)));
        assert_eq!(k("motor2:step=+1ms@3s"), Ok(FaultKind::Step(1_000_000)));
        assert_eq!(k("motor2:step=-1ms@3s"), Ok(FaultKind::Step(-1_000_000)));
        let f = |s: &str| parse(s, &M).unwrap();
        let a = bus_actions(&[
            f("motor1:release@2s"),
            f("motor2:step=-1ms@1s"),
            f("motor1:stuck@1500ms"),
            f("gateway:dies@1s"),
        ])
        .unwrap();
        let kinds: Vec<_> = a.iter().map(|f| f.kind).collect();
        assert_eq!(
            kinds,
            [
                FaultKind::Step(-1_000_000),
                FaultKind::Stuck,
                FaultKind::Release
            ]
        );
        assert!(bus_actions(&[f("motor1:release@2s")]).is_err());
        assert!(bus_actions(&[f("motor1:partition@1s"), f("motor1:partition@2s")]).is_err());
        assert!(bus_actions(&[f("motor1:rejoin@1s")]).is_err());
        // Down intervals ignore them.
        assert_eq!(down_intervals(&[f("motor1:stuck@1s")], 1), Ok(vec![]));
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
