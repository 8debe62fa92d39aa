//! `lut build | merge | verify | inspect | plot | export-json`: the characteristic diagram.

use crate::cmd_slurm::SlurmArgs;
use crate::heatmap::{self, HeatPanel};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use diagram::{AxisId, Cell, Diagram, Query};
use lut::distributed::{Job, TableJob};
use lut::margin;
use lut::progress::Progress;
use lut::table::{self, Grid, GridFile};
use lut::verify;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct BuildArgs {
    /// Grid file (TOML).
    #[arg(long, default_value = "data/default-grid.toml", value_parser = lut::paths::input_file)]
    pub grid: PathBuf,
    /// Output: a `.lut` table, or with --shard a shard file (default shard-K-of-N.bin).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Build only shard K of N (contiguous cell ranges; combine with `lut merge`).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Worker threads [default: SLURM_CPUS_PER_TASK inside a Slurm job, else all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress output.
    #[arg(long)]
    pub quiet: bool,
    /// With --slurm: cells of the merged table re-optimised before it is written (like
    /// `lut verify --cells`).
    #[arg(long, default_value_t = 8)]
    pub verify_cells: usize,
    /// With --slurm: seed of that check.
    #[arg(long, default_value_t = 1)]
    pub verify_seed: u64,
    #[command(flatten)]
    pub slurm: SlurmArgs,
}

fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let (k, n) = s
        .split_once('/')
        .ok_or_else(|| anyhow!("--shard {s}: expected K/N, e.g. 3/8"))?;
    Ok((
        k.trim().parse().context("--shard K")?,
        n.trim().parse().context("--shard N")?,
    ))
}

pub fn run_build(a: &BuildArgs) -> Result<()> {
    if let Some(n) = a.slurm.slurm {
        if a.shard.is_some() {
            bail!("--slurm splits the grid itself; drop --shard");
        }
        let out = a
            .out
            .clone()
            .unwrap_or_else(|| lut::paths::repo_output("data/default.lut"));
        let spec = GridFile::load(&a.grid)?;
        Grid::from_spec(&a.grid.display().to_string(), spec.clone())?;
        let job = Job::Table(TableJob {
            grid: spec,
            verify_cells: a.verify_cells,
            verify_seed: a.verify_seed,
        });
        return a.slurm.run(n, job, &out);
    }
    let grid = Grid::load(&a.grid)?;
    let count = grid.axes.cell_count();
    let lens = grid.axes.lens();
    let threads = a.threads.or_else(lut::slurm::cpus_per_task);
    match &a.shard {
        Some(spec) => {
            let (k, n) = parse_shard(spec)?;
            let out = a
                .out
                .clone()
                .unwrap_or_else(|| PathBuf::from(format!("shard-{k}-of-{n}.bin")));
            let range = table::shard_range(count, k, n)?;
            eprintln!(
                "building shard {k}/{n}: cells {range:?} of {count} ({lens:?}) from {}",
                a.grid.display()
            );
            let progress = Progress::new(range.len(), "optimising", "cells", a.quiet);
            let (shard, stats) = table::build_shard(&grid, k, n, threads, &progress)?;
            diagram::write_atomically(&out, &shard.to_bytes()?)?;
            report(&stats);
            eprintln!("shard written to {}", out.display());
        }
        None => {
            let out = a
                .out
                .clone()
                .unwrap_or_else(|| lut::paths::repo_output("data/default.lut"));
            eprintln!(
                "building {count} cells ({lens:?}) from {}",
                a.grid.display()
            );
            let (d, stats) = table::build_table(&grid, threads, a.quiet)?;
            d.save(&out)?;
            report(&stats);
            let bottoming = d.cells().iter().filter(|c| c.is_bottoming_out()).count();
            eprintln!("table written to {} (LUT id 0x{:04x}, CRC-32C 0x{:08x}, {bottoming} bottoming-out cells)", out.display(), d.lut_id(), d.checksum());
        }
    }
    Ok(())
}

fn report(s: &table::BuildStats) {
    let secs = s.wall.as_secs_f64();
    eprintln!(
        "{} cells in {secs:.1} s: {:.1} optimisations/s, {:.0} occupant simulations/s ({} simulations, {} threads)",
        s.cells,
        s.cells as f64 / secs,
        s.occupant_simulations as f64 / secs,
        s.occupant_simulations,
        rayon::current_num_threads()
    );
}

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Shard files (any order).
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Output table.
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run_merge(a: &MergeArgs) -> Result<()> {
    let shards = a
        .shards
        .iter()
        .map(|p| {
            let bytes = std::fs::read(p).with_context(|| format!("reading {}", p.display()))?;
            let origin = p.display().to_string();
            Ok((origin.clone(), table::read_shard(&origin, &bytes)?))
        })
        .collect::<Result<Vec<_>>>()?;
    let d = table::merge_shards(&shards, None)?;
    d.save(&a.out)?;
    eprintln!(
        "merged {} shards into {} (LUT id 0x{:04x})",
        shards.len(),
        a.out.display(),
        d.lut_id()
    );
    Ok(())
}

#[derive(Args, Debug)]
pub struct VerifyArgs {
    /// Table file (.lut or .json).
    #[arg(value_parser = lut::paths::input_file)]
    pub file: PathBuf,
    /// Number of random cells to re-optimise.
    #[arg(long, default_value_t = 20)]
    pub cells: usize,
    /// Seed for the cell choice and the independent re-optimisations.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<PathBuf>,
    /// The planning margin's check over every cell: a setting planned for opponent mass M
    /// judged at every true opponent from M − this down to M (`lut::margin`). Default: the span
    /// the table states in its header (then enforced), else 2 400 kg (then reported only).
    /// Given explicitly, it is enforced.
    #[arg(long)]
    pub margin_kg: Option<f64>,
    /// Step between the true opponent masses of the margin check [kg].
    #[arg(long, default_value_t = margin::DEFAULT_STEP_KG)]
    pub margin_step_kg: f64,
}

pub fn run_verify(a: &VerifyArgs) -> Result<()> {
    let d = Diagram::load_any(&a.file)?;
    let rows = verify::verify(&d, a.cells, a.seed)?;
    if let Some(to) = &a.json {
        lut::json_out::write(to, &rows)?;
    } else {
        println!(
            "{:>6} {:<14} {:>9} {:>9} {:>9} {:>6} {:>6}  result",
            "cell", "coords", "table g", "resim g", "reopt g", "bottom", "reopt"
        );
        for r in &rows {
            println!(
                "{:>6} {:<14} {:>9.3} {:>9.3} {:>9.3} {:>6} {:>6}  {}",
                r.index,
                format!("{:?}", r.coords),
                r.table_objective_g,
                r.resimulated_objective_g,
                r.reoptimised_objective_g,
                r.table_bottoming_out,
                r.reoptimised_bottoming_out,
                r.problem.as_deref().unwrap_or("ok")
            );
        }
    }
    let bad = rows.iter().filter(|r| !r.ok).count();
    eprintln!(
        "{}: {} of {} cells verified (tolerances: re-simulation max({} g, {} %), re-optimisation max({} g, {} %))",
        a.file.display(),
        rows.len() - bad,
        rows.len(),
        verify::RESIM_TOL_ABS_G,
        verify::RESIM_TOL_REL * 100.0,
        verify::REOPT_TOL_ABS_G,
        verify::REOPT_TOL_REL * 100.0
    );
    let margin_failed = verify_margin(&d, a)?;
    if bad > 0 {
        return Err(host::CheckFailed(format!(
            "{bad} of {} verified cells do not match",
            rows.len()
        ))
        .into());
    }
    if let Some(why) = margin_failed {
        return Err(host::CheckFailed(why).into());
    }
    Ok(())
}

/// The planning margin's check over every cell (`lut::margin`), printed on stderr; `Some(why)`
/// when it fails and is enforced (the span stated in the header, or given).
fn verify_margin(d: &Diagram, a: &VerifyArgs) -> Result<Option<String>> {
    let stated = margin::stated_span_kg(d)?;
    let (span_kg, enforced) = match (a.margin_kg, stated) {
        (Some(kg), _) => (kg, true),
        (None, Some(kg)) => (kg, true),
        (None, None) => (margin::DEFAULT_SPAN_KG, false),
    };
    if !(span_kg.is_finite()
        && span_kg >= 0.0
        && a.margin_step_kg.is_finite()
        && a.margin_step_kg > 0.0)
    {
        bail!("--margin-kg must be ≥ 0 and --margin-step-kg > 0 (finite)");
    }
    let reference = margin::reference_settings()?;
    let rows = verify::check_margin(d, &reference, span_kg, a.margin_step_kg)?;
    let s = margin::MarginSummary::of(&rows);
    let source = match (a.margin_kg, stated) {
        (Some(_), _) => "given",
        (None, Some(_)) => "stated in the header",
        (None, None) => {
            "the shipped rule's 2 × 1 200 kg; the table states none: reported, not enforced"
        }
    };
    eprintln!(
        "planning margin ({source}): each cell's setting, planned for opponent mass M, on the true pulse of every opponent from M − {span_kg:.0} kg to M ({:.0} kg steps, airbag as executed), against the reference restraint",
        a.margin_step_kg
    );
    eprintln!(
        "  safety: holds in {} of {} cells (bottoms out where the reference does not: {} cells; strikes through deeper where both do: {})",
        s.hold, s.cells, s.bottom_out_alone, s.strike_deeper
    );
    eprintln!(
        "  benefit: a_max + a_mean worse than the reference at a lighter opponent in {} cells (their worst: p50 {:+.1} %); not enforced — the offline misreport grids judge it closed loop",
        s.worse, s.worse_p50_change_pct
    );
    if let Some(w) = &s.worst {
        let q = d.axes();
        let at = |axis: &[f32], i: usize| axis.get(i).copied().unwrap_or(f32::NAN);
        eprintln!(
            "  worst: cell {} ({} km/h, {} kg planned, occupant {} kg, seat {} mm) at a {:.0} kg opponent: {:+.1} %, bottoming out alone at {} and deeper at {} lighter opponents",
            w.index,
            at(&q.closing_speed_kph, w.coords[0]),
            at(&q.opponent_mass_kg, w.coords[1]),
            at(&q.occupant_mass_kg, w.coords[2]),
            at(&q.seat_distance_mm, w.coords[3]),
            w.worst_truth_kg,
            w.worst_change_pct,
            w.bottoms_out_alone,
            w.strikes_deeper
        );
    }
    Ok((enforced && !s.holds()).then(|| {
        format!(
            "planning margin of {span_kg:.0} kg fails in {} of {} cells",
            s.cells - s.hold,
            s.cells
        )
    }))
}

#[derive(Args, Debug)]
pub struct InspectArgs {
    /// Table file (.lut or .json).
    #[arg(value_parser = lut::paths::input_file)]
    pub file: PathBuf,
    /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<PathBuf>,
}

fn field_stats(cells: &[Cell]) -> Vec<(&'static str, f64, f64, f64)> {
    Cell::FIELD_NAMES
        .iter()
        .enumerate()
        .map(|(i, &name)| {
            let vals = cells.iter().map(|c| f64::from(c.to_array()[i]));
            let (mut lo, mut hi, mut sum) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
            for v in vals {
                lo = lo.min(v);
                hi = hi.max(v);
                sum += v;
            }
            (name, lo, sum / cells.len().max(1) as f64, hi)
        })
        .collect()
}

pub fn run_inspect(a: &InspectArgs) -> Result<()> {
    let d = Diagram::load_any(&a.file)?;
    let h = d.header();
    let cells = d.cells();
    let bottoming = cells.iter().filter(|c| c.is_bottoming_out()).count();
    let no_fire = cells
        .iter()
        .filter(|c| c.airbag_level_kn < h.airbag_thresholds.no_fire_below_kn)
        .count();
    let stats = field_stats(cells);
    let axes = d.axes();
    if let Some(to) = &a.json {
        let v = serde_json::json!({
            "file": a.file.display().to_string(),
            "lut_id": d.lut_id(),
            "crc32c": d.checksum(),
            "header": h,
            "axes": axes,
            "cells": cells.len(),
            "bottoming_out_cells": bottoming,
            "airbag_no_fire_cells": no_fire,
            "fields": stats.iter().map(|(n, lo, mean, hi)| serde_json::json!({"field": n, "min": lo, "mean": mean, "max": hi})).collect::<Vec<_>>(),
        });
        lut::json_out::write(to, &v)?;
        return Ok(());
    }
    println!("file            {}", a.file.display());
    println!(
        "LUT id          0x{:04x} (CRC-32C 0x{:08x})",
        d.lut_id(),
        d.checksum()
    );
    println!(
        "ego             {} kg, class {}: {}",
        h.ego.mass_kg, h.ego.class, h.ego.description
    );
    println!(
        "build           seed {}, restitution {}, defaults hash {}",
        h.build.optimiser_seed, h.build.restitution, h.build.defaults_hash
    );
    for (k, v) in &h.build.extra {
        println!("                {k} = {v}");
    }
    println!(
        "airbag stages   no fire < {} kN, stage 2 ≥ {} kN",
        h.airbag_thresholds.no_fire_below_kn, h.airbag_thresholds.stage2_from_kn
    );
    for (axis, pts) in AxisId::ALL.iter().zip(axes.as_slices()) {
        println!(
            "axis {:<19} {:>3} points {:>7} … {:<7} {:?}",
            axis.name(),
            pts.len(),
            pts.first().unwrap_or(&f32::NAN),
            pts.last().unwrap_or(&f32::NAN),
            pts
        );
    }
    println!(
        "cells           {} ({} bottoming-out = no feasible setting, {} airbag no-fire)",
        cells.len(),
        bottoming,
        no_fire
    );
    println!("{:<22} {:>10} {:>10} {:>10}", "field", "min", "mean", "max");
    for (n, lo, mean, hi) in stats {
        println!("{n:<22} {lo:>10.3} {mean:>10.3} {hi:>10.3}");
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// Table file.
    #[arg(value_parser = lut::paths::input_file)]
    pub file: PathBuf,
    /// JSON output file.
    #[arg(long = "json", alias = "out", value_name = "FILE")]
    pub out: PathBuf,
}

pub fn run_export(a: &ExportArgs) -> Result<()> {
    let d = Diagram::load_any(&a.file)?;
    d.save_json(&a.out)?;
    eprintln!("{} written", a.out.display());
    Ok(())
}

#[derive(Args, Debug)]
pub struct PlotArgs {
    /// Table file.
    #[arg(value_parser = lut::paths::input_file)]
    pub file: PathBuf,
    /// Output field to plot (one of the cell fields, e.g. a_max_g, belt_limiter_kn).
    #[arg(long, default_value = "a_max_g")]
    pub field: String,
    /// Horizontal axis.
    #[arg(long, default_value = "closing_speed_kph")]
    pub x: String,
    /// Vertical axis.
    #[arg(long, default_value = "occupant_mass_kg")]
    pub y: String,
    /// Values of the other two axes, NAME=VALUE (interpolated); default 1800 kg opponent, 300 mm seat,
    /// 75 kg occupant, 80 km/h.
    #[arg(long = "slice", value_name = "AXIS=VALUE")]
    pub slice: Vec<String>,
    /// Output picture (.png or .svg).
    #[arg(long = "plot", alias = "out", value_name = "FILE")]
    pub out: PathBuf,
}

fn axis_by_name(n: &str) -> Result<AxisId> {
    AxisId::ALL
        .iter()
        .copied()
        .find(|a| a.name() == n)
        .ok_or_else(|| {
            anyhow!(
                "unknown axis {n:?}; axes: {}",
                AxisId::ALL.map(|a| a.name()).join(", ")
            )
        })
}

pub fn run_plot(a: &PlotArgs) -> Result<()> {
    let d = Diagram::load_any(&a.file)?;
    let fi = Cell::FIELD_NAMES
        .iter()
        .position(|f| *f == a.field)
        .ok_or_else(|| {
            anyhow!(
                "unknown field {:?}; fields: {}",
                a.field,
                Cell::FIELD_NAMES.join(", ")
            )
        })?;
    let (ax, ay) = (axis_by_name(&a.x)?, axis_by_name(&a.y)?);
    if ax == ay {
        bail!("--x and --y must differ");
    }
    let mut base = [80.0f32, 1800.0, 75.0, 300.0];
    for s in &a.slice {
        let (n, v) = s
            .split_once('=')
            .ok_or_else(|| anyhow!("--slice {s}: expected AXIS=VALUE"))?;
        base[axis_by_name(n.trim())?.index()] =
            v.trim().parse().with_context(|| format!("--slice {s}"))?;
    }
    let axes = d.axes().as_slices();
    let xs: Vec<f64> = axes[ax.index()].iter().map(|&v| f64::from(v)).collect();
    let ys: Vec<f64> = axes[ay.index()].iter().map(|&v| f64::from(v)).collect();
    let mut z = Vec::new();
    let mut marked = Vec::new();
    for &y in &ys {
        let mut row = Vec::new();
        let mut mrow = Vec::new();
        for &x in &xs {
            let mut q = base;
            q[ax.index()] = x as f32;
            q[ay.index()] = y as f32;
            let l = d.lookup(&Query::from_array(q));
            row.push(f64::from(l.values.to_array()[fi]));
            mrow.push(l.bottoming_out);
        }
        z.push(row);
        marked.push(mrow);
    }
    let fixed: Vec<String> = AxisId::ALL
        .iter()
        .filter(|&&i| i != ax && i != ay)
        .map(|i| format!("{} = {}", i.name(), base[i.index()]))
        .collect();
    heatmap::draw(
        &a.out,
        &[HeatPanel {
            title: format!("{} at {}", a.field, fixed.join(", ")),
            x_label: ax.name().into(),
            y_label: ay.name().into(),
            x: xs,
            y: ys,
            z,
            marked: Some(marked),
            decimals: 1,
        }],
    )?;
    eprintln!(
        "plot written to {} (framed cells: bottoming-out)",
        a.out.display()
    );
    Ok(())
}
