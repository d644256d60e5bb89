//! The emulated robot with the simulator's plants: the six release images drive
//! Triskar2 toward a wall and the obstacle node stops it short, as the simulator's
//! `rtcan-sim/tests/triskar2.rs` asserts; the gateway's host link (USART1 + DMA1) in
//! both directions.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use rtcan_emu::engine_ram;
use rtcan_emu::mcu::{Mcu, Timing};
use rtcan_emu::robot::{EmuRobot, HostScript, MODULES};
use rtcan_emu::sim_report::{triskar_run, RunInfo};
use std::path::PathBuf;

fn image(name: &str) -> Vec<u8> {
    let dir = std::env::var_os("RTCAN_EMU_IMAGES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../examples/triskar2/target/thumbv7m-none-eabi/release")
        });
    let p = dir.join(name);
    std::fs::read(&p).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (build the images first: cd examples/triskar2 && cargo build --release)",
            p.display()
        )
    })
}

fn plan() -> rtcan_model::Plan {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robot.toml");
    rtcan_model::Robot::load(&path).unwrap_or_else(|d| panic!("{}", d.render()))
}

fn robot(script: HostScript) -> EmuRobot {
    let mcus = MODULES
        .iter()
        .map(|n| Mcu::new(n, &image(n), Timing::default()).unwrap())
        .collect();
    EmuRobot::new(&plan(), mcus, 1.5, 1, script).unwrap()
}

const MS: u64 = 1_000_000;

fn no_faults(r: &EmuRobot) {
    for m in &r.bus.mcus {
        assert_eq!(
            m.st.unknown,
            vec![],
            "{}: unknown register accesses",
            m.name
        );
        assert_eq!(m.st.fault, None, "{}", m.name);
    }
}

/// Issue 14: each node is an RTIC task at its robot.toml priority. Read off every
/// emulated image's NVIC after boot: the dispatcher interrupt of each node priority
/// level in use on the module (RTIC gives the lowest level the first dispatcher of
/// `rtcan_codegen::rtic_app::DISPATCHERS`) is at the rank of the robot.toml priority
/// (Triskar2's 1, 2, 3 → RTIC 1, 2, 3), the protocol task, the CAN interrupts and the slot
/// timer above the node band (13, 14, 15), and the unused dispatchers left at 0. With one
/// app task per module (before), motor1's and proximity's second level was missing.
#[test]
fn node_tasks_run_at_their_robot_toml_priorities() {
    let mut robot = robot(HostScript::default());
    robot.run_until(20 * MS).unwrap();
    no_faults(&robot);
    let plan = plan();
    let rank = rtcan_codegen::rtic_app::node_priorities(&plan);
    // STM32F103 IRQ numbers (RM0008 table 63) of the dispatchers, in their order.
    let dispatcher_irq: Vec<u16> = rtcan_codegen::rtic_app::DISPATCHERS
        .iter()
        .map(|d| match *d {
            "EXTI2" => 8,
            "EXTI3" => 9,
            "EXTI4" => 10,
            "EXTI9_5" => 23,
            "EXTI15_10" => 40,
            "EXTI0" => 6,
            "TAMPER" => 2,
            "RTC" => 3,
            "FLASH" => 4,
            "RCC" => 5,
            "PVD" => 1,
            "WWDG" => 0,
            other => panic!("IRQ number of {other}"),
        })
        .collect();
    // RTIC logical priority p on 4 NVIC bits.
    let hw = |p: u8| i16::from(16 - p) << 4;
    let mut seen = Vec::new();
    for (mi, name) in MODULES.iter().enumerate() {
        let m = plan.modules.iter().position(|m| m.name == *name).unwrap();
        let scs = &robot.bus.mcus[mi].st.scs;
        let prio = |irq: u16| scs.priority(16 + irq);
        assert_eq!(prio(28), hw(15), "{name}: TIM2, slot timer");
        for irq in [19, 20, 22] {
            assert_eq!(prio(irq), hw(14), "{name}: CAN IRQ {irq}");
        }
        assert_eq!(prio(7), hw(13), "{name}: EXTI1, protocol task");
        let mut levels: Vec<u8> = plan
            .nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.module == m)
            .map(|(i, _)| rank[i])
            .collect();
        levels.sort_unstable();
        levels.dedup();
        for (k, &irq) in dispatcher_irq.iter().enumerate() {
            let want = levels.get(k).map_or(0, |&l| hw(l));
            assert_eq!(prio(irq), want, "{name}: dispatcher IRQ {irq}");
        }
        seen.push((*name, levels));
    }
    // Triskar2's robot.toml, spelled out: both nodes of motor1 (kinematics 2,
    // motor_ctrl1 3) and of proximity (ir_ranger 2, obstacle_avoid 3) at their own level.
    assert_eq!(
        seen,
        [
            ("gateway", vec![1]),
            ("motor1", vec![2, 3]),
            ("motor2", vec![1, 3]),
            ("motor3", vec![3]),
            ("proximity", vec![2, 3]),
            ("psu", vec![1]),
        ]
    );
}

/// The simulator's assertions (rtcan-sim/tests/triskar2.rs,
/// `robot_drives_to_the_wall_and_the_obstacle_node_stops_it_short`) on the emulated
/// run, through the same report type. Differences in the bounds: none for the robot;
/// HRT misses counted after the first second (proximity's start-up, docs/EMULATOR.md);
/// SRT counts from the bus (`sim_report`).
#[test]
fn emulated_robot_drives_to_the_wall_and_stops_short() {
    let mut robot = robot(HostScript::default());
    let mut raw = vec![Vec::new(); 6];
    for ms in (100..=10_000).step_by(100) {
        robot.run_until(ms * MS).unwrap();
        for (i, m) in robot.bus.mcus.iter_mut().enumerate() {
            raw[i].extend(rtcan_emu::rtt::drain(m));
        }
    }
    no_faults(&robot);
    let logs: Vec<Vec<String>> = MODULES
        .iter()
        .zip(&raw)
        .map(|(n, b)| rtcan_emu::rtt::decode(&image(n), b).unwrap())
        .collect();
    let info = RunInfo {
        seconds: 10.0,
        seed: 1,
        wall_x_m: 1.5,
        cpi: 1.5,
    };
    // The engines' own counters, from each image's RAM (found through its DWARF).
    let engines: Vec<_> = MODULES
        .iter()
        .map(|n| Some(engine_ram::locate(&image(n)).unwrap()))
        .collect();
    let sent: Vec<usize> = (0..6)
        .map(|i| robot.bus.log.iter().filter(|(n, _, _)| *n == i).count())
        .collect();
    let r = triskar_run(&mut robot, &plan(), info, &logs, &engines).unwrap();
    eprintln!("{}", rtcan_sim::triskar::report::triskar_text(&r));
    for (m, bus) in r.modules.iter().zip(&sent) {
        let c = &m.counters;
        eprintln!("{}: bus {bus} {c:?}", m.name);
        // The engine counts a frame when its mailbox reports it sent: the bus log and
        // the engine agree but for a frame still on its way to the TX interrupt.
        assert!(
            (*bus as i64 - i64::from(c.tx_frames)).abs() <= 1,
            "{}: engine tx_frames {} vs {bus} on the bus",
            m.name,
            c.tx_frames
        );
        assert_eq!(
            (
                c.tx_failed,
                c.rx_bad_dlc,
                c.rx_bad_sync,
                c.bus_off,
                c.queue_full
            ),
            (0, 0, 0, 0, 0),
            "{}",
            m.name
        );
    }
    // It moved: the host's command reached the wheels through the gateway's USART and
    // DMA, gateway → proximity → motor1 → motors, and went well over halfway to the wall.
    assert!(r.max_x_m > 0.6, "max x {}", r.max_x_m);
    assert!(r.overrides > 10, "overrides {}", r.overrides);
    assert!(
        r.min_gap_m > 0.1 && r.min_gap_m < 0.5,
        "min gap {}",
        r.min_gap_m
    );
    assert!(r.stopped_short());
    let at_7s = r.path.iter().find(|s| s.t_ns >= 7_000_000_000).unwrap();
    assert!(at_7s.cmd_vx > 0.29, "command still forward");
    assert!(at_7s.vx.abs() < 0.01, "but the robot stands: {}", at_7s.vx);
    assert!(at_7s.velocity_vx.abs() < 0.01);
    for h in &r.run.figures.hrt {
        assert!(h.count > 0, "{}", h.name);
    }
    for m in &r.modules {
        assert!(m.synced, "{} synced", m.name);
        assert_eq!(m.safe_trips, 0, "{} tripped", m.name);
    }
    // The motor modules cleared their safe state and are driving/holding normally.
    for m in r.modules.iter().filter(|m| m.name.starts_with("motor")) {
        assert!(!m.safe_now, "{}", m.name);
    }
    // The images make no `proximity_read` calls: its request/reply topics stay silent.
    for c in r
        .run
        .figures
        .srt
        .iter()
        .filter(|c| !c.name.starts_with("proximity_read"))
    {
        assert!(c.count > 50, "{}: {}", c.name, c.count);
        assert_eq!(c.misses, 0, "{}", c.name);
    }
    // The odometry the gateway wrote to its USART tracks the true path.
    let (t, x, _, _) = *r.odometry.last().unwrap();
    let truth = r.path.iter().rev().find(|s| s.t_ns <= t).unwrap();
    assert!(
        (f64::from(x) - truth.pose.x).abs() < 0.05,
        "{x} vs {}",
        truth.pose.x
    );
    assert!(
        r.gateway_rx.1 >= 8 && r.gateway_rx.2 >= 16,
        "{:?}",
        r.gateway_rx
    );
    // The JSON is the simulator's, field for field.
    let v: serde_json::Value =
        serde_json::from_str(&rtcan_sim::triskar::report::triskar_json(&r, 0.2)).unwrap();
    assert_eq!(v["scenario"], "triskar2");
    assert_eq!(v["robot"]["stopped_short"], true);
    assert!(v["run"]["hrt"].as_array().unwrap().len() == 5);
    assert_eq!(v["run"]["cpu"]["design"], "emulated");
}

/// Issue 12 item 4: the gateway's host link. Teleop frames (COBS + CRC-16,
/// `triskar2_link`) go into USART1's RX pin; DMA1 channel 5 moves them into the image's
/// ring; the gateway publishes `teleop` on the bus with the command's velocity. A frame
/// with a bad CRC changes nothing. Odometry frames come out of USART1 TX.
#[test]
fn host_link_teleop_in_odometry_out() {
    let script = HostScript {
        vx: 0.25,
        from_ns: 300 * MS,
        until_ns: 10_000 * MS,
        period_ns: 50 * MS,
    };
    let mut r = robot(script);
    r.run_until(100 * MS).unwrap();
    // A command of 0.9 m/s with its CRC broken: the link decoder must drop it.
    let mut bad = r.teleop_frame(0.9);
    let n = bad.len();
    bad[n - 2] ^= 0x55;
    r.host_bytes(120 * MS, &bad);
    r.run_until(1_200 * MS).unwrap();
    no_faults(&r);
    let g = &r.bus.mcus[0];
    assert_eq!(g.st.usart1.rx_lost, 0);
    assert!(
        r.teleop.iter().all(|&(_, vx)| vx != 0.9),
        "bad CRC accepted"
    );
    // Before the command: zero; from one forwarding period after it: 0.25.
    let before: Vec<f32> = r
        .teleop
        .iter()
        .filter(|t| t.0 < 300 * MS)
        .map(|t| t.1)
        .collect();
    let after: Vec<f32> = r
        .teleop
        .iter()
        .filter(|t| t.0 > 360 * MS)
        .map(|t| t.1)
        .collect();
    assert!(
        before.len() >= 3 && before.iter().all(|&v| v == 0.0),
        "{before:?}"
    );
    assert!(
        after.len() >= 15 && after.iter().all(|&v| v == 0.25),
        "{after:?}"
    );
    let first = r.teleop.iter().find(|t| t.1 == 0.25).unwrap().0;
    assert!(
        (300 * MS..360 * MS).contains(&first),
        "first 0.25 at {first}"
    );
    // The robot answers: the wheels turn, odometry read from USART1 TX moves forward.
    assert!(r.physics.max_x_m > 0.1, "{}", r.physics.max_x_m);
    let odo = &r.host_rx.odometry;
    assert!(odo.len() >= 50, "odometry frames {}", odo.len());
    assert_eq!(r.host_rx.bad, 0);
    let last = odo.last().unwrap();
    assert!(
        last.1 > 0.1 && (f64::from(last.1) - r.physics.base.pose().x).abs() < 0.05,
        "{last:?}"
    );
}

/// The engine counters of every image are found in its DWARF: all 22 fields of
/// `rtcan_core::counters::Counters`, inside the driver's static, in SRAM.
#[test]
fn engine_counters_located_in_every_image() {
    for n in MODULES {
        let elf = image(n);
        let at = engine_ram::locate(&elf).unwrap();
        assert_eq!(at.fields.len(), 22, "{n}: {:?}", at.fields);
        let base = rtcan_emu::elf::symbol(&elf, "_SEGGER_RTT")
            .unwrap()
            .unwrap();
        for (name, a) in &at.fields {
            assert!(
                (0x2000_0000..0x2001_0000).contains(a) && a % 4 == 0,
                "{n}: {name} at {a:#x}"
            );
        }
        // Distinct, consecutive words (the struct is 22 u32).
        let first = at.fields[0].1;
        for (k, (_, a)) in at.fields.iter().enumerate() {
            assert_eq!(*a, first + 4 * k as u32, "{n}");
        }
        let _ = base;
    }
    // Not an image: an error, no panic.
    assert!(engine_ram::locate(b"not an elf").is_err());
}

/// docs/EMULATOR.md "Findings": proximity misses HRT slots. The evidence, from the
/// emulated RAM: the `proximity` topic's counters (rtcan-pubsub `TopicStats`) written by
/// the app (publish, replace) and by the engine's slot prepare (nothing to send), with
/// their exact emulated times, against the frames on the bus.
/// Synchronous HRT publishers (R2P §3.4.5, issue 14) in the real images: the proximity
/// app is woken `lead` before each `proximity` slot by the slot timer's prepare alarm
/// (boards/app `Driver`), not by the 1 ms SysTick. Traced through the stores into the
/// topic's `TopicStats` in proximity's RAM (located through the image's DWARF, exact
/// emulated time and PC) against the frames on the bus. Before (docs/EMULATOR.md
/// "Findings"): every 200 ms a sample published 0.56 ms after its slot's prepare, an
/// empty slot and a replaced sample (15 of each in 3 s). Now: none after start-up, and
/// every sample is on the bus at most `lead` + 20 µs after it was published.
#[test]
fn proximity_hrt_misses_traced() {
    let mut robot = robot(HostScript::default());
    let plan = plan();
    let topic = plan.topics.iter().find(|t| t.name == "proximity").unwrap();
    let lead_ns = topic.lead_ns.unwrap();
    let elf = image("proximity");
    let stats = engine_ram::find_struct(&elf, "PROXIMITY", "TopicStats", "hrt_replaced").unwrap();
    let addr = |f: &str| stats.iter().find(|(n, _)| n == f).unwrap().1;
    let (published, replaced, nothing) = (
        addr("published"),
        addr("hrt_replaced"),
        addr("nothing_to_send"),
    );
    let p = &mut robot.bus.mcus[4];
    for a in [published, replaced, nothing] {
        p.watch_writes(a, 4).unwrap();
    }
    p.trace_exceptions();
    robot.run_until(3_000 * MS).unwrap();
    no_faults(&robot);
    let p = &robot.bus.mcus[4];
    let mut events: Vec<(u64, String)> =
        p.st.writes
            .iter()
            .map(|w| {
                let what = if w.addr == published {
                    "publish"
                } else if w.addr == replaced {
                    "REPLACED (previous sample never sent)"
                } else {
                    "slot prepare: NOTHING to send"
                };
                (
                    w.time_ps / 1000,
                    format!("{what} #{} pc {:#010x}", w.value, w.pc),
                )
            })
            .collect();
    let bit_ns = robot.bus.bit_ps / 1000;
    // The topic's first frames (fragment 0 of its message ID), from proximity.
    let hrt_sofs: Vec<u64> = robot
        .bus
        .log
        .iter()
        .filter(|(n, f, _)| {
            *n == 4
                && rtcan_core::CanId::from_raw(f.id)
                    .is_some_and(|id| id.msg_id() == topic.msg_id && id.fragment() == 0)
        })
        .map(|(_, _, sof)| sof * bit_ns)
        .collect();
    for &t in &hrt_sofs {
        events.push((t, "bus: proximity frame".to_string()));
    }
    events.sort();
    for (t, e) in events
        .iter()
        .filter(|(t, _)| (1_000_000_000..1_100_000_000).contains(t))
    {
        eprintln!("{:>12.3} ms  {e}", *t as f64 / 1e6);
    }
    // After start-up (the first second: sync, master heard, the grid).
    let after = |s: &str| {
        events
            .iter()
            .filter(|(t, e)| *t >= 1_000_000_000 && e.starts_with(s))
            .count()
    };
    assert_eq!(after("slot prepare"), 0, "empty proximity slots");
    assert_eq!(after("REPLACED"), 0, "samples replaced unsent");
    // 2 s at 25 Hz: 50 samples, each on the bus.
    assert!(
        (49..=51).contains(&after("publish")),
        "{}",
        after("publish")
    );
    assert_eq!(after("publish"), after("bus"));
    // Sample age: the publish store → the SOF of the next proximity frame.
    let mut ages = Vec::new();
    for (t, _) in events
        .iter()
        .filter(|(t, e)| *t >= 1_000_000_000 && e.starts_with("publish"))
    {
        let Some(sof) = hrt_sofs.iter().find(|&&s| s > *t) else {
            continue;
        };
        ages.push(sof - t);
    }
    let max = *ages.iter().max().unwrap();
    let min = *ages.iter().min().unwrap();
    let mean = ages.iter().sum::<u64>() as f64 / ages.len() as f64;
    eprintln!(
        "proximity sample age at transmission (publish -> SOF), {} samples: min {:.3} us, mean {:.3} us, max {:.3} us (lead {} us)",
        ages.len(),
        min as f64 / 1e3,
        mean / 1e3,
        max as f64 / 1e3,
        lead_ns / 1000
    );
    assert!(max <= lead_ns + 20_000, "max age {max} ns");
    // Where the time between the due time and the publish goes: the slot timer's alarm
    // (TIM2, exception 44) at the due time, the protocol task it pends (EXTI1, 23), the
    // app task (RTIC dispatcher EXTI2, 24) it wakes, then the app's poll up to the publish
    // store. Due time = the slot's SOF − lead (the SOF follows the boundary by ≈ 1 µs).
    let entries = robot.bus.mcus[4].st.entries.clone().unwrap_or_default();
    let last_before = |exc: u16, t: u64| {
        entries
            .iter()
            .rev()
            .find(|(at, e)| *e == exc && at / 1000 <= t)
            .map(|(at, _)| at / 1000)
    };
    let (mut entry, mut poll) = (Vec::new(), Vec::new());
    for (t, _) in events
        .iter()
        .filter(|(t, e)| *t >= 1_000_000_000 && e.starts_with("publish"))
    {
        let Some(&sof) = hrt_sofs.iter().find(|&&s| s > *t) else {
            continue;
        };
        let due = sof - lead_ns;
        let (Some(app), Some(tim)) = (last_before(24, *t), last_before(44, *t)) else {
            continue;
        };
        let proto = last_before(23, app).unwrap_or(0);
        entry.push(app as i64 - due as i64);
        poll.push(*t as i64 - app as i64);
        if entry.len() <= 3 {
            // Exceptions taken while the app ran up to the publish (they preempt it).
            let mut within = std::collections::BTreeMap::<u16, u32>::new();
            for (at, e) in &entries {
                if (app..*t).contains(&(at / 1000)) && *e != 24 {
                    *within.entry(*e).or_insert(0) += 1;
                }
            }
            eprintln!(
                "due {due} ns: last TIM2 entry {:+} ns, protocol entry {:+} ns, app entry {:+} ns, publish {:+} ns; exceptions between app entry and publish: {within:?}",
                tim as i64 - due as i64,
                proto as i64 - due as i64,
                app as i64 - due as i64,
                *t as i64 - due as i64
            );
        }
    }
    let stats = |v: &[i64]| {
        (
            *v.iter().min().unwrap_or(&0),
            v.iter().sum::<i64>() / v.len().max(1) as i64,
            *v.iter().max().unwrap_or(&0),
        )
    };
    eprintln!(
        "due -> app task entry {:?} ns, app entry -> publish {:?} ns (min, mean, max; {} samples)",
        stats(&entry),
        stats(&poll),
        poll.len()
    );
    // The finding (docs/EMULATOR.md, "Findings"): the alarm wakes the app promptly; the
    // ≈ 190 µs to the publish are spent after the app task's entry (its poll up to the
    // store, and the exceptions preempting it).
    assert_eq!(entry.len(), 50);
    assert!(
        stats(&entry).2 < 100_000,
        "app entered late: {:?}",
        stats(&entry)
    );
    assert!(stats(&poll).0 > 100_000, "app fast: {:?}", stats(&poll));
    // Published before the slot's frame is prepared (half a slot ahead).
    assert!(min > plan.bus.slot_ns / 2, "min age {min} ns");
}
