//! A computation split into N shards and run on a Slurm cluster: one job array (task K
//! computes shard K) plus one collect job that depends on it (merges the shards, checks the
//! result and writes the output atomically).
//!
//! Everything lives in a **work directory** (default `<out>.slurm/`), which must be on a file
//! system the compute nodes share:
//!
//! | file | content |
//! |---|---|
//! | `spec.json` | what is computed ([`Job`]), N, the output path, the inputs' identity |
//! | `state.json` | every submission: array job id, its task list, collect job id |
//! | `shard.sh`, `collect.sh` | the batch scripts (`lut slurm shard DIR K`, `lut slurm collect DIR`) |
//! | `shard-K-of-N.bin` | finished shards ([`crate::shard`]: identity, range, checksum) |
//! | `progress/K` | cells (samples) done by a running task |
//! | `logs/` | the jobs' stdout+stderr (`shard-K.JOBID.log`, `collect.JOBID.log`) |
//!
//! Running the same command again **resumes**: an output that is already complete is left
//! alone; jobs still queued are watched, not submitted twice; otherwise only shards without a
//! valid file are submitted. A complete, valid shard is never recomputed.

use crate::progress::{read_progress_file, Progress};
use crate::robustness::RobustnessJob;
use crate::shard::{short, ShardHeader};
use crate::slurm::{self, Queued, Record, Submit};
use crate::table::{self, Grid, GridFile};
use anyhow::{anyhow, bail, Context, Result};
use diagram::Diagram;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// Spec file name in the work directory.
pub const SPEC_FILE: &str = "spec.json";
/// State file name in the work directory.
pub const STATE_FILE: &str = "state.json";

/// What a distributed run computes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Job {
    /// The characteristic diagram of a grid.
    Table(TableJob),
    /// The Monte-Carlo robustness study of one cell.
    Robustness(RobustnessJob),
}

/// A table build: the grid and how the merged table is spot-checked.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TableJob {
    /// The grid (a copy: editing the grid file during a run changes nothing).
    pub grid: GridFile,
    /// Cells re-optimised by the collect job's check (like `lut verify --cells`).
    pub verify_cells: usize,
    /// Seed of that check.
    pub verify_seed: u64,
}

impl TableJob {
    fn grid(&self) -> Result<Grid> {
        Grid::from_spec("grid of the distributed build", self.grid.clone())
    }

    /// Merge, check (checksum, every cell, the grid's identity, spot re-optimisation), write.
    fn collect(&self, identity: &str, shards: &[(String, Vec<u8>)], out: &Path) -> Result<String> {
        let decoded = shards
            .iter()
            .map(|(o, b)| Ok((o.clone(), table::read_shard(o, b)?)))
            .collect::<Result<Vec<_>>>()?;
        let d = table::merge_shards(&decoded, Some(identity))?;
        let name = out.display().to_string();
        let bytes = d.to_bytes();
        let back = Diagram::from_bytes(&name, &bytes).map_err(|e| anyhow!("merged table: {e}"))?;
        if back.checksum() != d.checksum() || back.cells().len() != self.grid()?.axes.cell_count() {
            bail!("merged table does not survive its own file format (checksum or cell count)");
        }
        if table::table_identity(back.header(), back.axes())? != identity {
            bail!("merged table's header and axes are not those of the grid");
        }
        let rows = table::verify(&back, self.verify_cells, self.verify_seed)?;
        let bad: Vec<String> = rows
            .iter()
            .filter(|r| !r.ok)
            .map(|r| format!("cell {}: {}", r.index, r.problem.as_deref().unwrap_or("?")))
            .collect();
        if !bad.is_empty() {
            bail!(
                "merged table fails the spot re-optimisation: {}",
                bad.join("; ")
            );
        }
        diagram::write_atomically(out, &bytes).map_err(|e| anyhow!("{e}"))?;
        Ok(format!(
            "table {name}: {} cells, LUT id 0x{:04x}, CRC-32C 0x{:08x}; {} cells re-optimised, all within tolerance",
            back.cells().len(),
            back.lut_id(),
            back.checksum(),
            rows.len()
        ))
    }

    fn output_matches(out: &Path, identity: &str) -> bool {
        Diagram::load(out).is_ok_and(|d| {
            table::table_identity(d.header(), d.axes()).is_ok_and(|id| id == identity)
        })
    }
}

impl Job {
    /// Kind tag (shard files, job names).
    pub fn kind(&self) -> &'static str {
        match self {
            Job::Table(_) => table::TABLE_SHARD_KIND,
            Job::Robustness(_) => crate::robustness::SHARD_KIND,
        }
    }

    /// What an item is called.
    pub fn unit(&self) -> &'static str {
        match self {
            Job::Table(_) => "cells",
            Job::Robustness(_) => "samples",
        }
    }

    /// Identity of the inputs.
    pub fn identity(&self) -> Result<String> {
        match self {
            Job::Table(t) => t.grid()?.identity(),
            Job::Robustness(r) => r.identity(),
        }
    }

    /// Items in total.
    pub fn items(&self) -> Result<usize> {
        match self {
            Job::Table(t) => Ok(t.grid()?.axes.cell_count()),
            Job::Robustness(r) => Ok(r.samples()),
        }
    }

    /// Compute shard `k` of `n`; the encoded shard file.
    pub fn compute_shard(
        &self,
        k: usize,
        n: usize,
        threads: Option<usize>,
        progress: &Progress,
    ) -> Result<Vec<u8>> {
        match self {
            Job::Table(t) => {
                let (s, stats) = table::build_shard(&t.grid()?, k, n, threads, progress)?;
                eprintln!(
                    "{} cells in {:.1} s: {:.2} cells/s, {} occupant simulations",
                    stats.cells,
                    stats.wall.as_secs_f64(),
                    stats.cells as f64 / stats.wall.as_secs_f64().max(1e-9),
                    stats.occupant_simulations
                );
                s.to_bytes()
            }
            Job::Robustness(r) => r.compute_shard(k, n, threads, progress),
        }
    }

    /// Read and check one shard file on its own; its header.
    pub fn read_shard(&self, origin: &str, bytes: &[u8]) -> Result<ShardHeader> {
        match self {
            Job::Table(_) => Ok(table::read_shard(origin, bytes)?.header),
            Job::Robustness(_) => crate::robustness::read_shard(origin, bytes).map(|s| s.header),
        }
    }

    /// Combine all shards into the checked output, written atomically to `out`; a summary.
    pub fn collect(
        &self,
        identity: &str,
        shards: &[(String, Vec<u8>)],
        out: &Path,
    ) -> Result<String> {
        match self {
            Job::Table(t) => t.collect(identity, shards, out),
            Job::Robustness(r) => r.collect(identity, shards, out),
        }
    }

    /// `out` holds this job's complete output.
    pub fn output_matches(&self, out: &Path, identity: &str) -> bool {
        match self {
            Job::Table(_) => TableJob::output_matches(out, identity),
            Job::Robustness(_) => crate::robustness::output_matches(out, identity),
        }
    }
}

/// The work directory's description of the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spec {
    /// What is computed.
    pub job: Job,
    /// Shard count.
    pub n: u32,
    /// Output file (absolute).
    pub out: PathBuf,
    /// Identity of the inputs.
    pub identity: String,
    /// Items in total.
    pub items: u64,
    /// CPUs per array task.
    pub cpus_per_task: u32,
    /// Extra sbatch options.
    pub sbatch_args: Vec<String>,
    /// The `lut` binary the jobs run (absolute).
    pub lut: PathBuf,
}

/// One submission.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Submission {
    /// Job id of the array (none when every shard was already there).
    pub array_job: Option<String>,
    /// Shards (array task ids) submitted.
    pub tasks: Vec<u32>,
    /// Job id of the collect job.
    pub collect_job: String,
    /// Submission time (Unix seconds).
    pub unix_time: u64,
}

impl Submission {
    /// The array's and the collect job's ids.
    pub fn job_ids(&self) -> Vec<String> {
        self.array_job
            .iter()
            .chain([&self.collect_job])
            .cloned()
            .collect()
    }
}

/// Every submission of the work directory.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Oldest first.
    pub submissions: Vec<Submission>,
}

/// Options of a distributed run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Shard count N.
    pub n: usize,
    /// CPUs per array task (and for the collect job).
    pub cpus_per_task: u32,
    /// Extra sbatch options.
    pub sbatch_args: Vec<String>,
    /// Submit and return (then `lut slurm status` / re-run the command).
    pub no_wait: bool,
    /// Failed shards are re-submitted this often before giving up.
    pub retries: u32,
    /// Queue polling interval.
    pub poll: Duration,
}

/// A work directory.
#[derive(Clone, Debug)]
pub struct Work {
    /// The directory (absolute).
    pub dir: PathBuf,
    /// Its spec.
    pub spec: Spec,
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: invalid", path.display()))
}

fn write_json<T: Serialize>(path: &Path, v: &T) -> Result<()> {
    let mut text = serde_json::to_string_pretty(v)?;
    text.push('\n');
    diagram::write_atomically(path, text.as_bytes()).map_err(|e| anyhow!("{e}"))
}

fn absolute(p: &Path) -> Result<PathBuf> {
    std::path::absolute(p).with_context(|| format!("cannot make {} absolute", p.display()))
}

/// Default work directory of an output: `<out>.slurm`.
pub fn default_work_dir(out: &Path) -> PathBuf {
    let mut s = out.as_os_str().to_owned();
    s.push(".slurm");
    PathBuf::from(s)
}

/// Single-quote for sh.
fn sh_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

impl Work {
    /// Open an existing work directory.
    pub fn open(dir: &Path) -> Result<Self> {
        let dir = absolute(dir)?;
        let spec: Spec = read_json(&dir.join(SPEC_FILE)).with_context(|| {
            format!(
                "{} is not a work directory of a distributed run",
                dir.display()
            )
        })?;
        Ok(Work { dir, spec })
    }

    /// Path of shard `k`'s file.
    pub fn shard_path(&self, k: u32) -> PathBuf {
        self.dir.join(format!("shard-{k}-of-{}.bin", self.spec.n))
    }

    fn progress_path(&self, k: u32) -> PathBuf {
        self.dir.join("progress").join(k.to_string())
    }

    /// Log file of shard `k` in array job `job`.
    pub fn shard_log(&self, k: u32, job: &str) -> PathBuf {
        self.dir.join("logs").join(format!("shard-{k}.{job}.log"))
    }

    /// Log file of collect job `job`.
    pub fn collect_log(&self, job: &str) -> PathBuf {
        self.dir.join("logs").join(format!("collect.{job}.log"))
    }

    /// Submissions so far.
    pub fn state(&self) -> Result<State> {
        let p = self.dir.join(STATE_FILE);
        if p.exists() {
            read_json(&p)
        } else {
            Ok(State::default())
        }
    }

    /// Check shard `k`'s file: `Ok(None)` if absent, `Ok(Some(header))` if valid, `Err` with
    /// the reason (naming the file) if present but not a valid shard of this run.
    pub fn check_shard(&self, k: u32) -> Result<Option<ShardHeader>> {
        let path = self.shard_path(k);
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => bail!("{}: {e}", path.display()),
        };
        let origin = path.display().to_string();
        let h = self.spec.job.read_shard(&origin, &bytes)?;
        if h.identity != self.spec.identity {
            bail!(
                "{origin}: shard of another grid or configuration (identity {}…, this run's is {}…)",
                short(&h.identity),
                short(&self.spec.identity)
            );
        }
        if (h.k, h.n) != (k, self.spec.n) {
            bail!(
                "{origin}: holds shard {}/{}, not {k}/{}",
                h.k,
                h.n,
                self.spec.n
            );
        }
        Ok(Some(h))
    }

    /// Compute shard `k` here (what an array task runs) and write it atomically.
    pub fn run_shard(&self, k: u32, threads: Option<usize>) -> Result<()> {
        let n = self.spec.n as usize;
        let range = crate::shard::shard_range(self.spec.items as usize, k as usize, n)?;
        eprintln!(
            "{} shard {k}/{n}: {} {range:?} of {}, {} threads, work dir {}",
            self.spec.job.kind(),
            self.spec.job.unit(),
            self.spec.items,
            threads.map_or("all".into(), |t| t.to_string()),
            self.dir.display()
        );
        let progress = Progress::new(range.len(), "computing", self.spec.job.unit(), false)
            .with_file(&self.progress_path(k));
        let bytes = self
            .spec
            .job
            .compute_shard(k as usize, n, threads, &progress)?;
        progress.finish();
        let path = self.shard_path(k);
        diagram::write_atomically(&path, &bytes).map_err(|e| anyhow!("{e}"))?;
        self.check_shard(k)?;
        eprintln!("shard written to {}", path.display());
        Ok(())
    }

    /// Merge and check all shards, write the output (what the collect job runs).
    pub fn collect(&self) -> Result<String> {
        let mut shards = Vec::new();
        let mut problems = Vec::new();
        for k in 1..=self.spec.n {
            match self.check_shard(k) {
                Ok(Some(_)) => {
                    let p = self.shard_path(k);
                    shards.push((p.display().to_string(), std::fs::read(&p)?));
                }
                Ok(None) => problems.push(format!(
                    "shard {k}/{}: {} missing",
                    self.spec.n,
                    self.shard_path(k).display()
                )),
                Err(e) => problems.push(format!("{e:#}")),
            }
        }
        if !problems.is_empty() {
            bail!("cannot collect:\n  {}", problems.join("\n  "));
        }
        self.spec
            .job
            .collect(&self.spec.identity, &shards, &self.spec.out)
    }

    fn write_scripts(&self) -> Result<()> {
        let lut = sh_quote(&self.spec.lut.display().to_string());
        let dir = sh_quote(&self.dir.display().to_string());
        let shard = format!(
            "#!/bin/sh\n# Written by lut: array task K computes shard K of {} of the run in this directory.\nexec {lut} slurm shard {dir} \"$SLURM_ARRAY_TASK_ID\"\n",
            self.spec.n
        );
        let collect = format!(
            "#!/bin/sh\n# Written by lut: merges and checks the shards, writes {}.\nexec {lut} slurm collect {dir}\n",
            self.spec.out.display()
        );
        for (name, text) in [("shard.sh", shard), ("collect.sh", collect)] {
            let p = self.dir.join(name);
            std::fs::write(&p, text).with_context(|| format!("writing {}", p.display()))?;
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755))?;
        }
        Ok(())
    }

    /// Submit the shards in `tasks` (none: only the collect job) and a collect job after them.
    pub fn submit(&self, tasks: &[u32]) -> Result<Submission> {
        let spec = &self.spec;
        for &k in tasks {
            let _ = std::fs::remove_file(self.progress_path(k));
        }
        let name = format!("lut-{}", spec.job.kind());
        let array_job = if tasks.is_empty() {
            None
        } else {
            Some(slurm::sbatch(&Submit {
                job_name: name.clone(),
                array: Some(slurm::array_list(tasks)),
                cpus_per_task: spec.cpus_per_task,
                output: self.dir.join("logs").join("shard-%a.%A.log"),
                chdir: self.dir.clone(),
                after_ok: None,
                extra: spec.sbatch_args.clone(),
                script: self.dir.join("shard.sh"),
            })?)
        };
        let collect_job = slurm::sbatch(&Submit {
            job_name: format!("{name}-collect"),
            array: None,
            cpus_per_task: spec.cpus_per_task,
            output: self.dir.join("logs").join("collect.%j.log"),
            chdir: self.dir.clone(),
            after_ok: array_job.clone(),
            extra: spec.sbatch_args.clone(),
            script: self.dir.join("collect.sh"),
        })
        .inspect_err(|_| {
            // Do not leave an array behind that nothing collects.
            if let Some(a) = &array_job {
                let _ = slurm::scancel(std::slice::from_ref(a));
            }
        })?;
        let sub = Submission {
            array_job,
            tasks: tasks.to_vec(),
            collect_job,
            unix_time: SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
        };
        let mut state = self.state()?;
        state.submissions.push(sub.clone());
        write_json(&self.dir.join(STATE_FILE), &state)?;
        Ok(sub)
    }

    /// Where the run stands; `records`: also ask slurmctld why finished tasks failed.
    pub fn status(&self, records: bool) -> Result<Status> {
        let state = self.state()?;
        let last = state.submissions.last();
        let ids = last.map(Submission::job_ids).unwrap_or_default();
        let queue = slurm::squeue(&ids)?;
        let array_records: Vec<Record> = match (records, last.and_then(|s| s.array_job.as_ref())) {
            (true, Some(a)) => slurm::scontrol_show(a)?,
            _ => Vec::new(),
        };
        let n = self.spec.n;
        let mut shards = Vec::new();
        for k in 1..=n {
            let range =
                crate::shard::shard_range(self.spec.items as usize, k as usize, n as usize)?;
            let items = range.len();
            let queued: Option<&Queued> = last.and_then(|s| {
                queue
                    .iter()
                    .find(|q| Some(&q.job) == s.array_job.as_ref() && q.task == Some(k))
            });
            let (state, done, detail) = match self.check_shard(k) {
                Ok(Some(_)) => (ShardState::Done, items, String::new()),
                Err(e) if queued.is_none() => (ShardState::Invalid, 0, format!("{e:#}")),
                _ => match queued {
                    Some(q) if q.is_running() => {
                        let done = read_progress_file(&self.progress_path(k)).map_or(0, |p| p.0);
                        (ShardState::Running, done.min(items), q.state.clone())
                    }
                    Some(q) => (
                        ShardState::Pending,
                        0,
                        format!("{} ({})", q.state, q.reason),
                    ),
                    None => match last {
                        Some(s) if s.tasks.contains(&k) => {
                            let job = s.array_job.as_deref().unwrap_or("?");
                            let rec = array_records
                                .iter()
                                .find(|r| r.task == Some(k))
                                .map_or_else(
                                    || "no shard file written".to_string(),
                                    |r| format!("no shard file written; {}", r.describe()),
                                );
                            let log = self.shard_log(k, job);
                            (
                                ShardState::Failed,
                                0,
                                format!("array task {job}_{k}: {rec}; log {}", log.display()),
                            )
                        }
                        _ => (ShardState::Missing, 0, "not computed yet".to_string()),
                    },
                },
            };
            shards.push(ShardStatus {
                k,
                state,
                items,
                done,
                detail,
            });
        }
        let collect = last.map(|s| {
            let q = queue
                .iter()
                .find(|q| q.job == s.collect_job && q.task.is_none());
            CollectStatus {
                job: s.collect_job.clone(),
                queued: q.map(|q| format!("{} ({})", q.state, q.reason)),
                log: self.collect_log(&s.collect_job),
            }
        });
        Ok(Status {
            dir: self.dir.clone(),
            out: self.spec.out.clone(),
            unit: self.spec.job.unit().to_string(),
            items: self.spec.items,
            n,
            output_complete: self
                .spec
                .job
                .output_matches(&self.spec.out, &self.spec.identity),
            jobs_queued: !queue.is_empty(),
            shards,
            collect,
            submissions: state.submissions.len(),
        })
    }
}

/// State of one shard.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ShardState {
    /// A valid shard file is there.
    Done,
    /// Its array task runs.
    Running,
    /// Its array task waits in the queue.
    Pending,
    /// Its array task of the latest submission ended without a valid shard file.
    Failed,
    /// A file is there but it is not a valid shard of this run.
    Invalid,
    /// Not computed and not submitted.
    Missing,
}

/// One shard's status.
#[derive(Clone, Debug, Serialize)]
pub struct ShardStatus {
    /// K.
    pub k: u32,
    /// State.
    pub state: ShardState,
    /// Items of the shard.
    pub items: usize,
    /// Items done (running: from its progress file).
    pub done: usize,
    /// Queue state, or why it failed / is invalid.
    pub detail: String,
}

/// The collect job of the latest submission.
#[derive(Clone, Debug, Serialize)]
pub struct CollectStatus {
    /// Job id.
    pub job: String,
    /// Queue state if still queued.
    pub queued: Option<String>,
    /// Its log file.
    pub log: PathBuf,
}

/// Where a run stands.
#[derive(Clone, Debug, Serialize)]
pub struct Status {
    /// Work directory.
    pub dir: PathBuf,
    /// Output file.
    pub out: PathBuf,
    /// Item name.
    pub unit: String,
    /// Items in total.
    pub items: u64,
    /// Shards.
    pub n: u32,
    /// The output is complete and of this run.
    pub output_complete: bool,
    /// Any job of the latest submission is still queued.
    pub jobs_queued: bool,
    /// Per shard.
    pub shards: Vec<ShardStatus>,
    /// The latest collect job.
    pub collect: Option<CollectStatus>,
    /// Submissions so far.
    pub submissions: usize,
}

impl Status {
    /// Shards in `s`.
    pub fn count(&self, s: ShardState) -> usize {
        self.shards.iter().filter(|x| x.state == s).count()
    }

    /// Items done (complete shards plus running tasks' progress).
    pub fn items_done(&self) -> usize {
        self.shards.iter().map(|s| s.done).sum()
    }

    /// Shards that need computing (no valid file and not queued).
    pub fn to_submit(&self) -> Vec<u32> {
        self.shards
            .iter()
            .filter(|s| {
                matches!(
                    s.state,
                    ShardState::Failed | ShardState::Invalid | ShardState::Missing
                )
            })
            .map(|s| s.k)
            .collect()
    }

    /// One line: shards done/running/pending/failed and items.
    pub fn summary(&self) -> String {
        format!(
            "shards {}/{} done, {} running, {} pending, {} failed; {}/{} {}",
            self.count(ShardState::Done),
            self.n,
            self.count(ShardState::Running),
            self.count(ShardState::Pending),
            self.count(ShardState::Failed) + self.count(ShardState::Invalid),
            self.items_done(),
            self.items,
            self.unit
        )
    }

    /// Multi-line report (for `lut slurm status`).
    pub fn report(&self) -> String {
        let mut s = format!(
            "work dir {}\noutput   {} ({})\n{}\n",
            self.dir.display(),
            self.out.display(),
            if self.output_complete {
                "complete"
            } else {
                "not written yet"
            },
            self.summary()
        );
        for sh in &self.shards {
            s.push_str(&format!(
                "  shard {:>3}: {:<8} {:>6}/{:<6} {}\n",
                sh.k,
                format!("{:?}", sh.state).to_lowercase(),
                sh.done,
                sh.items,
                sh.detail
            ));
        }
        if let Some(c) = &self.collect {
            s.push_str(&format!(
                "  collect job {}: {} (log {})\n",
                c.job,
                c.queued.as_deref().unwrap_or("not queued"),
                c.log.display()
            ));
        }
        s
    }
}

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

/// Submit (or resume, or attach to) a distributed run of `job` writing `out`, then wait unless
/// `opts.no_wait`. See the module docs for the resume rules.
pub fn run(job: Job, out: &Path, work_dir: &Path, opts: &RunOptions) -> Result<()> {
    let identity = job.identity()?;
    let items = job.items()?;
    if opts.n == 0 || opts.n > items {
        bail!(
            "--slurm {}: need 1 ≤ N ≤ {items} (one shard per {} at most)",
            opts.n,
            job.unit().trim_end_matches('s')
        );
    }
    let out_abs = absolute(out)?;
    if job.output_matches(&out_abs, &identity) {
        eprintln!(
            "{} is complete and up to date (nothing submitted)",
            out_abs.display()
        );
        return Ok(());
    }
    let dir = absolute(work_dir)?;
    std::fs::create_dir_all(dir.join("logs"))
        .and_then(|_| std::fs::create_dir_all(dir.join("progress")))
        .with_context(|| format!("cannot create {}", dir.display()))?;
    let spec_path = dir.join(SPEC_FILE);
    if spec_path.exists() {
        let old: Spec = read_json(&spec_path)?;
        if old.identity != identity {
            bail!(
                "{} holds a run of another grid or configuration (identity {}…, this one's is {}…): remove it or choose another --work-dir",
                dir.display(),
                short(&old.identity),
                short(&identity)
            );
        }
        if old.n as usize != opts.n {
            bail!(
                "{} holds a run split into {} shards: resume it with --slurm {}, or remove the directory",
                dir.display(),
                old.n,
                old.n
            );
        }
    }
    let spec = Spec {
        job,
        n: opts.n as u32,
        out: out_abs,
        identity,
        items: items as u64,
        cpus_per_task: opts.cpus_per_task,
        sbatch_args: opts.sbatch_args.clone(),
        lut: std::env::current_exe().context("cannot find the lut binary's path")?,
    };
    write_json(&spec_path, &spec)?;
    let work = Work { dir, spec };
    work.write_scripts()?;
    let mut retries = opts.retries;
    loop {
        let st = work.status(false)?;
        if st.jobs_queued {
            eprintln!(
                "slurm: jobs of an earlier submission are still queued; watching them ({})",
                st.summary()
            );
        } else {
            for s in st.shards.iter().filter(|s| s.state == ShardState::Invalid) {
                eprintln!("slurm: recomputing shard {}: {}", s.k, s.detail);
            }
            let tasks = st.to_submit();
            let sub = work.submit(&tasks)?;
            eprintln!(
                "slurm: submitted {} of {} shards ({} {}) as array job {} (tasks {}), collect job {} after it; {} shards already done",
                tasks.len(),
                work.spec.n,
                work.spec.items,
                work.spec.job.unit(),
                sub.array_job.as_deref().unwrap_or("-"),
                slurm::array_list(&tasks),
                sub.collect_job,
                work.spec.n as usize - tasks.len()
            );
        }
        if opts.no_wait {
            eprintln!(
                "slurm: not waiting. Progress: lut slurm status {0}; merge finished shards here: lut slurm collect {0}; wait or resume: run the same command again",
                work.dir.display()
            );
            return Ok(());
        }
        match watch(&work, opts.poll) {
            Ok(()) => return Ok(()),
            Err(e) if retries > 0 => {
                retries -= 1;
                eprintln!(
                    "slurm: {e:#}\nslurm: re-submitting what is missing ({retries} retries left)"
                );
            }
            Err(e) => return Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting_and_default_dir() {
        assert_eq!(sh_quote("a'b c"), r"'a'\''b c'");
        assert_eq!(
            default_work_dir(Path::new("x/t.lut")),
            PathBuf::from("x/t.lut.slurm")
        );
    }
}
