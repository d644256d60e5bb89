//! A candump log as a [`Link`], replayed at `speed` times its recorded pace (0: as fast
//! as it reads). Remote, error and CAN FD frames are skipped and counted, malformed lines
//! counted; neither stops the replay.
use std::io::BufRead;
use std::path::Path;
use std::time::{Duration, Instant};

use rtcan_core::Nanos;
use rtcan_sim::candump::{classify, Line};

use crate::link::{Link, Stamped};

/// Frames handed out per `recv` at most.
const CHUNK: usize = 256;
/// Longest wait per `recv` when paced, so callers stay responsive.
const MAX_WAIT: Duration = Duration::from_millis(50);

/// A log being replayed.
pub struct ReplayLink {
    lines: Box<dyn BufRead>,
    speed: f64,
    started: Instant,
    first_ns: Option<Nanos>,
    now_ns: Nanos,
    held: Option<Stamped>,
    /// Frames RTCAN never sends (remote, error, FD), skipped.
    pub skipped: u64,
    /// Lines that did not parse, skipped.
    pub malformed: u64,
    ended: bool,
}

impl ReplayLink {
    /// Opens the log at `path` (`-`: standard input).
    pub fn open(path: &Path, speed: f64) -> Result<Self, String> {
        let lines: Box<dyn BufRead> = if path.as_os_str() == "-" {
            Box::new(std::io::BufReader::new(std::io::stdin()))
        } else {
            let f = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
            Box::new(std::io::BufReader::new(f))
        };
        Ok(Self::from_reader(lines, speed))
    }

    /// Replays the log text read from `lines`.
    pub fn from_reader(lines: Box<dyn BufRead>, speed: f64) -> Self {
        ReplayLink {
            lines,
            speed,
            started: Instant::now(),
            first_ns: None,
            now_ns: 0,
            held: None,
            skipped: 0,
            malformed: 0,
            ended: false,
        }
    }

    fn next_frame(&mut self) -> Result<Option<Stamped>, String> {
        if let Some(s) = self.held.take() {
            return Ok(Some(s));
        }
        let mut text = String::new();
        loop {
            text.clear();
            // Bounded line length: a corrupt log cannot make one line take all memory.
            let n = <&mut dyn BufRead as std::io::Read>::take(&mut *self.lines, 4096)
                .read_line(&mut text)
                .map_err(|e| format!("reading the log: {e}"))?;
            if n == 0 {
                return Ok(None);
            }
            match classify(&text) {
                Ok(Line::Frame(e)) => {
                    return Ok(Some(Stamped {
                        time_ns: e.time_ns,
                        frame: e.frame,
                    }))
                }
                Ok(Line::Blank) => {}
                Ok(Line::Skipped(_)) => self.skipped += 1,
                Err(_) => self.malformed += 1,
            }
        }
    }

    /// Wall-clock time at which a frame stamped `t` is due.
    fn due(&self, t: Nanos) -> Duration {
        let rel = t.saturating_sub(self.first_ns.unwrap_or(t));
        Duration::from_secs_f64(rel as f64 * 1e-9 / self.speed)
    }
}

impl Link for ReplayLink {
    fn recv(&mut self) -> Result<Option<Vec<Stamped>>, String> {
        if self.ended {
            return Ok(None);
        }
        let mut out = Vec::new();
        while out.len() < CHUNK {
            let Some(s) = self.next_frame()? else {
                self.ended = out.is_empty();
                return Ok(if out.is_empty() { None } else { Some(out) });
            };
            self.first_ns.get_or_insert(s.time_ns);
            if self.speed > 0.0 {
                let due = self.due(s.time_ns);
                let elapsed = self.started.elapsed();
                if due > elapsed {
                    if !out.is_empty() {
                        self.held = Some(s);
                        break;
                    }
                    std::thread::sleep((due - elapsed).min(MAX_WAIT));
                    if due > self.started.elapsed() {
                        self.held = Some(s);
                        break;
                    }
                }
            }
            self.now_ns = s.time_ns;
            out.push(s);
        }
        Ok(Some(out))
    }

    fn publish(&mut self, topic: &str, _payload: &[u8]) -> Result<(), String> {
        Err(format!(
            "cannot publish `{topic}`: a replayed log is read-only (publish with --sim)"
        ))
    }

    fn now_ns(&self) -> Nanos {
        self.now_ns
    }
}
