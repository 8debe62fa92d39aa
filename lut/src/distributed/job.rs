//! The two kinds of distributed job: a table build and a robustness study.

use crate::progress::Progress;
use crate::robustness::RobustnessJob;
use crate::shard::ShardHeader;
use crate::table::{self, Grid, GridFile};
use crate::verify;
use anyhow::{anyhow, bail, Result};
use diagram::Diagram;
use serde::{Deserialize, Serialize};
use std::path::Path;

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

    /// Merge, check (checksum, every cell, the grid's identity, spot re-optimisation, the
    /// planning margin the header states), write.
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
        let rows = verify::verify(&back, self.verify_cells, self.verify_seed)?;
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
        let margin = verify::enforce_stated_margin(&back)
            .map_err(|e| anyhow!("merged table: {e}"))?
            .map(|line| format!("; {line}"))
            .unwrap_or_default();
        diagram::write_atomically(out, &bytes)?;
        Ok(format!(
            "table {name}: {} cells, LUT id 0x{:04x}, CRC-32C 0x{:08x}; {} cells re-optimised, all within tolerance{margin}",
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
