//! Where a distributed run stands: each shard's state and the collect job's.

use super::*;

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
