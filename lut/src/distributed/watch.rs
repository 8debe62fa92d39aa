//! Waiting for a submitted run, with progress.

use super::{ShardState, Status, Work};
use crate::slurm::{self, Record};
use anyhow::{bail, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// Shows a watched run: an indicatif bar on a terminal, a line on every change of the shards'
/// states (and every 10 s) otherwise.
struct Watcher {
    bar: Option<ProgressBar>,
    start: Instant,
    done0: Option<usize>,
    last_line: Instant,
    last_summary: String,
}

impl Watcher {
    fn new(items: u64, unit: &str) -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let b = ProgressBar::with_draw_target(Some(items), ProgressDrawTarget::stderr());
            if let Ok(st) = ProgressStyle::with_template(&format!(
                "slurm [{{elapsed_precise}}] {{wide_bar}} {{pos}}/{{len}} {unit} {{msg}}"
            )) {
                b.set_style(st);
            }
            b
        });
        let now = Instant::now();
        Watcher {
            bar,
            start: now,
            done0: None,
            last_line: now,
            last_summary: String::new(),
        }
    }

    fn update(&mut self, st: &Status) {
        let done = st.items_done();
        let done0 = *self.done0.get_or_insert(done);
        let el = self.start.elapsed().as_secs_f64();
        let rate = if el > 0.5 && done > done0 {
            format!("{:.2} {}/s", (done - done0) as f64 / el, st.unit)
        } else {
            format!("– {}/s", st.unit)
        };
        let shards = format!(
            "shards {}/{} done, {} running, {} pending, {} failed",
            st.count(ShardState::Done),
            st.n,
            st.count(ShardState::Running),
            st.count(ShardState::Pending),
            st.count(ShardState::Failed) + st.count(ShardState::Invalid)
        );
        match &self.bar {
            Some(b) => {
                b.set_position(done as u64);
                b.set_message(format!("{shards}, {rate}"));
            }
            None => {
                if shards != self.last_summary
                    || self.last_line.elapsed() >= Duration::from_secs(10)
                {
                    eprintln!(
                        "slurm: {shards}; {done}/{} {}, {rate}, {el:.0} s",
                        st.items, st.unit
                    );
                    self.last_summary = shards;
                    self.last_line = Instant::now();
                }
            }
        }
    }

    fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish();
        }
    }
}

/// Watch until nothing of the latest submission is queued: `Ok` when the output is complete,
/// otherwise an error naming the failed shards (or the failed collect job) and their logs.
pub fn watch(work: &Work, poll: Duration) -> Result<()> {
    let mut w = Watcher::new(work.spec.items, work.spec.job.unit());
    loop {
        let st = work.status(false)?;
        w.update(&st);
        if !st.jobs_queued {
            w.finish();
            if st.output_complete {
                eprintln!("slurm: {} written", work.spec.out.display());
                return Ok(());
            }
            let st = work.status(true)?;
            let failed: Vec<String> = st
                .shards
                .iter()
                .filter(|s| s.state != ShardState::Done)
                .map(|s| format!("shard {}/{} ({:?}): {}", s.k, st.n, s.state, s.detail))
                .collect();
            if !failed.is_empty() {
                bail!(
                    "distributed run failed: {} of {} shards missing or failed (re-run the same command to resume: only these are re-submitted):\n  {}",
                    failed.len(),
                    st.n,
                    failed.join("\n  ")
                );
            }
            let c = st.collect.as_ref();
            let rec = match c {
                Some(c) => slurm::scontrol_show(&c.job)?
                    .first()
                    .map_or("no record".into(), Record::describe),
                None => "never submitted".into(),
            };
            let tail = c
                .and_then(|c| std::fs::read_to_string(&c.log).ok())
                .map(|t| {
                    let lines: Vec<&str> = t.lines().collect();
                    lines[lines.len().saturating_sub(6)..].join("\n    ")
                })
                .unwrap_or_default();
            bail!(
                "every shard is done but the collect job {} did not write {} ({rec}); log {}:\n    {tail}",
                c.map_or("?", |c| c.job.as_str()),
                work.spec.out.display(),
                c.map_or_else(String::new, |c| c.log.display().to_string())
            );
        }
        std::thread::sleep(poll);
    }
}
