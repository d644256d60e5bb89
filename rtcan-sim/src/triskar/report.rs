//! Report of a triskar2 run: the bus tables of every scenario, then the robot: what
//! the gateway commanded, what the obstacle node let through, the path, the gap to the
//! wall, and each module's engine counters. Text, JSON (docs/SIM.md) and an SVG path.
use std::fmt::Write as _;

use super::TriskarRun;
use crate::report::{json_str, num, run_json, text};

fn s(ns: u64) -> f64 {
    ns as f64 / 1e9
}

/// Terminal report.
pub fn triskar_text(r: &TriskarRun) -> String {
    let mut o = String::new();
    let c = &r.config;
    let _ = writeln!(
        o,
        "host script: gateway forwards vx = {:.2} m/s from {:.1} s to {:.1} s; wall at x = {:.2} m{}",
        c.command_vx,
        c.command_from_s,
        c.command_until_s,
        c.wall_x_m,
        c.gateway_dies_at_s
            .map_or(String::new(), |t| format!("; gateway (master) dies at {t:.1} s"))
    );
    if !c.faults.is_empty() || c.guardian {
        let specs: Vec<String> = c.faults.iter().map(|f| f.spec(&super::MODULES)).collect();
        let _ = writeln!(
            o,
            "faults: {}{}",
            if specs.is_empty() {
                "none".to_string()
            } else {
                specs.join(" ")
            },
            if c.guardian {
                "; every module has a bus guardian"
            } else {
                ""
            }
        );
    }
    let masters: Vec<&str> = r
        .modules
        .iter()
        .filter(|m| m.master)
        .map(|m| m.name)
        .collect();
    let _ = writeln!(
        o,
        "sync on the wire: {} syncs, {} cycles with two syncs, longest gap {:.1} ms; frames out of their slots (wire check) {} of {}; masters at the end: {}",
        r.syncs.syncs,
        r.syncs.doubled,
        r.syncs.longest_gap.0 as f64 / 1e6,
        r.slots_live.0,
        r.slots_live.1,
        if masters.is_empty() { "none".to_string() } else { masters.join(" ") }
    );
    let _ = writeln!(o);
    o.push_str(&text(&r.run));
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "path (every 0.5 s)   x [m]    y [m]  theta  vx [m/s]  gap [m]  teleop vx  velocity vx"
    );
    // Rows at least 0.5 s apart (the path is sampled every 50 ms, more sparsely in
    // long runs).
    let mut next = 0;
    for p in r.path.iter().filter(|p| {
        let due = p.t_ns >= next;
        if due {
            next = p.t_ns - p.t_ns % 500_000_000 + 500_000_000;
        }
        due
    }) {
        let _ = writeln!(
            o,
            "  t = {:5.2} s  {:>8.3} {:>8.3} {:>6.3} {:>9.3} {:>8.3} {:>10.2} {:>12.2}",
            s(p.t_ns),
            p.pose.x,
            p.pose.y,
            p.pose.theta,
            p.vx,
            p.gap_m,
            p.cmd_vx,
            p.velocity_vx
        );
    }
    let _ = writeln!(
        o,
        "obstacle override: {} velocity messages limited by obstacle_avoid",
        r.overrides
    );
    let _ = writeln!(
        o,
        "max x {:.3} m; min gap body-wall {:.3} m; final gap {:.3} m; stopped short of the wall: {}",
        r.max_x_m,
        r.min_gap_m,
        r.final_gap_m,
        if r.stopped_short() { "yes" } else { "NO" }
    );
    if let (Some(&(t, x, y, th)), Some(truth)) = (r.odometry.last(), r.path.last()) {
        let _ = writeln!(
            o,
            "odometry at the gateway ({:.2} s): x {x:.3} y {y:.3} theta {th:.3} (true x {:.3} y {:.3})",
            s(t),
            truth.pose.x,
            truth.pose.y
        );
    }
    let (prox, bat, log, last) = &r.gateway_rx;
    let _ = writeln!(
        o,
        "gateway received: {} odometry, {prox} proximity, {bat} battery, {log} log (last: \"{last}\")",
        r.odometry_rx
    );
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "module     synced  safe trips  safe now   rx deliv  tx frames  aborted  dl missed  hrt empty  hrt late  sync missed  overruns  wheel [rad/s]"
    );
    for m in &r.modules {
        let k = &m.counters;
        let _ = writeln!(
            o,
            "{:<10} {:>6} {:>11} {:>9} {:>10} {:>10} {:>8} {:>10} {:>10} {:>9} {:>12} {:>9}  {}",
            m.name,
            m.synced,
            m.safe_trips,
            m.safe_now,
            k.rx_delivered,
            k.tx_frames,
            k.tx_aborted,
            k.deadline_missed,
            k.hrt_empty,
            k.hrt_late,
            k.sync_missed,
            k.rx_overrun,
            m.motor.map_or("-".into(), |(w, _)| format!("{w:.3}"))
        );
    }
    o
}

/// JSON report (fields in docs/SIM.md).
pub fn triskar_json(r: &TriskarRun, speed_x: f64) -> String {
    let c = &r.config;
    let path: Vec<String> = r
        .path
        .iter()
        .map(|p| {
            format!(
                "{{\"t\":{},\"x\":{},\"y\":{},\"theta\":{},\"vx\":{},\"gap\":{},\"teleop_vx\":{},\"velocity_vx\":{}}}",
                num(s(p.t_ns)),
                num(p.pose.x),
                num(p.pose.y),
                num(p.pose.theta),
                num(p.vx),
                num(p.gap_m),
                num(f64::from(p.cmd_vx)),
                num(f64::from(p.velocity_vx))
            )
        })
        .collect();
    let modules: Vec<String> = r
        .modules
        .iter()
        .map(|m| {
            let k = &m.counters;
            format!(
                "{{\"name\":{},\"synced\":{},\"safe_trips\":{},\"safe_now\":{},\"counters\":{{\"rx_delivered\":{},\"tx_frames\":{},\"tx_aborted\":{},\"tx_failed\":{},\"deadline_missed\":{},\"queue_full\":{},\"hrt_empty\":{},\"hrt_late\":{},\"sync_missed\":{},\"rx_overrun\":{},\"rx_errors\":{}}},\"wheel_rad_s\":{}}}",
                json_str(m.name),
                m.synced,
                m.safe_trips,
                m.safe_now,
                k.rx_delivered,
                k.tx_frames,
                k.tx_aborted,
                k.tx_failed,
                k.deadline_missed,
                k.queue_full,
                k.hrt_empty,
                k.hrt_late,
                k.sync_missed,
                k.rx_overrun,
                k.rx_unknown_id + k.rx_bad_dlc + k.rx_out_of_order + k.rx_other_transfer + k.rx_incomplete
                    + k.rx_bad_size + k.rx_bad_sync + k.rx_bad_heartbeat,
                m.motor.map_or("null".into(), |(w, _)| num(f64::from(w)))
            )
        })
        .collect();
    format!(
        "{{\"scenario\":\"triskar2\",\"seconds\":{},\"seed\":{},\"wall_x\":{},\"command_vx\":{},\"command_from_s\":{},\"command_until_s\":{},\"gateway_dies_at_s\":{},\"run\":{},\"robot\":{{\"max_x\":{},\"min_gap\":{},\"final_gap\":{},\"stopped_short\":{},\"overrides\":{},\"odometry_rx\":{},\"path\":[{}]}},\"modules\":[{}],\"faults\":[{}],\"guardian\":{},\"sync\":{{\"syncs\":{},\"doubled_syncs\":{},\"longest_sync_gap_ms\":{},\"slot_violations\":{},\"slots_checked\":{},\"masters_at_end\":[{}]}},\"speed_x_real_time\":{}}}",
        c.sim.seconds,
        c.sim.seed,
        num(c.wall_x_m),
        num(f64::from(c.command_vx)),
        num(c.command_from_s),
        num(c.command_until_s),
        c.gateway_dies_at_s.map_or("null".into(), num),
        run_json(&r.run),
        num(r.max_x_m),
        num(r.min_gap_m),
        num(r.final_gap_m),
        r.stopped_short(),
        r.overrides,
        r.odometry_rx,
        path.join(","),
        modules.join(","),
        c.faults
            .iter()
            .map(|f| format!("\"{}\"", json_str(&f.spec(&super::MODULES))))
            .collect::<Vec<_>>()
            .join(","),
        c.guardian,
        r.syncs.syncs,
        r.syncs.doubled,
        num(r.syncs.longest_gap.0 as f64 / 1e6),
        r.slots_live.0,
        r.slots_live.1,
        r.modules
            .iter()
            .filter(|m| m.master)
            .map(|m| format!("\"{}\"", m.name))
            .collect::<Vec<_>>()
            .join(","),
        num(speed_x)
    )
}

/// Top view of the path (x, y in m) with the wall and the final footprint.
pub fn path_svg(r: &TriskarRun) -> String {
    let (w, h, m) = (640.0, 400.0, 40.0);
    let wall = r.config.wall_x_m;
    let body = crate::plant::OmniGeometry::TRISKAR2.body_radius_m;
    let x0 = -0.5;
    let x1 = (wall + 0.3).min(r.max_x_m.max(0.0) + 1.0).max(1.0);
    let (y0, y1) = (-1.0, 1.0);
    let sx = (w - 2.0 * m) / (x1 - x0);
    let sy = (h - 2.0 * m) / (y1 - y0);
    let k = sx.min(sy);
    let px = |x: f64| m + (x - x0) * k;
    let py = |y: f64| h / 2.0 - y * k;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">"
    );
    let _ = writeln!(o, "<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>");
    let _ = writeln!(
        o,
        "<text x=\"{m}\" y=\"20\">triskar2: path (top view, m), min gap {:.3} m</text>",
        r.min_gap_m
    );
    // Metre grid.
    let mut gx = x0.ceil();
    while gx <= x1 {
        let _ = writeln!(
            o,
            "<line x1=\"{0:.1}\" y1=\"{1:.1}\" x2=\"{0:.1}\" y2=\"{2:.1}\" stroke=\"#ddd\"/><text x=\"{0:.1}\" y=\"{3:.1}\">{gx}</text>",
            px(gx),
            py(y1),
            py(y0),
            py(y0) + 14.0
        );
        gx += 1.0;
    }
    if wall <= x1 {
        let _ = writeln!(
            o,
            "<line x1=\"{0:.1}\" y1=\"{1:.1}\" x2=\"{0:.1}\" y2=\"{2:.1}\" stroke=\"black\" stroke-width=\"4\"/><text x=\"{3:.1}\" y=\"{4:.1}\">wall</text>",
            px(wall),
            py(y1),
            py(y0),
            px(wall) - 30.0,
            py(y1) - 4.0
        );
    }
    let pts: Vec<String> = r
        .path
        .iter()
        .map(|p| format!("{:.1},{:.1}", px(p.pose.x), py(p.pose.y)))
        .collect();
    let _ = writeln!(
        o,
        "<polyline points=\"{}\" fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"2\"/>",
        pts.join(" ")
    );
    let odo: Vec<String> = r
        .odometry
        .iter()
        .step_by(5)
        .map(|&(_, x, y, _)| format!("{:.1},{:.1}", px(f64::from(x)), py(f64::from(y))))
        .collect();
    let _ = writeln!(
        o,
        "<polyline points=\"{}\" fill=\"none\" stroke=\"#ff7f0e\" stroke-dasharray=\"4 3\"/>",
        odo.join(" ")
    );
    if let Some(p) = r.path.last() {
        let _ = writeln!(
            o,
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"{:.1}\" fill=\"none\" stroke=\"#1f77b4\"/>",
            px(p.pose.x),
            py(p.pose.y),
            body * k
        );
    }
    let _ = writeln!(
        o,
        "<text x=\"{m}\" y=\"{}\" fill=\"#1f77b4\">true path (final footprint circle)</text><text x=\"{}\" y=\"{}\" fill=\"#ff7f0e\">odometry at the gateway</text>",
        h - 8.0,
        m + 240.0,
        h - 8.0
    );
    o.push_str("</svg>\n");
    o
}
