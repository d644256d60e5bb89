//! `battery_monitor`: samples the pack at 10 Hz, publishes `battery` at 1 Hz and a
//! `log` line at 2 Hz (both NRT). It needs the pack's sensors of the module it runs on
//! ([`PsuHw`]).
use core::fmt::Write as _;

use rtcan::robot_toml as msg;
use rtcan::robot_toml::nodes::battery_monitor as n;

use crate::app::{run_node, AppStats, Every, MS};
use crate::battery::{BatteryConfig, BatteryNode, BatteryStatus};
use crate::Nanos;

/// The PSU module's hardware: the pack's voltage and current sensors.
pub trait PsuHw {
    /// Terminal voltage, V.
    fn voltage_v(&mut self) -> f32;
    /// Discharge current, A (positive out of the battery).
    fn current_a(&mut self) -> f32;
}

pub use PsuHw as Hw;

/// The node's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Task {
    node: BatteryNode,
    sample: Every,
    battery: Every,
    log: Every,
    status: Option<BatteryStatus>,
    pub stats: AppStats,
}

/// At power-on.
pub const fn new() -> Task {
    Task {
        node: BatteryNode::new(BatteryConfig::TRISKAR2),
        sample: Every::new(100 * MS),
        battery: Every::new(1_000 * MS),
        log: Every::new(500 * MS),
        status: None,
        stats: AppStats {
            published: 0,
            publish_errors: 0,
        },
    }
}

impl Task {
    /// Latest battery estimate.
    pub const fn status(&self) -> Option<BatteryStatus> {
        self.status
    }
}

/// Runs what is due; returns when the next step is.
pub fn poll(t: &mut Task, now: Nanos, hw: &mut impl Hw) -> Nanos {
    let running = run_node(&n::NODE, &n::module::STATUS);
    if t.sample.due(now) {
        t.status = Some(t.node.step(now, hw.voltage_v(), hw.current_a()));
    }
    if let (true, Some(s)) = (t.battery.due(now), t.status) {
        if running {
            let b = msg::Battery {
                mv: s.mv(),
                ma: s.ma(),
                pct: s.pct(),
            };
            t.stats.count(n::battery_pub().send(b, now));
        }
    }
    if let (true, Some(s)) = (t.log.due(now), t.status) {
        if running {
            t.stats.count(n::log_pub().send(log_line(&s), now));
        }
    }
    t.sample.next().min(t.battery.next()).min(t.log.next())
}

/// Log codes of the `log` topic.
pub const LOG_STATUS: u16 = 1;
/// The battery is low.
pub const LOG_LOW: u16 = 2;

/// A `log` line describing the battery, e.g. `battery 24.61V 2.10A 91%`.
pub fn log_line(s: &BatteryStatus) -> msg::LogLine {
    let mut text = Text::default();
    let _ = write!(
        text,
        "battery {}V {}A {}%",
        Fixed2(s.voltage_v),
        Fixed2(s.current_a),
        s.pct()
    );
    msg::LogLine {
        level: if s.low { 2 } else { 1 },
        code: if s.low { LOG_LOW } else { LOG_STATUS },
        text: text.buf,
    }
}

/// A value printed with two decimals from integer hundredths: core's float formatting
/// (`{:.2}`) costs about 10 KiB of flash, a third of a module image.
struct Fixed2(f32);

impl core::fmt::Display for Fixed2 {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        // `as` saturates (and NaN gives 0): out-of-range values print clamped.
        let c = libm::roundf(self.0 * 100.0) as i32;
        let sign = if c < 0 { "-" } else { "" };
        let a = c.unsigned_abs();
        write!(f, "{sign}{}.{:02}", a / 100, a % 100)
    }
}

/// A fixed 29-byte text buffer (zero padded; longer text is cut).
#[derive(Default)]
struct Text {
    buf: [u8; 29],
    len: usize,
}

impl core::fmt::Write for Text {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for b in s.bytes() {
            if let Some(slot) = self.buf.get_mut(self.len) {
                *slot = b;
                self.len += 1;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn status(voltage_v: f32, current_a: f32, percent: f32, low: bool) -> BatteryStatus {
        BatteryStatus {
            voltage_v,
            current_a,
            percent,
            low,
            consumed_mah: 0.0,
        }
    }

    fn text(l: &msg::LogLine) -> &str {
        let end = l.text.iter().position(|&b| b == 0).unwrap_or(l.text.len());
        core::str::from_utf8(&l.text[..end]).unwrap()
    }

    #[test]
    fn log_line_prints_two_decimals_like_the_float_format() {
        let l = log_line(&status(24.614, 2.1, 91.4, false));
        assert_eq!(text(&l), "battery 24.61V 2.10A 91%");
        assert_eq!((l.level, l.code), (1, LOG_STATUS));
        let l = log_line(&status(21.996, -0.5, 9.6, true));
        assert_eq!(text(&l), "battery 22.00V -0.50A 10%");
        assert_eq!((l.level, l.code), (2, LOG_LOW));
        let l = log_line(&status(0.004, -0.004, 0.0, true));
        assert_eq!(text(&l), "battery 0.00V 0.00A 0%");
    }
}
