//! Progress on long commands: units done, the current unit, time left and the process's peak
//! resident memory so far, as a bar on a terminal and as plain lines in a log.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle, TermLike};
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The process's peak resident memory so far, in bytes (`VmHWM`); `None` where the system
/// does not say (anything but Linux).
pub fn peak_resident_bytes() -> Option<u64> {
    status_kib("VmHWM:").map(|k| k * 1024)
}

/// The process's resident memory now, in bytes (`VmRSS`); `None` where the system does not say.
pub fn resident_bytes() -> Option<u64> {
    status_kib("VmRSS:").map(|k| k * 1024)
}

fn status_kib(field: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status_field_kib(&status, field)
}

/// The value in KiB of `field` in a `/proc/PID/status` text.
fn status_field_kib(status: &str, field: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with(field))?;
    line[field.len()..].split_whitespace().next()?.parse().ok()
}

/// `bytes` as a person reads it: `812 MB`, `2.4 GB`.
pub fn bytes_text(bytes: u64) -> String {
    let mb = bytes as f64 / 1e6;
    if mb < 1000.0 {
        format!("{mb:.0} MB")
    } else {
        format!("{:.1} GB", mb / 1000.0)
    }
}

/// A duration as `1h02m`, `3m07s` or `12s`.
pub fn duration_text(d: Duration) -> String {
    let s = d.as_secs();
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m{:02}s", s / 60, s % 60),
        _ => format!("{}h{:02}m", s / 3600, s % 3600 / 60),
    }
}

/// The peak memory as the bars and lines show it: `peak 2.4 GB`, or nothing where unknown.
fn peak_text() -> String {
    peak_resident_bytes()
        .map(|b| format!("peak {}", bytes_text(b)))
        .unwrap_or_default()
}

/// A bar over `units` units named `what` (`maps`, `configurations`), showing the elapsed time,
/// the time left, the peak memory and the message (the current unit). On a terminal it
/// redraws in place; into a log (stderr not a terminal: CI, a batch job) it writes a line per
/// unit done, and at most every half minute between.
pub fn bar(units: usize, what: &str) -> ProgressBar {
    let b = ProgressBar::with_draw_target(Some(units as u64), draw_target());
    b.set_style(style(&format!(
        "[{{elapsed_precise}}] {{bar:30}} {{pos}}/{{len}} {what}, {{left}} left, {{peak}}  {{msg}}"
    )));
    b
}

/// Where bars draw: stderr on a terminal, [`LogLines`] otherwise.
pub fn draw_target() -> ProgressDrawTarget {
    if std::io::stderr().is_terminal() {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::term_like(Box::new(LogLines::default()))
    }
}

/// A bar's lines written into a log: a line when the count of units done (its first `K/N`)
/// changes, or when half a minute passed since the last line; never the bar's redraws in
/// place.
#[derive(Debug, Default)]
pub struct LogLines {
    last: Mutex<Option<(String, Instant)>>,
    /// The lines written, kept for the tests instead of written.
    #[cfg(test)]
    written: std::sync::Arc<Mutex<Vec<String>>>,
}

/// The first `K/N` token of a bar's line.
fn count_token(line: &str) -> Option<&str> {
    line.split_whitespace()
        .map(|w| w.trim_matches(|c: char| !c.is_ascii_alphanumeric() && c != '/'))
        .find(|w| {
            let mut parts = w.split('/');
            let is_num = |p: Option<&str>| {
                p.is_some_and(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()))
            };
            is_num(parts.next()) && is_num(parts.next()) && parts.next().is_none()
        })
}

impl LogLines {
    /// Whether `line` is to be written, noting it as the last written if so.
    fn admits(&self, line: &str) -> bool {
        let line = line.trim();
        if line.is_empty() {
            return false;
        }
        let count = count_token(line).unwrap_or("").to_string();
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        let due = match &*last {
            None => true,
            Some((c, at)) => *c != count || at.elapsed() >= Duration::from_secs(30),
        };
        if due {
            *last = Some((count, Instant::now()));
        }
        due
    }

    fn write(&self, s: &str) -> std::io::Result<()> {
        if self.admits(s) {
            // The bar's fill is noise in a log.
            let text: String = s
                .chars()
                .filter(|c| !matches!(c, '█' | '░' | '▉' | '▊' | '▋' | '▌' | '▍' | '▎' | '▏'))
                .collect();
            let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
            #[cfg(test)]
            self.written.lock().unwrap().push(text);
            #[cfg(not(test))]
            eprintln!("{text}");
        }
        Ok(())
    }
}

impl TermLike for LogLines {
    fn width(&self) -> u16 {
        160
    }
    fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn write_line(&self, s: &str) -> std::io::Result<()> {
        self.write(s)
    }
    fn write_str(&self, s: &str) -> std::io::Result<()> {
        self.write(s)
    }
    fn clear_line(&self) -> std::io::Result<()> {
        Ok(())
    }
    fn flush(&self) -> std::io::Result<()> {
        Ok(())
    }
}

/// `template` with the `{peak}` key (the process's peak resident memory) and the `{left}` key
/// (time left at the run's average pace so far) added.
pub fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .with_key("peak", |_: &ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = w.write_str(&peak_text());
        })
        .with_key("left", |s: &ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = w.write_str(&left_text(s.elapsed(), s.pos(), s.len()));
        })
}

/// Time left if the units left take as long as the units done did on average: `about 8m40s`,
/// or `?` before the first unit is done. (indicatif's own `{eta}` follows the latest units'
/// pace, which runs to years when one long unit follows many short ones.)
pub fn left_text(elapsed: Duration, done: u64, units: Option<u64>) -> String {
    match units {
        Some(units) if done > 0 => {
            let left = elapsed.mul_f64(units.saturating_sub(done) as f64 / done as f64);
            format!("about {}", duration_text(left))
        }
        _ => "?".to_string(),
    }
}

/// Plain progress lines for logs, one per unit started:
/// `[3/29] maps/ps9ctf.bsp  (2m10s in, about 8m40s left, peak 1.2 GB)`.
pub struct Lines {
    units: usize,
    what: String,
    done: usize,
    start: Instant,
}

impl Lines {
    pub fn new(units: usize, what: &str) -> Self {
        Self {
            units,
            what: what.to_string(),
            done: 0,
            start: Instant::now(),
        }
    }

    /// The line announcing the next unit, `name`; counts the previous one as done.
    pub fn next(&mut self, name: &str) -> String {
        let elapsed = self.start.elapsed();
        let mut line = format!("[{}/{}] {name}", self.done + 1, self.units);
        let mut notes = Vec::new();
        if self.done > 0 {
            notes.push(format!("{} in", duration_text(elapsed)));
            let left = elapsed.mul_f64((self.units - self.done) as f64 / self.done as f64);
            notes.push(format!("about {} left", duration_text(left)));
        }
        let peak = peak_text();
        if !peak.is_empty() {
            notes.push(peak);
        }
        if !notes.is_empty() {
            let _ = write!(line, "  ({})", notes.join(", "));
        }
        self.done += 1;
        line
    }

    /// The closing line: units, total time and peak memory.
    pub fn finish(&self) -> String {
        let mut line = format!(
            "{} {} done in {}",
            self.units,
            self.what,
            duration_text(self.start.elapsed())
        );
        let peak = peak_text();
        if !peak.is_empty() {
            let _ = write!(line, ", {peak}");
        }
        line
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_left_follows_the_average_pace() {
        let ten_min = Duration::from_secs(600);
        assert_eq!(left_text(ten_min, 0, Some(4)), "?");
        assert_eq!(left_text(ten_min, 1, None), "?");
        assert_eq!(
            left_text(ten_min, 2, Some(4)),
            format!("about {}", duration_text(ten_min))
        );
        assert_eq!(
            left_text(ten_min, 4, Some(4)),
            format!("about {}", duration_text(Duration::ZERO))
        );
    }

    #[test]
    fn reads_a_status_field() {
        let status = "Name:\tshadowlab\nVmPeak:\t 2000 kB\nVmHWM:\t  812340 kB\nVmRSS:\t 1000 kB\n";
        assert_eq!(status_field_kib(status, "VmHWM:"), Some(812_340));
        assert_eq!(status_field_kib(status, "VmRSS:"), Some(1000));
        assert_eq!(status_field_kib(status, "VmSwap:"), None);
    }

    #[test]
    fn texts() {
        assert_eq!(bytes_text(812_340_000), "812 MB");
        assert_eq!(bytes_text(2_400_000_000), "2.4 GB");
        assert_eq!(duration_text(Duration::from_secs(12)), "12s");
        assert_eq!(duration_text(Duration::from_secs(187)), "3m07s");
        assert_eq!(duration_text(Duration::from_secs(3720)), "1h02m");
    }

    #[test]
    fn lines_count_units_and_say_time_left_after_the_first() {
        let mut lines = Lines::new(3, "maps");
        let first = lines.next("a");
        assert!(first.starts_with("[1/3] a"), "{first}");
        assert!(!first.contains("left"), "{first}");
        let second = lines.next("b");
        assert!(second.starts_with("[2/3] b"), "{second}");
        assert!(second.contains("left"), "{second}");
    }

    #[test]
    fn log_lines_write_when_the_count_changes() {
        assert_eq!(count_token("[00:01] ███ 3/29 maps, 2m left"), Some("3/29"));
        assert_eq!(count_token("rung 1: [00:01] 3/48, 2m left"), Some("3/48"));
        assert_eq!(count_token("no count here 3/ /4 a/b"), None);
        let log = LogLines::default();
        assert!(log.admits("[00:00:01] 0/4 configurations, 0s left  oa_dm1"));
        assert!(!log.admits("[00:00:02] 0/4 configurations, 9s left  oa_dm1"));
        assert!(log.admits("[00:00:03] 1/4 configurations, 6s left  oa_dm1"));
        assert!(!log.admits("   "));
    }

    #[test]
    fn a_bar_into_a_log_writes_every_unit_done() {
        let log = LogLines::default();
        let written = log.written.clone();
        // As `tune` drives its bar: made empty, then sized and named per stage.
        let b =
            ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::term_like(Box::new(log)));
        b.set_style(style(
            "{prefix}: [{elapsed_precise}] {bar:30} {pos}/{len}, {left} left, {peak}  {msg}",
        ));
        b.set_length(5);
        b.set_position(0);
        b.set_prefix("rung 1");
        for i in 0..5 {
            b.set_message(format!("map {i} {}", "x=1 ".repeat(60)));
            std::thread::sleep(Duration::from_millis(5));
            b.inc(1);
        }
        b.finish();
        let lines = written.lock().unwrap().clone();
        for k in 1..=5 {
            assert!(
                lines.iter().any(|l| l.contains(&format!("{k}/5"))),
                "{k}/5 missing: {lines:?}"
            );
        }
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn peak_memory_is_known_on_linux() {
        let peak = peak_resident_bytes().expect("VmHWM on Linux");
        assert!(peak >= resident_bytes().unwrap_or(0));
    }
}
