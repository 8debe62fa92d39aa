//! Progress of a long computation over items (table cells, Monte-Carlo samples): an indicatif
//! bar with ETA on a terminal, plain periodic lines otherwise (batch schedulers capture stderr
//! into files; a bar would be invisible there), and optionally a small progress file that a
//! distributed run's watcher reads (`"done total"`, replaced atomically about once a second).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How often the progress file is rewritten at most.
const FILE_EVERY: Duration = Duration::from_secs(1);
/// How often a plain progress line is printed at most.
const LINE_EVERY: Duration = Duration::from_secs(10);

/// Progress over a known number of items; `inc` is called from worker threads.
pub struct Progress {
    bar: ProgressBar,
    tty: bool,
    total: usize,
    unit: &'static str,
    done: AtomicUsize,
    start: Instant,
    last: Mutex<(Instant, Instant)>,
    quiet: bool,
    file: Option<PathBuf>,
}

impl Progress {
    /// Progress over `total` items called `unit` ("cells"); `quiet` suppresses all output.
    pub fn new(total: usize, label: &str, unit: &'static str, quiet: bool) -> Self {
        let tty = std::io::stderr().is_terminal() && !quiet;
        let bar = if tty {
            let b = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr());
            if let Ok(style) = ProgressStyle::with_template(&format!(
                "{{msg}} [{{elapsed_precise}}] {{wide_bar}} {{pos}}/{{len}} {unit}, ETA {{eta}}"
            )) {
                b.set_style(style);
            }
            b.set_message(label.to_string());
            b
        } else {
            ProgressBar::hidden()
        };
        let now = Instant::now();
        Progress {
            bar,
            tty,
            total,
            unit,
            done: AtomicUsize::new(0),
            start: now,
            last: Mutex::new((now, now)),
            quiet,
            file: None,
        }
    }

    /// Also keep `path` up to date with `"done total"` (written now with 0 done).
    pub fn with_file(mut self, path: &Path) -> Self {
        write_progress_file(path, 0, self.total);
        self.file = Some(path.to_path_buf());
        self
    }

    /// One item finished.
    pub fn inc(&self) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        if self.tty {
            self.bar.inc(1);
        }
        let finished = done == self.total;
        if self.quiet && self.file.is_none() {
            return;
        }
        let now = Instant::now();
        let mut last = match self.last.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        };
        if let Some(f) = &self.file {
            // The first item too: a watcher sees at once that the task computes.
            if finished || done == 1 || now.duration_since(last.1) >= FILE_EVERY {
                last.1 = now;
                write_progress_file(f, done, self.total);
            }
        }
        if !self.tty && !self.quiet && (finished || now.duration_since(last.0) >= LINE_EVERY) {
            last.0 = now;
            let el = now.duration_since(self.start).as_secs_f64();
            let eta = el / done as f64 * (self.total - done) as f64;
            eprintln!(
                "progress: {done}/{} {} ({:.0} %), elapsed {el:.0} s, ETA {eta:.0} s",
                self.total,
                self.unit,
                100.0 * done as f64 / self.total.max(1) as f64
            );
        }
    }

    /// Finish the bar.
    pub fn finish(&self) {
        self.bar.finish();
    }
}

/// Replace `path` with `"done total"`. Best effort: progress must never fail a computation.
fn write_progress_file(path: &Path, done: usize, total: usize) {
    let _ = diagram::write_atomically(path, format!("{done} {total}\n").as_bytes());
}

/// Read a progress file: `(done, total)`, `None` if absent or unreadable.
pub fn read_progress_file(path: &Path) -> Option<(usize, usize)> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut it = text.split_whitespace().map(str::parse::<usize>);
    match (it.next(), it.next()) {
        (Some(Ok(d)), Some(Ok(t))) => Some((d, t)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn progress_file_counts_every_item() {
        let dir = std::env::temp_dir().join(format!("lut-progress-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("p");
        let p = Progress::new(5, "x", "items", true).with_file(&f);
        assert_eq!(read_progress_file(&f), Some((0, 5)));
        for _ in 0..5 {
            p.inc();
        }
        // The last item is always written, whatever the rate limit.
        assert_eq!(read_progress_file(&f), Some((5, 5)));
        std::fs::write(&f, "garbage").unwrap();
        assert_eq!(read_progress_file(&f), None);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
