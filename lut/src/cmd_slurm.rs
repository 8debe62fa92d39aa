//! Slurm options shared by `lut build` and `lut study robustness`, and `lut slurm
//! status | collect | cancel | shard` for a run's work directory.

use anyhow::{bail, Result};
use clap::{Args, Subcommand};
use lut::distributed::{self, Job, RunOptions, Work};
use lut::slurm;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Options of a command that can run as a Slurm job array.
#[derive(Args, Debug)]
pub struct SlurmArgs {
    /// Run on Slurm: N shards as one job array plus a dependent job that merges and checks
    /// them and writes the output. Running the command again resumes.
    #[arg(long, value_name = "N")]
    pub slurm: Option<usize>,
    /// CPUs per array task (the task's thread pool is sized from it).
    #[arg(long, default_value_t = 1, requires = "slurm")]
    pub cpus_per_task: u32,
    /// Submit and return; then `lut slurm status DIR`, or run the same command again to wait.
    #[arg(long, requires = "slurm")]
    pub no_wait: bool,
    /// Work directory on a file system the nodes share [default: OUT.slurm].
    #[arg(long, requires = "slurm")]
    pub work_dir: Option<PathBuf>,
    /// Extra sbatch option, passed as given (repeatable), e.g. --sbatch-arg=--mem=2G.
    /// SBATCH_* variables of the environment apply too.
    #[arg(
        long = "sbatch-arg",
        value_name = "OPT",
        allow_hyphen_values = true,
        requires = "slurm"
    )]
    pub sbatch_args: Vec<String>,
    /// Re-submit failed shards this many times before giving up.
    #[arg(long, default_value_t = 0, requires = "slurm")]
    pub retries: u32,
    /// Queue polling interval [s].
    #[arg(long, default_value_t = 2.0, requires = "slurm")]
    pub poll_seconds: f64,
}

impl SlurmArgs {
    /// Run `job` on Slurm, writing `out`.
    pub fn run(&self, n: usize, job: Job, out: &Path) -> Result<()> {
        if !(self.poll_seconds > 0.0 && self.poll_seconds < 3600.0) {
            bail!("--poll-seconds must be in (0, 3600)");
        }
        if self.cpus_per_task == 0 {
            bail!("--cpus-per-task must be ≥ 1");
        }
        let dir = self
            .work_dir
            .clone()
            .unwrap_or_else(|| distributed::default_work_dir(out));
        distributed::run(
            job,
            out,
            &dir,
            &RunOptions {
                n,
                cpus_per_task: self.cpus_per_task,
                sbatch_args: self.sbatch_args.clone(),
                no_wait: self.no_wait,
                retries: self.retries,
                poll: Duration::from_secs_f64(self.poll_seconds),
            },
        )
    }
}

#[derive(Subcommand, Debug)]
pub enum SlurmCommand {
    /// Where a distributed run stands: shards done / running / pending / failed, jobs, output.
    Status {
        /// Work directory (OUT.slurm by default).
        dir: PathBuf,
        /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
        #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
        json: Option<PathBuf>,
    },
    /// Merge and check the shards of a work directory and write its output (what the collect
    /// job runs; also usable by hand once every shard is done).
    Collect {
        /// Work directory.
        dir: PathBuf,
    },
    /// Cancel the queued jobs of a work directory's latest submission.
    Cancel {
        /// Work directory.
        dir: PathBuf,
    },
    /// Compute one shard of a work directory (what array task K runs).
    #[command(hide = true)]
    Shard {
        /// Work directory.
        dir: PathBuf,
        /// Shard K (1-based; the array task id).
        k: u32,
    },
}

pub fn run(cmd: &SlurmCommand) -> Result<()> {
    match cmd {
        SlurmCommand::Status { dir, json } => {
            let st = Work::open(dir)?.status(true)?;
            if let Some(to) = json {
                lut::json_out::write(to, &st)?;
            } else {
                print!("{}", st.report());
            }
            Ok(())
        }
        SlurmCommand::Collect { dir } => {
            let line = Work::open(dir)?.collect()?;
            eprintln!("{line}");
            Ok(())
        }
        SlurmCommand::Cancel { dir } => {
            let w = Work::open(dir)?;
            let ids = w
                .state()?
                .submissions
                .last()
                .map(lut::distributed::Submission::job_ids)
                .unwrap_or_default();
            slurm::scancel(&ids)?;
            eprintln!("cancelled jobs {}", ids.join(", "));
            Ok(())
        }
        SlurmCommand::Shard { dir, k } => Work::open(dir)?.run_shard(*k, slurm::cpus_per_task()),
    }
}
