//! Report of a triskar2 run: the bus tables of every scenario, then the robot: what
//! the gateway commanded, what the obstacle node let through, the path, the gap to the
//! wall, and each module's engine counters. Text, JSON (docs/SIM.md) and an SVG path.
use std::fmt::Write as _;

use super::TriskarRun;
use crate::report::{num, run_value, text};
use serde_json::json;

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
    let ages: Vec<String> = r
        .modules
        .iter()
        .flat_map(|m| {
            m.sample_age.iter().map(move |a| {
                format!(
                    "{}/{} max {:.1} mean {:.1}",
                    m.name,
                    a.topic,
                    a.stat.max_ns as f64 / 1e3,
                    a.stat.mean_ns() / 1e3
                )
            })
        })
        .collect();
    if !ages.is_empty() {
        let _ = writeln!(
            o,
            "HRT sample age at transmission (publish -> SOF), us: {}",
            ages.join("; ")
        );
    }
    o
}

/// JSON report (fields in docs/SIM.md).
pub fn triskar_json(r: &TriskarRun, speed_x: f64) -> String {
    triskar_value(r, speed_x).to_string()
}

/// JSON report as a value.
pub fn triskar_value(r: &TriskarRun, speed_x: f64) -> serde_json::Value {
    let c = &r.config;
    let path: Vec<serde_json::Value> = r
        .path
        .iter()
        .map(|p| {
            json!({
                "t": num(s(p.t_ns)),
                "x": num(p.pose.x),
                "y": num(p.pose.y),
                "theta": num(p.pose.theta),
                "vx": num(p.vx),
                "gap": num(p.gap_m),
                "teleop_vx": num(f64::from(p.cmd_vx)),
                "velocity_vx": num(f64::from(p.velocity_vx)),
            })
        })
        .collect();
    let modules: Vec<serde_json::Value> = r
        .modules
        .iter()
        .map(|m| {
            let k = &m.counters;
            json!({
                "name": m.name,
                "synced": m.synced,
                "safe_trips": m.safe_trips,
                "safe_now": m.safe_now,
                "counters": {
                    "rx_delivered": k.rx_delivered,
                    "tx_frames": k.tx_frames,
                    "tx_aborted": k.tx_aborted,
                    "tx_failed": k.tx_failed,
                    "deadline_missed": k.deadline_missed,
                    "queue_full": k.queue_full,
                    "hrt_empty": k.hrt_empty,
                    "hrt_late": k.hrt_late,
                    "sync_missed": k.sync_missed,
                    "rx_overrun": k.rx_overrun,
                    "rx_errors": k.rx_unknown_id + k.rx_bad_dlc + k.rx_out_of_order
                        + k.rx_other_transfer + k.rx_incomplete + k.rx_bad_size
                        + k.rx_bad_sync + k.rx_bad_heartbeat,
                },
                "wheel_rad_s": m.motor.map_or(serde_json::Value::Null, |(w, _)| num(f64::from(w))),
                "sample_age": m.sample_age.iter().map(|a| json!({
                    "topic": a.topic,
                    "count": a.stat.count,
                    "max_ns": a.stat.max_ns,
                    "mean_ns": num(a.stat.mean_ns()),
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    let faults: Vec<String> = c.faults.iter().map(|f| f.spec(&super::MODULES)).collect();
    let masters: Vec<&str> = r
        .modules
        .iter()
        .filter(|m| m.master)
        .map(|m| m.name)
        .collect();
    json!({
        "scenario": "triskar2",
        "seconds": c.sim.seconds,
        "seed": c.sim.seed,
        "wall_x": num(c.wall_x_m),
        "command_vx": num(f64::from(c.command_vx)),
        "command_from_s": num(c.command_from_s),
        "command_until_s": num(c.command_until_s),
        "gateway_dies_at_s": c.gateway_dies_at_s.map_or(serde_json::Value::Null, num),
        "run": run_value(&r.run),
        "robot": {
            "max_x": num(r.max_x_m),
            "min_gap": num(r.min_gap_m),
            "final_gap": num(r.final_gap_m),
            "stopped_short": r.stopped_short(),
            "overrides": r.overrides,
            "odometry_rx": r.odometry_rx,
            "path": path,
        },
        "modules": modules,
        "faults": faults,
        "guardian": c.guardian,
        "sync": {
            "syncs": r.syncs.syncs,
            "doubled_syncs": r.syncs.doubled,
            "longest_sync_gap_ms": num(r.syncs.longest_gap.0 as f64 / 1e6),
            "slot_violations": r.slots_live.0,
            "slots_checked": r.slots_live.1,
            "masters_at_end": masters,
        },
        "speed_x_real_time": num(speed_x),
    })
}

/// The robot's path seen from above (m): the true path and the odometry the gateway
/// received, the wall, and the final footprint; the CSV has both tracks.
pub fn path_plot(r: &TriskarRun) -> Result<crate::plot::Plot, String> {
    use crate::plot::{colour, svg};
    use plotters::prelude::*;
    let wall = r.config.wall_x_m;
    let body = crate::plant::OmniGeometry::TRISKAR2.body_radius_m;
    let x0 = -0.5;
    let x1 = (wall + 0.3).min(r.max_x_m.max(0.0) + 1.0).max(1.0);
    let (y0, y1) = (-1.0, 1.0);
    let truth: Vec<(f64, f64)> = r.path.iter().map(|p| (p.pose.x, p.pose.y)).collect();
    let odo: Vec<(f64, f64)> = r
        .odometry
        .iter()
        .map(|&(_, x, y, _)| (f64::from(x), f64::from(y)))
        .collect();
    let last = truth.last().copied();
    // Metres equal on both axes: the canvas keeps the plot's aspect ratio.
    let w = 820u32;
    let h = ((f64::from(w) - 90.0) * (y1 - y0) / (x1 - x0) + 110.0).clamp(260.0, 900.0) as u32;
    let picture = svg(w, h, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!(
                    "triskar2: path from above, min gap to the wall {:.3} m",
                    r.min_gap_m
                ),
                ("sans-serif", 16),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("x [m]")
            .y_desc("y [m]")
            .draw()?;
        let (ct, co) = (colour(0), colour(4));
        chart
            .draw_series(odo.iter().map(|&p| Circle::new(p, 3, co.stroke_width(1))))?
            .label("odometry at the gateway")
            .legend(move |(x, y)| Circle::new((x + 8, y), 3, co.stroke_width(1)));
        // The true path on top of the odometry it should match.
        chart
            .draw_series(LineSeries::new(truth.iter().copied(), ct.stroke_width(2)))?
            .label("true path")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], ct.stroke_width(2)));
        if wall <= x1 {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    [(wall, y0), (wall, y1)],
                    BLACK.stroke_width(4),
                )))?
                .label(format!("wall (x = {wall:.2} m)"))
                .legend(|(x, y)| {
                    PathElement::new([(x + 8, y - 6), (x + 8, y + 6)], BLACK.stroke_width(4))
                });
        }
        if let Some((x, y)) = last {
            // The footprint as a polygon in data coordinates (a circle element's radius
            // is in pixels).
            let ring: Vec<(f64, f64)> = (0..=48)
                .map(|k| {
                    let a = f64::from(k) / 48.0 * std::f64::consts::TAU;
                    (x + body * a.cos(), y + body * a.sin())
                })
                .collect();
            chart
                .draw_series(std::iter::once(PathElement::new(ring, ct.stroke_width(1))))?
                .label("final footprint")
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, ct.stroke_width(1)));
        }
        crate::plot::legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    })?;
    let mut csv = String::from("track,t_s,x_m,y_m\n");
    for p in r.path.iter() {
        let _ = writeln!(csv, "true,{},{},{}", s(p.t_ns), p.pose.x, p.pose.y);
    }
    for &(t, x, y, _) in r.odometry.iter() {
        let _ = writeln!(csv, "odometry,{},{x},{y}", s(t));
    }
    Ok(crate::plot::Plot { svg: picture, csv })
}
