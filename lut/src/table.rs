//! Characteristic-diagram building: grid files, one optimum per cell, sharded parallel builds
//! and merging (checking a built table is [`crate::verify`]'s).
//!
//! Every cell is independent: its collision is simulated once, its optimiser is seeded from the
//! grid seed and the cell index only. Hence a build is byte-identical whatever the thread count
//! or sharding, and `lut merge` of shards equals a full build.

use crate::fire_floor::SatelliteRelief;
use crate::hash::{fnv1a, splitmix64};
use crate::margin;
use crate::optimise::{self, Case, OptimiserConfig, SearchSpace};
use crate::progress::Progress;
use crate::scenario::{Ego, Opponent, Pulse};
pub use crate::shard::shard_range;
use crate::shard::{self, Payload, ShardFile, ShardHeader};
use anyhow::{anyhow, bail, Context, Result};
use diagram::{AirbagThresholds, Axes, BuildInfo, Cell, Diagram, EgoVehicle, GridPoint, Header};
use physics::{
    defaults, mps2_to_g, MassClass, OccupantInput, OccupantOutcome, RestraintHardware,
    RestraintSettings,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Grid file schema (TOML), see data/default-grid.toml.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridFile {
    /// Ego vehicle.
    pub ego: EgoSpec,
    /// Optimiser effort and seed.
    pub optimiser: OptimiserSpec,
    /// Axis points.
    pub axes: AxesSpec,
    /// The planning margin the cells must hold (`lut::margin`); none: cells as optimised.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robust: Option<RobustSpec>,
}

/// `[robust]` of a grid file: every cell's setting, planned for opponent mass M, must not
/// bottom out (or strike deeper than the reference restraint) at any opponent from
/// M − `lighter_opponent_kg` to M; a cell whose optimum does is re-optimised over those
/// opponents (`lut::margin::LighterSet::robust_optimum`). Written to the table's header.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobustSpec {
    /// The span below the planned opponent mass [kg].
    pub lighter_opponent_kg: f64,
}

impl GridFile {
    /// Read a grid file (not validated: see [`Grid::from_spec`]).
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        toml::from_str(&text).with_context(|| format!("{}: invalid grid file", path.display()))
    }
}

/// `[ego]` of a grid file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EgoSpec {
    /// Ego mass [kg].
    pub mass_kg: f64,
    /// Ego stiffness class 1..=6.
    pub class: u8,
    /// Free text.
    pub description: String,
}

/// `[optimiser]` of a grid file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OptimiserSpec {
    /// Base seed (each cell's swarm is seeded from it and the cell index).
    pub seed: u64,
    /// Swarm size.
    pub particles: usize,
    /// Swarm iterations.
    pub pso_iterations: u64,
    /// Nelder–Mead iterations.
    pub nm_iterations: u64,
}

/// `[axes]` of a grid file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxesSpec {
    /// Car-to-car closing speed [km/h].
    pub closing_speed_kph: Vec<f32>,
    /// Opponent mass [kg].
    pub opponent_mass_kg: Vec<f32>,
    /// Occupant mass [kg].
    pub occupant_mass_kg: Vec<f32>,
    /// Seat distance chest to wheel [mm].
    pub seat_distance_mm: Vec<f32>,
}

/// A validated grid: what to build.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Ego vehicle.
    pub ego: Ego,
    /// Ego description (stored in the header).
    pub description: String,
    /// Optimiser configuration (seed = base seed).
    pub optimiser: OptimiserConfig,
    /// Axes.
    pub axes: Axes,
    /// The planning margin's span the cells hold [kg] (`[robust]`), if any.
    pub robust_lighter_opponent_kg: Option<f64>,
}

const EXTRA_PARTICLES: &str = "optimiser.particles";
const EXTRA_PSO: &str = "optimiser.pso_iterations";
const EXTRA_NM: &str = "optimiser.nm_iterations";
const EXTRA_NM_TOL: &str = "optimiser.nm_sd_tolerance_g";
const EXTRA_NO_FIRE: &str = "optimiser.no_fire_below_kn";
const EXTRA_RESERVE: &str = "optimiser.ride_down_reserve_mm";
const EXTRA_FIRE_DELAY: &str = "optimiser.fire_delay_tolerance_ms";
const EXTRA_AIRBAG_FLOOR: &str = "optimiser.airbag_floor_dv_mps";
const EXTRA_ECU_LATENCY: &str = "optimiser.ecu_latency_ms";
const EXTRA_SAT_FLOOR: &str = "optimiser.satellite_floor_dv_mps";
const EXTRA_SAT_FROM: &str = "optimiser.satellite_relief_from_mps";
const EXTRA_SAT_FULL: &str = "optimiser.satellite_relief_full_mps";
const EXTRA_SAT_WINDOW: &str = "optimiser.satellite_window_ms";
const EXTRA_SAT_LAG: &str = "optimiser.satellite_lag_ms";
const EXTRA_SAT_DEPTH: &str = "optimiser.satellite_depth_m";
const EXTRA_SAT_BOUNDARY: &str = "optimiser.satellite_boundary_scale";
const EXTRA_ACCEL_ONLY: &str = "optimiser.accel_only_below_kph";

impl Grid {
    /// Parse and validate grid TOML; `origin` names the source in errors.
    pub fn parse(origin: &str, text: &str) -> Result<Self> {
        let f: GridFile =
            toml::from_str(text).with_context(|| format!("{origin}: invalid grid file"))?;
        Self::from_spec(origin, f)
    }

    /// Validate a parsed grid file; `origin` names the source in errors.
    pub fn from_spec(origin: &str, f: GridFile) -> Result<Self> {
        let class = MassClass::new(f.ego.class).map_err(|e| anyhow!("{origin}: ego.class: {e}"))?;
        if !(f.ego.mass_kg.is_finite() && f.ego.mass_kg > 100.0) {
            bail!("{origin}: ego.mass_kg must be a finite mass > 100 kg");
        }
        if f.optimiser.particles < 2 {
            bail!("{origin}: optimiser.particles must be ≥ 2");
        }
        let axes = Axes::new(
            f.axes.closing_speed_kph,
            f.axes.opponent_mass_kg,
            f.axes.occupant_mass_kg,
            f.axes.seat_distance_mm,
        );
        axes.validate().map_err(|e| anyhow!("{origin}: {e}"))?;
        let seat = &axes.seat_distance_mm;
        let lo = defaults::MODULE_THICKNESS_M * 1e3;
        if seat.first().is_some_and(|&d| f64::from(d) <= lo) {
            bail!("{origin}: seat_distance_mm must exceed the {lo} mm module thickness");
        }
        let robust_lighter_opponent_kg = match f.robust {
            None => None,
            Some(r) if r.lighter_opponent_kg.is_finite() && r.lighter_opponent_kg > 0.0 => {
                Some(r.lighter_opponent_kg)
            }
            Some(r) => bail!(
                "{origin}: robust.lighter_opponent_kg must be a finite mass > 0 kg, not {}",
                r.lighter_opponent_kg
            ),
        };
        let optimiser = OptimiserConfig {
            seed: f.optimiser.seed,
            particles: f.optimiser.particles,
            pso_iterations: f.optimiser.pso_iterations,
            nm_iterations: f.optimiser.nm_iterations,
            ..OptimiserConfig::default()
        };
        Ok(Grid {
            ego: Ego {
                mass_kg: f.ego.mass_kg,
                class,
            },
            description: f.ego.description,
            optimiser,
            axes,
            robust_lighter_opponent_kg,
        })
    }

    /// Read a grid file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        Self::from_spec(&path.display().to_string(), GridFile::load(path)?)
    }

    /// The header a build of this grid writes. Contains no time stamp, host or thread count,
    /// so that rebuilds are byte-identical.
    pub fn header(&self) -> Header {
        let mut extra = BTreeMap::new();
        let o = &self.optimiser;
        extra.insert("tool".into(), format!("lut {}", env!("CARGO_PKG_VERSION")));
        extra.insert(
            "optimiser".into(),
            "argmin particle swarm + Nelder-Mead, unit-cube coordinates".into(),
        );
        extra.insert(EXTRA_PARTICLES.into(), o.particles.to_string());
        extra.insert(EXTRA_PSO.into(), o.pso_iterations.to_string());
        extra.insert(EXTRA_NM.into(), o.nm_iterations.to_string());
        extra.insert(EXTRA_NM_TOL.into(), format!("{:e}", o.nm_sd_tolerance));
        extra.insert(EXTRA_NO_FIRE.into(), format!("{}", o.no_fire_below_n / 1e3));
        extra.insert(EXTRA_RESERVE.into(), format!("{}", o.reserve_m * 1e3));
        extra.insert(
            EXTRA_FIRE_DELAY.into(),
            format!("{}", o.fire_delay_tolerance_s * 1e3),
        );
        extra.insert(
            EXTRA_AIRBAG_FLOOR.into(),
            format!("{}", o.airbag_floor_dv_mps),
        );
        extra.insert(
            EXTRA_ECU_LATENCY.into(),
            format!("{}", o.ecu_latency_s * 1e3),
        );
        let r = &o.satellite_relief;
        if r.is_on() {
            extra.insert(EXTRA_SAT_FLOOR.into(), format!("{}", r.floor_mps));
            extra.insert(EXTRA_SAT_FROM.into(), format!("{}", r.from_mps));
            extra.insert(EXTRA_SAT_FULL.into(), format!("{}", r.full_mps));
            extra.insert(EXTRA_SAT_WINDOW.into(), format!("{}", r.window_s * 1e3));
            extra.insert(EXTRA_SAT_LAG.into(), format!("{}", r.lag_s * 1e3));
            extra.insert(EXTRA_SAT_DEPTH.into(), format!("{}", r.depth_m));
            extra.insert(EXTRA_SAT_BOUNDARY.into(), format!("{}", r.boundary_scale));
        }
        if o.accel_only_below_mps.is_finite() {
            extra.insert(
                EXTRA_ACCEL_ONLY.into(),
                format!("{}", o.accel_only_below_mps * 3.6),
            );
        }
        extra.insert(
            "occupant".into(),
            "belted; seat friction and hardware: physics::defaults".into(),
        );
        if let Some(kg) = self.robust_lighter_opponent_kg {
            extra.insert(diagram::EXTRA_LIGHTER_OPPONENT_KG.into(), format!("{kg}"));
        }
        extra.insert(
            "objective".into(),
            "a_max_g + a_mean_g, no bottoming-out (penalty)".into(),
        );
        Header {
            ego: EgoVehicle {
                mass_kg: self.ego.mass_kg as f32,
                class: self.ego.class.number(),
                description: self.description.clone(),
            },
            build: BuildInfo {
                optimiser_seed: o.seed,
                restitution: defaults::RESTITUTION as f32,
                defaults_hash: defaults_hash(),
                extra,
            },
            airbag_thresholds: AirbagThresholds::DEFAULT,
        }
    }

    /// Reconstruct the grid a table was built from (for `lut verify`).
    pub fn from_table(d: &Diagram) -> Result<Self> {
        let h = d.header();
        let get = |k: &str| -> Result<String> {
            h.build
                .extra
                .get(k)
                .cloned()
                .ok_or_else(|| anyhow!("table header lacks build.extra[{k:?}]"))
        };
        let optimiser = OptimiserConfig {
            seed: h.build.optimiser_seed,
            particles: get(EXTRA_PARTICLES)?.parse()?,
            pso_iterations: get(EXTRA_PSO)?.parse()?,
            nm_iterations: get(EXTRA_NM)?.parse()?,
            nm_sd_tolerance: get(EXTRA_NM_TOL)?.parse()?,
            no_fire_below_n: get(EXTRA_NO_FIRE)?.parse::<f64>()? * 1e3,
            reserve_m: get(EXTRA_RESERVE)?.parse::<f64>()? * 1e-3,
            fire_delay_tolerance_s: get(EXTRA_FIRE_DELAY)?.parse::<f64>()? * 1e-3,
            // Tables built before plan = fire have no floor: 0 rebuilds them as built.
            airbag_floor_dv_mps: get(EXTRA_AIRBAG_FLOOR).map_or(Ok(0.0), |v| v.parse())?,
            ecu_latency_s: get(EXTRA_ECU_LATENCY).map_or(Ok(0.0), |v| v.parse::<f64>())? * 1e-3,
            // Tables built without the satellites' relief have none of its keys.
            satellite_relief: match h.build.extra.get(EXTRA_SAT_FLOOR) {
                None => SatelliteRelief::OFF,
                Some(floor) => SatelliteRelief {
                    floor_mps: floor.parse()?,
                    from_mps: get(EXTRA_SAT_FROM)?.parse()?,
                    full_mps: get(EXTRA_SAT_FULL)?.parse()?,
                    window_s: get(EXTRA_SAT_WINDOW)?.parse::<f64>()? * 1e-3,
                    lag_s: get(EXTRA_SAT_LAG)?.parse::<f64>()? * 1e-3,
                    depth_m: get(EXTRA_SAT_DEPTH)?.parse()?,
                    boundary_scale: get(EXTRA_SAT_BOUNDARY)?.parse()?,
                },
            },
            // Tables built before the accelerometer-only wait have no key: never.
            accel_only_below_mps: h
                .build
                .extra
                .get(EXTRA_ACCEL_ONLY)
                .map_or(Ok(f64::NEG_INFINITY), |v| {
                    v.parse::<f64>().map(|kph| kph / 3.6)
                })?,
        };
        Ok(Grid {
            ego: Ego {
                mass_kg: f64::from(h.ego.mass_kg),
                class: MassClass::new(h.ego.class)?,
            },
            description: h.ego.description.clone(),
            optimiser,
            axes: d.axes().clone(),
            robust_lighter_opponent_kg: margin::stated_span_kg(d)?,
        })
    }

    /// The lighter opponents of grid point `p` for the planning margin (`lut::margin`): from
    /// its mass down by `span_kg` in `step_kg` steps, never below the mass axis' lightest.
    ///
    /// # Errors
    /// The mass axis is empty, or a pulse / reference simulation fails.
    pub fn lighter_set(
        &self,
        p: &GridPoint,
        span_kg: f64,
        step_kg: f64,
        reference: &RestraintSettings,
        cfg: &OptimiserConfig,
    ) -> Result<margin::LighterSet> {
        let floor_kg = self
            .axes
            .opponent_mass_kg
            .first()
            .map(|&m| f64::from(m))
            .ok_or_else(|| anyhow!("no mass axis"))?;
        let span = margin::Span {
            lighter_opponent_kg: span_kg,
            step_kg,
            floor_kg,
        };
        margin::LighterSet::new(
            &self.ego,
            &p.query,
            &occupant_at(&p.query),
            &span,
            reference,
            cfg,
        )
    }

    /// Optimiser configuration of one cell: the base seed mixed with the cell index
    /// (SplitMix64), so a cell's result does not depend on which shard or thread computes it.
    pub fn cell_config(&self, index: usize) -> OptimiserConfig {
        OptimiserConfig {
            seed: splitmix64(self.optimiser.seed ^ splitmix64(index as u64)),
            ..self.optimiser
        }
    }
}

/// FNV-1a hash (hex) of every physics default a table depends on: restraint hardware,
/// stiffness classes, step, pulse length and restitution. A table built with other defaults
/// shows a different hash in `lut inspect`.
pub fn defaults_hash() -> String {
    let text = format!(
        "{:?}|{:?}|{:?}|{}|{}|{}",
        RestraintHardware::default(),
        physics::stiffness::CLASS_CURVES,
        physics::stiffness::COMBINED_CURVE,
        defaults::STEP_S,
        defaults::PULSE_DURATION_S,
        defaults::RESTITUTION
    );
    format!("{:016x}", fnv1a(text.as_bytes()))
}

/// The belted occupant of a grid point.
pub fn occupant_at(q: &diagram::Query) -> OccupantInput {
    OccupantInput {
        mass_kg: f64::from(q.occupant_mass_kg),
        chest_to_wheel_m: f64::from(q.seat_distance_mm) * 1e-3,
        belted: true,
    }
}

/// The predicted ego pulse of a grid point (car-to-car with an opponent of the point's mass).
pub fn pulse_at(ego: &Ego, q: &diagram::Query) -> Result<Pulse> {
    Pulse::predict(
        ego,
        Opponent::Car {
            mass_kg: f64::from(q.opponent_mass_kg),
        },
        f64::from(q.closing_speed_kph),
    )
}

/// Turn an optimum into a diagram cell.
pub fn cell_of(set: &RestraintSettings, o: &OccupantOutcome) -> Cell {
    Cell {
        belt_limiter_kn: (set.load_limiter_n * 1e-3) as f32,
        airbag_level_kn: (set.airbag_force_n * 1e-3) as f32,
        pretensioner_time_ms: (set.pretensioner_time_s * 1e3) as f32,
        airbag_time_ms: (set.airbag_time_s * 1e3) as f32,
        a_max_g: mps2_to_g(o.max_decel_mps2) as f32,
        a_mean_g: mps2_to_g(o.mean_decel_mps2) as f32,
        excursion_mm: (o.max_excursion_m * 1e3) as f32,
        bottoming_out: if o.bottomed_out { 1.0 } else { 0.0 },
        a_ideal_g: mps2_to_g(o.ideal_decel_mps2) as f32,
    }
}

/// Settings stored in a cell, in SI units.
pub fn settings_of(c: &Cell) -> RestraintSettings {
    RestraintSettings {
        load_limiter_n: f64::from(c.belt_limiter_kn) * 1e3,
        airbag_force_n: f64::from(c.airbag_level_kn) * 1e3,
        pretensioner_time_s: f64::from(c.pretensioner_time_ms) * 1e-3,
        airbag_time_s: f64::from(c.airbag_time_ms) * 1e-3,
    }
}

/// One optimised cell.
#[derive(Clone, Debug)]
pub struct CellResult {
    /// The cell.
    pub cell: Cell,
    /// The full optimum.
    pub optimum: optimise::Optimum,
}

/// Optimise the cell at grid point `p` with `cfg`.
pub fn optimise_point(grid: &Grid, p: &GridPoint, cfg: &OptimiserConfig) -> Result<CellResult> {
    let optimum = optimise_query(
        &grid.ego,
        &p.query,
        SearchSpace::adaptive(),
        &RestraintHardware::default(),
        cfg,
    )
    .with_context(|| format!("cell {} {:?}", p.index, p.coords))?;
    let optimum = match grid.robust_lighter_opponent_kg {
        Some(span_kg) => hold_margin(grid, p, cfg, optimum, span_kg)
            .with_context(|| format!("cell {} {:?}: planning margin", p.index, p.coords))?,
        None => optimum,
    };
    let o = optimum
        .outcomes
        .first()
        .ok_or_else(|| anyhow!("no outcome"))?;
    Ok(CellResult {
        cell: cell_of(&optimum.settings, o),
        optimum,
    })
}

/// The cell's optimum if it holds the planning margin over `span_kg` (`lut::margin`), else the
/// robust setting over the lighter opponents if that one holds it, else the reference
/// restraint. Why the reference: the margin compares a setting with the reference as the ECU
/// executes both at every lighter truth (the airbag no earlier than that pulse lets the ECU
/// fire one), so the reference, planned with the nominal pulse's airbag floor, holds it by
/// construction — the cell gives up its benefit where no adaptive setting is safe against a
/// misreported mass, never that safety. Where even the reference fails (it should not), the
/// setting that fails at fewer truths; `lut verify` reports it.
fn hold_margin(
    grid: &Grid,
    p: &GridPoint,
    cfg: &OptimiserConfig,
    optimum: optimise::Optimum,
    span_kg: f64,
) -> Result<optimise::Optimum> {
    let reference = margin::reference_settings()?;
    let set = grid.lighter_set(p, span_kg, margin::DEFAULT_STEP_KG, &reference, cfg)?;
    let before = set.judge(p, &optimum.settings)?;
    if before.ok {
        return Ok(optimum);
    }
    let (robust, sims) = set.robust_optimum(cfg)?;
    let after = set.judge(p, &robust)?;
    let pulse = pulse_at(&grid.ego, &p.query)?;
    let failing = |r: &margin::MarginRow| r.bottoms_out_alone + r.strikes_deeper;
    let settings = if after.ok {
        robust
    } else {
        // Its airbag planned no earlier than the nominal pulse lets the ECU fire one (plan =
        // fire); where the ECU fires none at the nominal truth it is still planned, for a
        // lighter truth the ECU does fire at, as the reference does there.
        let floor_s = cfg.earliest_airbag_s(&pulse);
        let planned_reference = RestraintSettings {
            airbag_time_s: if floor_s.is_finite() {
                reference.airbag_time_s.max(floor_s)
            } else {
                reference.airbag_time_s
            },
            ..reference
        };
        let with_reference = set.judge(p, &planned_reference)?;
        let best = [
            (failing(&before), None),
            (failing(&after), Some(robust)),
            (failing(&with_reference), Some(planned_reference)),
        ]
        .into_iter()
        .min_by_key(|(n, _)| *n)
        .and_then(|(_, s)| s);
        match best {
            Some(s) => s,
            None => {
                return Ok(optimise::Optimum {
                    occupant_simulations: optimum.occupant_simulations + sims,
                    ..optimum
                })
            }
        }
    };
    let case = Case {
        pulse: pulse.ego(),
        occupant: occupant_at(&p.query),
    };
    let (cost, outcomes) = optimise::evaluate(
        &[case],
        &settings,
        &RestraintHardware::default(),
        cfg.reserve_m,
    )?;
    Ok(optimise::Optimum {
        settings,
        cost,
        outcomes,
        occupant_simulations: optimum.occupant_simulations + sims + 1,
    })
}

/// The optimum of one grid point (`q`: closing speed, opponent, belted occupant): what every
/// cell of a build is, and what the studies re-optimise with other spaces and hardware
/// ([`optimise::optimise_situation`] on the point's predicted pulse and occupant).
///
/// # Errors
/// The pulse cannot be predicted or the optimiser fails.
pub fn optimise_query(
    ego: &Ego,
    q: &diagram::Query,
    space: SearchSpace,
    hw: &RestraintHardware,
    cfg: &OptimiserConfig,
) -> Result<optimise::Optimum> {
    optimise::optimise_situation(&pulse_at(ego, q)?, occupant_at(q), space, hw, cfg)
}

/// Optimise cell `index` of the grid (with its per-cell seed).
pub fn optimise_cell(grid: &Grid, index: usize) -> Result<CellResult> {
    let p = grid
        .axes
        .point(index)
        .ok_or_else(|| anyhow!("cell index {index} outside the grid"))?;
    optimise_point(grid, &p, &grid.cell_config(index))
}

/// Statistics of a build.
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildStats {
    /// Cells optimised.
    pub cells: usize,
    /// Occupant simulations run.
    pub occupant_simulations: u64,
    /// Wall-clock time.
    pub wall: Duration,
}

/// Optimise the cells of `range` in parallel (rayon; `threads` = None → all cores), counting
/// each finished cell on `progress`.
pub fn build_cells(
    grid: &Grid,
    range: Range<usize>,
    threads: Option<usize>,
    progress: &Progress,
) -> Result<(Vec<Cell>, BuildStats)> {
    let count = grid.axes.cell_count();
    if range.end > count {
        bail!("range {range:?} exceeds the {count} cells of the grid");
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n);
    }
    let pool = builder
        .build()
        .context("cannot start the rayon thread pool")?;
    let sims = AtomicU64::new(0);
    let start = Instant::now();
    let cells: Result<Vec<Cell>> = pool.install(|| {
        range
            .clone()
            .into_par_iter()
            .map(|i| {
                let r = optimise_cell(grid, i)?;
                sims.fetch_add(r.optimum.occupant_simulations, Ordering::Relaxed);
                progress.inc();
                Ok(r.cell)
            })
            .collect()
    });
    progress.finish();
    let cells = cells?;
    let stats = BuildStats {
        cells: cells.len(),
        occupant_simulations: sims.into_inner(),
        wall: start.elapsed(),
    };
    Ok((cells, stats))
}

/// Build the whole table.
pub fn build_table(
    grid: &Grid,
    threads: Option<usize>,
    quiet: bool,
) -> Result<(Diagram, BuildStats)> {
    let count = grid.axes.cell_count();
    let progress = Progress::new(count, "optimising", "cells", quiet);
    let (cells, stats) = build_cells(grid, 0..count, threads, &progress)?;
    let d = Diagram::from_cells(grid.header(), grid.axes.clone(), cells)
        .map_err(|e| anyhow!("built table is invalid: {e}"))?;
    Ok((d, stats))
}

/// Kind tag of table shard files.
pub const TABLE_SHARD_KIND: &str = "table";

/// What a table shard carries besides its header: the table's header and axes (so that
/// `lut merge` needs no grid file) and the cells of its range in row-major order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TableCells {
    /// Header of the table.
    pub header: Header,
    /// Axes of the table.
    pub axes: Axes,
    /// Cells start..end.
    pub cells: Vec<Cell>,
}

impl Payload for TableCells {
    fn item_count(&self) -> usize {
        self.cells.len()
    }
}

/// A table shard file.
pub type Shard = ShardFile<TableCells>;

/// Identity of a table build: SHA-256 of the header (ego, seed, optimiser effort, physics
/// defaults hash, tool version) and the axes — everything a cell's value depends on.
pub fn table_identity(header: &Header, axes: &Axes) -> Result<String> {
    shard::identity_of(TABLE_SHARD_KIND, &(header, axes))
}

impl Grid {
    /// Identity of this grid's table ([`table_identity`]).
    pub fn identity(&self) -> Result<String> {
        table_identity(&self.header(), &self.axes)
    }
}

/// Build shard `k` of `n`, counting cells on `progress`.
pub fn build_shard(
    grid: &Grid,
    k: usize,
    n: usize,
    threads: Option<usize>,
    progress: &Progress,
) -> Result<(Shard, BuildStats)> {
    let count = grid.axes.cell_count();
    let header = ShardHeader::new(TABLE_SHARD_KIND, &grid.identity()?, k, n, count)?;
    let (cells, stats) = build_cells(grid, header.range(), threads, progress)?;
    let payload = TableCells {
        header: grid.header(),
        axes: grid.axes.clone(),
        cells,
    };
    Ok((ShardFile { header, payload }, stats))
}

/// Read and check one table shard file on its own (see [`crate::shard`]); also that its
/// identity is the hash of the header and axes it carries.
pub fn read_shard(origin: &str, bytes: &[u8]) -> Result<Shard> {
    let s = Shard::from_bytes(origin, TABLE_SHARD_KIND, bytes)?;
    let id = table_identity(&s.payload.header, &s.payload.axes)?;
    if id != s.header.identity {
        bail!("{origin}: corrupt shard file: its header and axes do not hash to its identity");
    }
    if s.header.total as usize != s.payload.axes.cell_count() {
        bail!(
            "{origin}: {} of {} cells, but its axes have {} cells",
            s.header.describe(),
            s.header.total,
            s.payload.axes.cell_count()
        );
    }
    Ok(s)
}

/// Merge shards (any order; each named by its origin, e.g. the file name) into the full
/// table. Refuses shards of another grid (`expected` identity, or the first shard's),
/// overlapping or missing ranges, naming the files.
pub fn merge_shards(shards: &[(String, Shard)], expected: Option<&str>) -> Result<Diagram> {
    let heads: Vec<(&str, &ShardHeader)> = shards
        .iter()
        .map(|(o, s)| (o.as_str(), &s.header))
        .collect();
    shard::check_tiling(&heads, expected)?;
    let first = &shards[0].1.payload;
    let cells = shards.iter().flat_map(|(_, s)| {
        s.payload
            .cells
            .iter()
            .enumerate()
            .map(move |(i, c)| (s.header.start as usize + i, *c))
    });
    Diagram::from_indexed_cells(first.header.clone(), first.axes.clone(), cells)
        .map_err(|e| anyhow!("merge: {e}"))
}

/// Objective value stored in a cell (a_max + a_mean [g]).
pub fn cell_objective_g(c: &Cell) -> f64 {
    f64::from(c.a_max_g) + f64::from(c.a_mean_g)
}

/// `n` distinct cell indices below `count`, drawn with SplitMix64 from `seed` (the same cells
/// for the same seed, on any machine).
pub fn sample_cells(count: usize, n: usize, seed: u64) -> Vec<usize> {
    let mut picks = Vec::new();
    let mut state = seed;
    while picks.len() < n.min(count) {
        state = splitmix64(state);
        let i = (state % count as u64) as usize;
        if !picks.contains(&i) {
            picks.push(i);
        }
    }
    picks
}
