//! The Slurm client tools, called as a user would call them: `sbatch`, `squeue`, `scontrol`,
//! `scancel` from PATH, in this process's environment, so a user's `SLURM_CONF` and sbatch's
//! own `SBATCH_*` variables (partition, account, time limit, …) apply unchanged.
//!
//! No `sacct`: clusters without an accounting database (and the project's one-node test
//! cluster) have none. A job's end state is read with `scontrol show job` while slurmctld
//! still keeps its record (`MinJobAge`, 300 s by default), and the truth about a shard is its
//! file anyway. Not `sbatch --wait` either: it exits 0 for a job cancelled because its
//! dependency failed.
//!
//! The text parsers are pure functions, tested on output captured from Slurm 22.05.

use anyhow::{anyhow, bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// CPUs Slurm gave this task (`SLURM_CPUS_PER_TASK`, set when the job asked for
/// `--cpus-per-task`). Thread pools are sized from it: without cgroups a job sees every core
/// of the node, and rayon would start one thread per core.
pub fn cpus_per_task() -> Option<usize> {
    std::env::var("SLURM_CPUS_PER_TASK")
        .ok()?
        .trim()
        .parse()
        .ok()
        .filter(|&n| n > 0)
}

fn run(tool: &str, args: &[String]) -> Result<Output> {
    Command::new(tool).args(args).output().map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            anyhow!("{tool} not found on PATH: run this on a machine with the Slurm client tools (Debian: slurm-client) and SLURM_CONF pointing at your cluster")
        } else {
            anyhow!("cannot run {tool}: {e}")
        }
    })
}

fn checked(tool: &str, args: &[String]) -> Result<String> {
    let out = run(tool, args)?;
    if !out.status.success() {
        bail!(
            "{tool} {} failed ({}): {}",
            args.join(" "),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// One `sbatch` submission.
#[derive(Clone, Debug, Default)]
pub struct Submit {
    /// `--job-name`.
    pub job_name: String,
    /// `--array` (task list, e.g. `1-3,5`).
    pub array: Option<String>,
    /// `--cpus-per-task`.
    pub cpus_per_task: u32,
    /// `--output` (Slurm filename pattern: %a task, %A array job, %j job).
    pub output: PathBuf,
    /// `--chdir`.
    pub chdir: PathBuf,
    /// `--dependency=afterok:ID` (with `--kill-on-invalid-dep=yes`, so the job is cancelled
    /// rather than left pending forever when a task it waits for fails).
    pub after_ok: Option<String>,
    /// Further sbatch options, passed as given (e.g. `--mem=2G`).
    pub extra: Vec<String>,
    /// The batch script.
    pub script: PathBuf,
}

impl Submit {
    /// The sbatch arguments.
    pub fn args(&self) -> Vec<String> {
        let mut a = vec![
            "--parsable".to_string(),
            format!("--job-name={}", self.job_name),
            format!("--cpus-per-task={}", self.cpus_per_task),
            format!("--output={}", self.output.display()),
            format!("--chdir={}", self.chdir.display()),
        ];
        if let Some(list) = &self.array {
            a.push(format!("--array={list}"));
        }
        if let Some(id) = &self.after_ok {
            a.push(format!("--dependency=afterok:{id}"));
            a.push("--kill-on-invalid-dep=yes".into());
        }
        a.extend(self.extra.iter().cloned());
        a.push(self.script.display().to_string());
        a
    }
}

/// Submit; returns the job id.
pub fn sbatch(s: &Submit) -> Result<String> {
    let out = checked("sbatch", &s.args())?;
    parse_parsable(&out).with_context(|| format!("sbatch printed {out:?}, not a job id"))
}

/// `sbatch --parsable` prints `ID` or `ID;CLUSTER`.
pub fn parse_parsable(out: &str) -> Result<String> {
    let id = out.trim().split(';').next().unwrap_or("").trim();
    if id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        bail!("not a job id");
    }
    Ok(id.to_string())
}

/// A job (or array task) still in the queue.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Queued {
    /// Job id (for an array task: the array's job id).
    pub job: String,
    /// Array task id.
    pub task: Option<u32>,
    /// State (PENDING, RUNNING, COMPLETING, …).
    pub state: String,
    /// Reason (Dependency, Resources, None, …).
    pub reason: String,
}

impl Queued {
    /// Running in the broad sense (started, not yet gone).
    pub fn is_running(&self) -> bool {
        matches!(
            self.state.as_str(),
            "RUNNING" | "COMPLETING" | "CONFIGURING"
        )
    }
}

const SQUEUE_FORMAT: &str = "%F|%K|%T|%r";

/// Jobs and array tasks of `ids` still in the queue (one line per array task: `squeue -r`).
pub fn squeue(ids: &[String]) -> Result<Vec<Queued>> {
    if ids.is_empty() {
        return Ok(Vec::new());
    }
    let args = vec![
        "-h".into(),
        "-r".into(),
        "-j".into(),
        ids.join(","),
        "-o".into(),
        SQUEUE_FORMAT.into(),
    ];
    let out = run("squeue", &args)?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    // squeue fails when none of the ids is known any more: nothing of ours is queued.
    if !out.status.success() {
        if stderr.contains("Invalid job id") {
            return Ok(Vec::new());
        }
        bail!(
            "squeue {} failed ({}): {}",
            args.join(" "),
            out.status,
            stderr.trim()
        );
    }
    Ok(parse_squeue(&String::from_utf8_lossy(&out.stdout)))
}

/// Parse `squeue -h -r -o '%F|%K|%T|%r'` lines.
pub fn parse_squeue(text: &str) -> Vec<Queued> {
    text.lines()
        .filter_map(|l| {
            let mut f = l.trim().split('|');
            let (job, task, state, reason) = (f.next()?, f.next()?, f.next()?, f.next()?);
            Some(Queued {
                job: job.trim().to_string(),
                task: task.trim().parse().ok(),
                state: state.trim().to_string(),
                reason: reason.trim().to_string(),
            })
        })
        .collect()
}

/// slurmctld's record of a job or array task.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Record {
    /// Job id of this record (an array task has its own).
    pub job: String,
    /// Array job id.
    pub array_job: Option<String>,
    /// Array task id.
    pub task: Option<u32>,
    /// JobState.
    pub state: String,
    /// Reason.
    pub reason: String,
    /// ExitCode (`code:signal`).
    pub exit_code: String,
}

impl Record {
    /// Finished successfully.
    pub fn succeeded(&self) -> bool {
        self.state == "COMPLETED" && self.exit_code == "0:0"
    }

    /// "JobState=… Reason=… ExitCode=…".
    pub fn describe(&self) -> String {
        format!(
            "JobState={} Reason={} ExitCode={}",
            self.state, self.reason, self.exit_code
        )
    }
}

/// Records of job `id` (every task of an array); empty when slurmctld no longer knows it.
pub fn scontrol_show(id: &str) -> Result<Vec<Record>> {
    let args = vec!["-o".into(), "show".into(), "job".into(), id.to_string()];
    let out = run("scontrol", &args)?;
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        if stderr.contains("Invalid job id") {
            return Ok(Vec::new());
        }
        bail!(
            "scontrol {} failed ({}): {}",
            args.join(" "),
            out.status,
            stderr.trim()
        );
    }
    Ok(parse_scontrol(&String::from_utf8_lossy(&out.stdout)))
}

/// Parse `scontrol -o show job` (one record per line; `Key=Value` words).
pub fn parse_scontrol(text: &str) -> Vec<Record> {
    text.lines()
        .filter_map(|l| {
            let get = |key: &str| {
                l.split_whitespace()
                    .find_map(|w| w.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
                    .map(str::to_string)
            };
            Some(Record {
                job: get("JobId")?,
                array_job: get("ArrayJobId"),
                task: get("ArrayTaskId").and_then(|t| t.parse().ok()),
                state: get("JobState")?,
                reason: get("Reason").unwrap_or_default(),
                exit_code: get("ExitCode").unwrap_or_default(),
            })
        })
        .collect()
}

/// Cancel jobs or array tasks (`123`, `123_4`).
pub fn scancel(ids: &[String]) -> Result<()> {
    if ids.is_empty() {
        return Ok(());
    }
    checked("scancel", ids).map(|_| ())
}

/// Task list for `--array`: ascending ids, consecutive runs as ranges (`1-3,5,7-8`).
pub fn array_list(tasks: &[u32]) -> String {
    let mut t = tasks.to_vec();
    t.sort_unstable();
    t.dedup();
    let mut parts = Vec::new();
    let mut i = 0;
    while i < t.len() {
        let mut j = i;
        while j + 1 < t.len() && t[j + 1] == t[j] + 1 {
            j += 1;
        }
        parts.push(if j == i {
            t[i].to_string()
        } else {
            format!("{}-{}", t[i], t[j])
        });
        i = j + 1;
    }
    parts.join(",")
}

/// A throw-away one-node Slurm cluster (munged + slurmctld + slurmd on free local ports) started
/// by the repository's `tests/slurm-cluster.sh` (root; it installs slurm-wlm and munge where
/// missing): for the tests of every `--slurm N` command and for trying one without a cluster.
/// Stopped when dropped.
pub struct OneNodeCluster {
    script: PathBuf,
    dir: PathBuf,
    conf: PathBuf,
}

impl OneNodeCluster {
    /// Starts it with its configuration, state and logs in `dir`.
    ///
    /// # Errors
    /// The script did not start the daemons (its output is in the error).
    pub fn start(script: &Path, dir: &Path) -> Result<Self> {
        let free_port = || -> Result<u16> {
            Ok(std::net::TcpListener::bind("127.0.0.1:0")?
                .local_addr()?
                .port())
        };
        let out = Command::new("bash")
            .arg(script)
            .arg("start")
            .arg(dir)
            .env("SLURMCTLD_PORT", free_port()?.to_string())
            .env("SLURMD_PORT", free_port()?.to_string())
            .output()
            .with_context(|| format!("cannot run {}", script.display()))?;
        let stdout = String::from_utf8_lossy(&out.stdout);
        let conf = stdout
            .lines()
            .find_map(|l| l.strip_prefix("export SLURM_CONF="))
            .map(PathBuf::from);
        match (out.status.success(), conf) {
            (true, Some(conf)) => Ok(Self {
                script: script.to_path_buf(),
                dir: dir.to_path_buf(),
                conf,
            }),
            _ => bail!(
                "the one-node Slurm cluster did not start ({} must run as root; \
                 tests/setup-host.sh installs slurm-wlm and munge). Exit {}.\nstdout:\n{stdout}\nstderr:\n{}",
                script.display(),
                out.status,
                String::from_utf8_lossy(&out.stderr)
            ),
        }
    }

    /// Its `SLURM_CONF`.
    pub fn conf(&self) -> &Path {
        &self.conf
    }
}

impl Drop for OneNodeCluster {
    fn drop(&mut self) {
        let _ = Command::new("bash")
            .arg(&self.script)
            .arg("stop")
            .arg(&self.dir)
            .output();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_lists_are_compressed() {
        assert_eq!(array_list(&[5, 1, 2, 3, 8, 7]), "1-3,5,7-8");
        assert_eq!(array_list(&[4]), "4");
        assert_eq!(array_list(&[]), "");
    }

    #[test]
    fn parsable_job_ids() {
        assert_eq!(parse_parsable("123\n").unwrap(), "123");
        assert_eq!(parse_parsable("77;cluster\n").unwrap(), "77");
        assert!(parse_parsable("sbatch: error").is_err());
        assert!(parse_parsable("").is_err());
    }

    // Captured from Slurm 22.05.8 (tests/slurm-cluster.sh): an array 1,3,4 and a dependent job.
    #[test]
    fn squeue_lines() {
        let q = parse_squeue("1|1|RUNNING|None\n1|4|PENDING|Resources\n2|N/A|PENDING|Dependency\n");
        assert_eq!(q.len(), 3);
        assert_eq!(q[0].task, Some(1));
        assert!(q[0].is_running() && !q[1].is_running());
        assert_eq!(q[2].task, None);
        assert_eq!(q[2].reason, "Dependency");
    }

    #[test]
    fn scontrol_records() {
        let text = "JobId=4 ArrayJobId=1 ArrayTaskId=3 JobName=wrap UserId=root(0) JobState=FAILED Reason=NonZeroExitCode Dependency=(null) ExitCode=1:0 StdOut=/tmp/w/t_3.out\n\
                    JobId=2 JobName=wrap JobState=CANCELLED Reason=DependencyNeverSatisfied Dependency=afterok:1_*(failed) ExitCode=0:0\n\
                    JobId=3 ArrayJobId=1 ArrayTaskId=1 JobState=COMPLETED Reason=None ExitCode=0:0\n";
        let r = parse_scontrol(text);
        assert_eq!(r.len(), 3);
        assert_eq!(r[0].task, Some(3));
        assert_eq!(r[0].array_job.as_deref(), Some("1"));
        assert!(!r[0].succeeded());
        assert_eq!(
            r[0].describe(),
            "JobState=FAILED Reason=NonZeroExitCode ExitCode=1:0"
        );
        assert_eq!(r[1].task, None);
        assert_eq!(r[1].reason, "DependencyNeverSatisfied");
        assert!(r[2].succeeded());
    }

    #[test]
    fn submit_arguments() {
        let s = Submit {
            job_name: "lut-table".into(),
            array: Some("1-2".into()),
            cpus_per_task: 2,
            output: "/w/logs/shard-%a.%A.log".into(),
            chdir: "/w".into(),
            after_ok: None,
            extra: vec!["--mem=1G".into()],
            script: "/w/shard.sh".into(),
        };
        let a = s.args();
        assert!(
            a.contains(&"--array=1-2".to_string()) && a.contains(&"--cpus-per-task=2".to_string())
        );
        assert_eq!(a.last().map(String::as_str), Some("/w/shard.sh"));
        let c = Submit {
            after_ok: Some("12".into()),
            array: None,
            ..s
        };
        let a = c.args();
        assert!(a.contains(&"--dependency=afterok:12".to_string()));
        assert!(a.contains(&"--kill-on-invalid-dep=yes".to_string()));
    }
}
