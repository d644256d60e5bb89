//! The live screen of `rtcan monitor` (ratatui): modules (heartbeat age, state,
//! fingerprint match), topics (count, rate, transfer time, last value) and the bus load
//! by class. [`draw`] is the whole picture from one [`View`]; the terminal loop only
//! feeds it, so the picture is tested on ratatui's `TestBackend` and printed by
//! `--once --screen` without a terminal.
use std::io::IsTerminal as _;
use std::time::Duration;

use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
use ratatui::layout::{Constraint, Layout};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Cell, Paragraph, Row, Table};
use ratatui::{Frame, Terminal};
use rtcan_host::monitor::View;

/// Draws `v` on the whole of `f`; `title` names the bus.
pub fn draw(f: &mut Frame, v: &View, title: &str) {
    let [head, modules, stale, topics, load] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Length(v.modules.len() as u16 + 3),
        Constraint::Length(stale_rows(v)),
        Constraint::Min(3),
        Constraint::Length(3),
    ])
    .areas(f.area());
    f.render_widget(
        Paragraph::new(format!(
            "{title}  bus time {:.3} s  {} frames  (q: quit)",
            v.time_s, v.frames
        ))
        .style(Style::new().add_modifier(Modifier::BOLD)),
        head,
    );
    let bold = Style::new().add_modifier(Modifier::BOLD);
    let rows = v.modules.iter().map(|m| {
        let (text, colour) = match m.matches {
            Some(true) => ("yes", Color::Green),
            Some(false) => ("NO", Color::Red),
            None => ("?", Color::Yellow),
        };
        Row::new(vec![
            Cell::from(m.name.clone()),
            Cell::from(m.index.to_string()),
            Cell::from(format!("{:>9.1}", m.age_ms)),
            Cell::from(m.state.to_string()),
            Cell::from(format!("{:#010x}", m.fingerprint)),
            Cell::from(text).style(Style::new().fg(colour)),
        ])
    });
    f.render_widget(
        Table::new(
            rows,
            [
                Constraint::Length(12),
                Constraint::Length(3),
                Constraint::Length(10),
                Constraint::Length(6),
                Constraint::Length(12),
                Constraint::Length(6),
            ],
        )
        .header(Row::new(["MODULE", "#", "HB AGE ms", "STATE", "FINGERPRINT", "MATCH"]).style(bold))
        .block(Block::bordered().title("modules")),
        modules,
    );
    if !v.stale.is_empty() {
        // A stale image is a fault to fix, not a figure: red, above the topics.
        let lines: Vec<Line> = v
            .stale
            .iter()
            .map(|r| {
                Line::from(Span::styled(
                    format!("{:#06x} {:>6} frames  {}", r.msg_id, r.frames, r.reason),
                    Style::new().fg(Color::Red),
                ))
            })
            .collect();
        f.render_widget(
            Paragraph::new(lines)
                .wrap(ratatui::widgets::Wrap { trim: true })
                .block(
                    Block::bordered().title("stale images (frames under IDs robot.lock retired)"),
                ),
            stale,
        );
    }
    let rows = v.topics.iter().map(|t| {
        Row::new(vec![
            t.name.clone(),
            t.class.to_string(),
            format!("{:>7}", t.count),
            format!("{:>8.1}", t.rate_hz),
            format!("{:>7.3}", t.xfer_ms),
            t.last.clone(),
        ])
    });
    f.render_widget(
        Table::new(
            rows,
            [
                Constraint::Length(16),
                Constraint::Length(5),
                Constraint::Length(7),
                Constraint::Length(8),
                Constraint::Length(7),
                Constraint::Min(10),
            ],
        )
        .header(Row::new(["TOPIC", "CLASS", "COUNT", "RATE Hz", "XFER ms", "LAST"]).style(bold))
        .block(Block::bordered().title("topics")),
        topics,
    );
    let colours = [
        Color::Magenta,
        Color::Red,
        Color::Yellow,
        Color::Green,
        Color::Gray,
    ];
    let mut spans = Vec::new();
    for ((class, pct), colour) in v.load.iter().zip(colours) {
        spans.push(Span::styled(
            format!("{class} {pct:.1}%"),
            Style::new().fg(colour),
        ));
        spans.push(Span::raw("   "));
    }
    let total: f64 = v.load.iter().map(|(_, p)| p).sum();
    spans.push(Span::styled(format!("total {total:.1}%"), bold));
    f.render_widget(
        Paragraph::new(Line::from(spans)).block(Block::bordered().title("bus load")),
        load,
    );
}

/// Height of the stale-images block: none without stale frames, else two lines a row
/// (the reasons are long) and the border.
fn stale_rows(v: &View) -> u16 {
    if v.stale.is_empty() {
        0
    } else {
        (2 * v.stale.len() + 2) as u16
    }
}

/// Height that shows every row of `v`.
fn rows_needed(v: &View) -> u16 {
    (1 + v.modules.len() + 3 + v.topics.len() + 3 + 3) as u16 + stale_rows(v)
}

/// `v` drawn on a `width`-column test backend, as text lines (trailing blanks cut).
pub fn screen_text(v: &View, title: &str, width: u16) -> Result<String, String> {
    let height = rows_needed(v);
    let mut t = Terminal::new(TestBackend::new(width, height)).map_err(|e| e.to_string())?;
    t.draw(|f| draw(f, v, title)).map_err(|e| e.to_string())?;
    let buf = t.backend().buffer();
    let mut out = String::new();
    for y in 0..height {
        let line: String = (0..width)
            .filter_map(|x| buf.cell((x, y)).map(|c| c.symbol().to_string()))
            .collect();
        out.push_str(line.trim_end());
        out.push('\n');
    }
    Ok(out)
}

/// The live terminal: alternate screen, raw mode (restored on exit, on error and on a
/// panic by ratatui's hook).
pub struct Live {
    term: ratatui::DefaultTerminal,
}

impl Live {
    /// Takes over the terminal when stdout is one; `None` otherwise (a pipe gets the
    /// plain table instead).
    pub fn start() -> Option<Live> {
        if !std::io::stdout().is_terminal() {
            return None;
        }
        Some(Live {
            term: ratatui::init(),
        })
    }

    /// Redraws.
    pub fn draw(&mut self, v: &View, title: &str) -> Result<(), String> {
        self.term
            .draw(|f| draw(f, v, title))
            .map(|_| ())
            .map_err(|e| format!("terminal: {e}"))
    }

    /// Whether the person asked to quit (q, Esc or Ctrl-C), without waiting.
    pub fn quit_asked(&mut self) -> bool {
        while event::poll(Duration::ZERO).unwrap_or(false) {
            if let Ok(Event::Key(k)) = event::read() {
                let ctrl_c =
                    k.code == KeyCode::Char('c') && k.modifiers.contains(KeyModifiers::CONTROL);
                if k.kind == KeyEventKind::Press
                    && (ctrl_c || matches!(k.code, KeyCode::Char('q') | KeyCode::Esc))
                {
                    return true;
                }
            }
        }
        false
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        ratatui::restore();
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;
    use rtcan_host::monitor::{ModuleRow, StaleRow, TopicRow};

    fn view() -> View {
        View {
            time_s: 1.5,
            frames: 1234,
            modules: vec![
                ModuleRow {
                    name: "gateway".into(),
                    index: 0,
                    age_ms: 12.5,
                    state: 1,
                    fingerprint: 0xc063_6873,
                    matches: Some(true),
                },
                ModuleRow {
                    name: "stranger".into(),
                    index: 7,
                    age_ms: 100.0,
                    state: 2,
                    fingerprint: 0xdead_beef,
                    matches: Some(false),
                },
            ],
            topics: vec![TopicRow {
                name: "odometry".into(),
                class: "HRT",
                count: 75,
                rate_hz: 50.0,
                xfer_ms: 0.322,
                last: r#"{"x":0.5}"#.into(),
            }],
            load: [
                ("sync", 4.0),
                ("HRT", 20.5),
                ("SRT", 3.25),
                ("NRT", 0.5),
                ("other", 0.0),
            ],
            stale: Vec::new(),
        }
    }

    #[test]
    fn the_screen_shows_every_row_exactly() {
        let text = screen_text(&view(), "--sim robot.toml", 80).unwrap();
        let want = "\
--sim robot.toml  bus time 1.500 s  1234 frames  (q: quit)
┌modules───────────────────────────────────────────────────────────────────────┐
│MODULE       #   HB AGE ms  STATE  FINGERPRINT  MATCH                         │
│gateway      0        12.5  1      0xc0636873   yes                           │
│stranger     7       100.0  2      0xdeadbeef   NO                            │
└──────────────────────────────────────────────────────────────────────────────┘
┌topics────────────────────────────────────────────────────────────────────────┐
│TOPIC            CLASS COUNT   RATE Hz  XFER ms LAST                          │
│odometry         HRT        75     50.0   0.322 {\"x\":0.5}                     │
└──────────────────────────────────────────────────────────────────────────────┘
┌bus load──────────────────────────────────────────────────────────────────────┐
│sync 4.0%   HRT 20.5%   SRT 3.2%   NRT 0.5%   other 0.0%   total 28.2%        │
└──────────────────────────────────────────────────────────────────────────────┘
";
        assert_eq!(text, want, "\n{text}");
    }

    #[test]
    fn a_foreign_fingerprint_is_red_and_a_match_green() {
        let v = view();
        let mut t = Terminal::new(TestBackend::new(80, rows_needed(&v))).unwrap();
        t.draw(|f| draw(f, &v, "x")).unwrap();
        let buf = t.backend().buffer();
        // MATCH column: x = 1 (border) + 12+1 + 3+1 + 10+1 + 6+1 + 12+1 = 49.
        assert_eq!(buf.cell((49, 3)).unwrap().symbol(), "y");
        assert_eq!(buf.cell((49, 3)).unwrap().fg, Color::Green);
        assert_eq!(buf.cell((49, 4)).unwrap().symbol(), "N");
        assert_eq!(buf.cell((49, 4)).unwrap().fg, Color::Red);
    }

    #[test]
    fn a_stale_image_is_a_red_block_above_the_topics() {
        let mut v = view();
        v.stale.push(StaleRow {
            msg_id: 0x0145,
            frames: 58,
            reason: "retired ID of topic `encoder3`: rebuild and flash it".into(),
        });
        let text = screen_text(&v, "x", 80).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[6],
            "┌stale images (frames under IDs robot.lock retired)────────────────────────────┐"
        );
        assert_eq!(
            lines[7],
            "│0x0145     58 frames  retired ID of topic `encoder3`: rebuild and flash it    │"
        );
        assert!(lines[10].starts_with("┌topics"), "{text}");
        let mut t = Terminal::new(TestBackend::new(80, rows_needed(&v))).unwrap();
        t.draw(|f| draw(f, &v, "x")).unwrap();
        assert_eq!(t.backend().buffer().cell((1, 7)).unwrap().fg, Color::Red);
    }
}
