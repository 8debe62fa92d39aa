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
use crate::shard::{short, ShardHeader};
use crate::slurm::{self, Queued, Record, Submit};
use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

mod job;
mod status;
mod watch;

pub use job::{Job, TableJob};
pub use status::{CollectStatus, ShardState, ShardStatus, Status};
pub use watch::watch;

/// Spec file name in the work directory.
pub const SPEC_FILE: &str = "spec.json";
/// State file name in the work directory.
pub const STATE_FILE: &str = "state.json";

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
    Ok(diagram::write_atomically(path, text.as_bytes())?)
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

/// Quoted for sh (shlex; a path cannot hold the NUL byte it refuses).
fn sh_quote(s: &str) -> Result<String> {
    Ok(shlex::try_quote(s)
        .map_err(|e| anyhow!("{s:?}: {e}"))?
        .into_owned())
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
        diagram::write_atomically(&path, &bytes)?;
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
        let lut = sh_quote(&self.spec.lut.display().to_string())?;
        let dir = sh_quote(&self.dir.display().to_string())?;
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
        assert_eq!(
            shlex::split(&sh_quote("a'b c $HOME").unwrap()).unwrap(),
            ["a'b c $HOME"]
        );
        assert_eq!(
            default_work_dir(Path::new("x/t.lut")),
            PathBuf::from("x/t.lut.slurm")
        );
    }
}
