//! The misuse / single-fault / must-fire matrix: seeded variants of
//! misuse events as physics makes them, single sensor faults (alone and inside real events)
//! and crashes across the no-fire and must-fire lines, each a scenario built in code
//! (`e2e_tests::misuse`: the families, their envelopes and their sources) and run through the
//! restraint core under the simulated clock by the offline bench (`e2e_tests::offline::run`:
//! the world's sensor models → `RestraintCycle` → the stubs' module state machines), in
//! parallel. Prints one row per family; exits 1 when a restraint fired where none may, the
//! airbag missed a must-fire crash, or a crash phase that fired nothing never ended. The
//! beyond-physics half-sine sweep is printed and not judged.
//!
//! Required fire time of a must-fire crash: the classic "127 mm − 30 ms" criterion — the instant
//! a free-flying (unbelted) occupant has moved 127 mm relative to the compartment in the TRUE
//! pulse, minus 30 ms.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{Context, Result};
use clap::Parser;
use e2e_tests::misuse::{self, Family, Requirement};
use e2e_tests::offline::{run, run_until_airbag, OfflineConfig};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

/// The misuse / single-fault / must-fire matrix through the ECU core, offline.
#[derive(Parser)]
#[command(name = "misuse-matrix", version)]
struct Cli {
    /// Number of variants (spread evenly over the families).
    #[arg(long, default_value_t = 100_000)]
    variants: usize,
    /// Seed of the variant parameters.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print the families — name, requirement, what each samples — and exit.
    #[arg(long)]
    list: bool,
    /// Only these families (repeatable; `--list` names them).
    #[arg(long = "family")]
    families: Vec<String>,
    /// Repository root (default: the checkout around the current folder, found by walking up).
    #[arg(long)]
    repo: Option<PathBuf>,
    /// Also write the table and every failing variant as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// The table only: no progress bar, no failing scenarios on stderr (their count stays).
    #[arg(long)]
    quiet: bool,
    /// The suite's gate: families that do not hold yet (`e2e_tests::misuse::OPEN`) are
    /// printed and not judged; every other family must show 0.
    #[arg(long)]
    gate: bool,
    /// A TOML file of `[cycle]` keys (as in ecu.toml's `[cycle]`, without the header) that
    /// replace the defaults: for calibrating thresholds on the matrix.
    #[arg(long, value_name = "FILE")]
    cycle_config: Option<PathBuf>,
    /// An ECU config file (`ecu.toml`, as `ecu --config` takes it): its `[cycle]` table's
    /// settings, table and reference restraint, read by the ECU's own reader.
    #[arg(long, value_name = "FILE", conflicts_with = "cycle_config")]
    config: Option<PathBuf>,
    /// Run the matrix as a Slurm job array of N tasks (`sbatch` / `squeue` from PATH, the
    /// caller's `SLURM_CONF` and `SBATCH_*`), wait for it, and print the same table a local run
    /// prints (the variants and their order do not depend on where they ran).
    #[arg(long, value_name = "N")]
    slurm: Option<u32>,
    /// Work directory of a `--slurm` run: the batch script, each task's outcomes and log
    /// (default: `misuse-matrix-slurm/` in the current directory).
    #[arg(long, value_name = "DIR", requires = "slurm")]
    work_dir: Option<PathBuf>,
    /// CPUs per array task of a `--slurm` run.
    #[arg(long, default_value_t = 2, requires = "slurm")]
    cpus_per_task: u32,
    /// Further sbatch options for a `--slurm` run, as given (repeatable, e.g. `--mem=2G`).
    #[arg(
        long = "sbatch-arg",
        value_name = "OPT",
        allow_hyphen_values = true,
        requires = "slurm"
    )]
    sbatch_args: Vec<String>,
    /// Compute only every N-th variant from the K-th on (`K/N`) and write their outcomes to
    /// `--outcomes` instead of a table: one task of a `--slurm` run.
    #[arg(
        long,
        value_name = "K/N",
        requires = "outcomes",
        conflicts_with = "slurm"
    )]
    shard: Option<String>,
    /// Where `--shard` writes its outcomes (JSON).
    #[arg(long, value_name = "FILE", requires = "shard")]
    outcomes: Option<PathBuf>,
}

/// One computed variant as a shard file holds it: family index, variant index, outcome or
/// error text.
#[derive(serde::Serialize, serde::Deserialize)]
struct ShardRow {
    family: usize,
    variant: u64,
    outcome: Option<Outcome>,
    error: Option<String>,
}

/// `K/N` → (K, N) with K < N.
fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let (k, n) = s
        .split_once('/')
        .ok_or_else(|| anyhow::anyhow!("--shard {s:?}: expected K/N"))?;
    let (k, n): (usize, usize) = (k.trim().parse()?, n.trim().parse()?);
    anyhow::ensure!(n > 0 && k < n, "--shard {s}: K must be below N > 0");
    Ok((k, n))
}

/// The arguments that make a task compute the same variants as this run.
fn matrix_args(cli: &Cli, repo: &std::path::Path) -> Result<Vec<String>> {
    let abs = |p: &PathBuf| -> Result<String> {
        Ok(std::fs::canonicalize(p)
            .with_context(|| format!("{}", p.display()))?
            .display()
            .to_string())
    };
    let mut a = vec![
        "--variants".to_string(),
        cli.variants.to_string(),
        "--seed".into(),
        cli.seed.to_string(),
        "--repo".into(),
        abs(&repo.to_path_buf())?,
        "--quiet".into(),
    ];
    for f in &cli.families {
        a.extend(["--family".to_string(), f.clone()]);
    }
    if let Some(c) = &cli.config {
        a.extend(["--config".to_string(), abs(c)?]);
    }
    if let Some(c) = &cli.cycle_config {
        a.extend(["--cycle-config".to_string(), abs(c)?]);
    }
    Ok(a)
}

/// Quoted for the batch script's shell.
fn sh_quote(s: &str) -> String {
    shlex::try_quote(s).map_or_else(|_| format!("'{s}'"), |q| q.into_owned())
}

/// What a `--slurm` work directory computes (`spec.json`): the matrix's own arguments and the
/// number of tasks. Shard files are kept only for the spec they were computed under.
#[derive(serde::Serialize, serde::Deserialize, PartialEq, Debug)]
struct SlurmSpec {
    args: Vec<String>,
    tasks: u32,
}

/// The last submission of a work directory (`state.json`).
#[derive(serde::Serialize, serde::Deserialize, Default)]
struct SlurmState {
    job: Option<String>,
}

/// The outcomes of shard `k`, if its file is there and whole.
fn read_shard(work: &std::path::Path, k: u32) -> Option<Vec<ShardRow>> {
    let text = std::fs::read_to_string(work.join(format!("shard-{k}.json"))).ok()?;
    serde_json::from_str(&text).ok()
}

/// Runs the matrix as a Slurm array of `n` tasks and returns every variant's outcome.
///
/// Running the same command again **resumes**, as `lut build --slurm` does: with the same
/// arguments and N, a job still queued is watched rather than submitted twice, and otherwise
/// only the tasks without a whole shard file are submitted; other arguments start afresh.
fn run_on_slurm(
    cli: &Cli,
    repo: &std::path::Path,
    n: u32,
) -> Result<Vec<(usize, u64, Result<Outcome>)>> {
    anyhow::ensure!(n > 0, "--slurm 0: at least one task");
    let work = cli
        .work_dir
        .clone()
        .unwrap_or_else(|| PathBuf::from("misuse-matrix-slurm"));
    std::fs::create_dir_all(work.join("logs"))
        .with_context(|| format!("creating {}", work.display()))?;
    let work = std::fs::canonicalize(&work)?;
    let spec = SlurmSpec {
        args: matrix_args(cli, repo)?,
        tasks: n,
    };
    let (spec_path, state_path) = (work.join("spec.json"), work.join("state.json"));
    let same_spec = std::fs::read_to_string(&spec_path)
        .ok()
        .and_then(|t| serde_json::from_str::<SlurmSpec>(&t).ok())
        .is_some_and(|old| old == spec);
    if !same_spec {
        for e in std::fs::read_dir(&work)?.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with("shard-") && name.ends_with(".json") {
                std::fs::remove_file(e.path())?;
            }
        }
        let _ = std::fs::remove_file(&state_path);
        std::fs::write(&spec_path, serde_json::to_string_pretty(&spec)?)?;
    }
    let state: SlurmState = std::fs::read_to_string(&state_path)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default();
    let queued = match &state.job {
        Some(id) => !lut::slurm::squeue(std::slice::from_ref(id))?.is_empty(),
        None => false,
    };
    let mut ids = Vec::new();
    if let (true, Some(id)) = (queued, &state.job) {
        eprintln!(
            "misuse-matrix: Slurm job {id} of this work directory is still queued; watching it"
        );
        ids.push(id.clone());
    } else {
        let missing: Vec<u32> = (0..n).filter(|k| read_shard(&work, *k).is_none()).collect();
        if missing.is_empty() {
            eprintln!(
                "misuse-matrix: all {n} tasks already done in {} (same arguments)",
                work.display()
            );
        } else {
            let exe = std::env::current_exe()?;
            let mut line = vec![sh_quote(&exe.display().to_string())];
            line.extend(spec.args.iter().map(|a| sh_quote(a)));
            line.push(format!("--shard \"$SLURM_ARRAY_TASK_ID/{n}\""));
            line.push(format!(
                "--outcomes {}/shard-\"$SLURM_ARRAY_TASK_ID\".json",
                sh_quote(&work.display().to_string())
            ));
            let script = work.join("task.sh");
            std::fs::write(
                &script,
                format!(
                    "#!/bin/bash\n# misuse-matrix --slurm {n}: one array task\nexec {}\n",
                    line.join(" ")
                ),
            )?;
            let list: Vec<String> = missing.iter().map(u32::to_string).collect();
            let id = lut::slurm::sbatch(&lut::slurm::Submit {
                job_name: "misuse-matrix".into(),
                array: Some(list.join(",")),
                cpus_per_task: cli.cpus_per_task,
                output: work.join("logs/shard-%a.log"),
                chdir: work.clone(),
                after_ok: None,
                extra: cli.sbatch_args.clone(),
                script,
            })?;
            std::fs::write(
                &state_path,
                serde_json::to_string(&SlurmState {
                    job: Some(id.clone()),
                })?,
            )?;
            eprintln!(
                "misuse-matrix: Slurm job array {id}, tasks {} of {n} ({} already done), work directory {}",
                list.join(","),
                n as usize - missing.len(),
                work.display()
            );
            ids.push(id);
        }
    }
    let bar = if cli.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(u64::from(n))
    };
    bar.set_style(ProgressStyle::with_template(
        "{bar:40} {pos}/{len} tasks, {elapsed}",
    )?);
    loop {
        let queued = lut::slurm::squeue(&ids)?;
        let done = (0..n).filter(|k| read_shard(&work, *k).is_some()).count();
        bar.set_position(done as u64);
        if queued.is_empty() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(500));
    }
    bar.finish_and_clear();
    let mut results = Vec::new();
    for k in 0..n {
        let rows = read_shard(&work, k).with_context(|| {
            format!(
                "task {k} left no whole outcomes file ({}); its log: {} (run the same command again to resubmit only the missing tasks)",
                work.join(format!("shard-{k}.json")).display(),
                work.join(format!("logs/shard-{k}.log")).display()
            )
        })?;
        results.extend(rows.into_iter().map(|r| {
            let o = match (r.outcome, r.error) {
                (Some(o), _) => Ok(o),
                (None, e) => Err(anyhow::anyhow!(e.unwrap_or_else(|| "no outcome".into()))),
            };
            (r.family, r.variant, o)
        }));
    }
    results.sort_by_key(|r| (r.0, r.1));
    Ok(results)
}

/// One variant's result.
#[derive(serde::Serialize, serde::Deserialize)]
struct Outcome {
    /// Airbag fired (ms rel. contact or since start).
    airbag_ms: Option<f64>,
    /// A pretensioner fire never released (pyrotechnic, or a reversible one kept).
    pretensioner_kept: bool,
    /// Required airbag time of a crash ("127 mm − 30 ms"), ms after contact.
    required_ms: Option<f64>,
    /// The ECU's last mode was CrashDetected at the end of the run, entered at least
    /// [`UNFINISHED_MS`] before it (a crash phase that never ended).
    stuck_in_crash: bool,
    /// Largest crash-minus-safing Δv of a confirmed event, m/s.
    severity_excess_mps: Option<f64>,
    /// The clean twin's (the crash without what the family added) airbag fire − required,
    /// ms; `None` without a twin or when the twin fired no airbag.
    #[serde(default)]
    clean_margin_ms: Option<f64>,
    /// A family judged by outcome: whether the reference restraint's airbag is what keeps the
    /// occupant from bottoming out in the true pulse (`None`: not asked).
    #[serde(default)]
    airbag_needed: Option<bool>,
    /// The occupant bottomed out under what the ECU fired (`None`: no contact).
    #[serde(default)]
    bottomed_out: Option<bool>,
    /// A needed airbag fired by its required time and the occupant still bottomed out:
    /// whether the reference restraint, its airbag fired at the ECU's airbag time, bottoms
    /// out too (`None`: not asked).
    #[serde(default)]
    reference_bottomed_at_fire: Option<bool>,
    /// The occupant bottomed out under the reference restraint in the true pulse (`None`: no
    /// contact).
    #[serde(default)]
    reference_bottomed_out: Option<bool>,
}

/// Families whose crashes the report also weighs by the occupant's outcome against the
/// reference restraint's: every crash in them needs a restraint.
fn judged_by_occupant(req: Requirement) -> bool {
    matches!(req, Requirement::MustFire | Requirement::ByOutcome)
}

/// A crash phase entered less than this before the run's end is unfinished, not stuck, ms: the
/// accelerometer-only decision window (60 ms) and the event's own end after it (a rough road
/// or offset that lasts to within a few ms of the end would otherwise count).
const UNFINISHED_MS: f64 = 150.0;

fn run_variant(cfg: &OfflineConfig, text: &str, req: Requirement) -> Result<Outcome> {
    let mut outcome = run_one(cfg, text)?;
    if let Some(clean) = misuse::clean_twin(text) {
        // Only its airbag time counts: the twin runs up to it.
        let twin = run_until_airbag(&scenario_of(clean)?, cfg)?;
        let airbag_ms = twin.action("airbag_fire").map(|a| a.0);
        outcome.clean_margin_ms = airbag_ms.zip(twin.required_ms).map(|(t, r)| t - r);
    }
    if req == Requirement::ByOutcome {
        // A variant without a collision needs no airbag.
        let case = ReferenceCase::new(cfg, text)?;
        let needed = case
            .as_ref()
            .map_or(Ok(false), ReferenceCase::airbag_needed)?;
        outcome.airbag_needed = Some(needed);
        if let (Some(case), true, Some(true), Some(t), Some(r)) = (
            &case,
            needed,
            outcome.bottomed_out,
            outcome.airbag_ms,
            outcome.required_ms,
        ) {
            if t <= r {
                outcome.reference_bottomed_at_fire = Some(case.bottoms_out_with_airbag_at(t)?);
            }
        }
    }
    Ok(outcome)
}

/// What the judge of a family by outcome simulates: the variant's true pulse, its occupant and
/// the reference restraint. The occupant model and the reference are the actuator stubs'
/// (`actuator_stubs::outcome`), not the ECU's.
struct ReferenceCase {
    truth: world::Truth,
    occupant: physics::OccupantInput,
    reference: physics::RestraintSettings,
}

impl ReferenceCase {
    /// The variant's case (`None`: no collision in its true world).
    fn new(cfg: &OfflineConfig, text: &str) -> Result<Option<Self>> {
        let scenario = scenario_of(text)?;
        let truth = world::Truth::new(&scenario).map_err(anyhow::Error::msg)?;
        if truth.collision.is_none() {
            return Ok(None);
        }
        let occupant = physics::OccupantInput {
            mass_kg: scenario.occupant.mass_kg,
            chest_to_wheel_m: scenario.occupant.chest_to_wheel_mm * 1e-3,
            belted: scenario.occupant.belted,
        };
        Ok(Some(Self {
            truth,
            occupant,
            reference: cfg.reference.settings(),
        }))
    }

    /// Whether the occupant bottoms out under `set` in the true pulse.
    fn bottoms_out(&self, set: &physics::RestraintSettings) -> Result<bool> {
        let judged =
            actuator_stubs::outcome::judge(&self.truth.pulse.ego_pulse(), &self.occupant, set)
                .map_err(anyhow::Error::msg)?;
        Ok(judged.0.bottomed_out)
    }

    /// Whether the reference restraint's airbag is what keeps the occupant from bottoming out:
    /// its belt alone (the airbag never fired) bottoms out, the whole reference restraint (the
    /// airbag at its time) does not.
    fn airbag_needed(&self) -> Result<bool> {
        let belt = physics::RestraintSettings {
            airbag_force_n: 0.0,
            airbag_time_s: actuator_stubs::outcome::NEVER_S,
            ..self.reference
        };
        Ok(self.bottoms_out(&belt)? && !self.bottoms_out(&self.reference)?)
    }

    /// Whether the reference restraint with its airbag fired `airbag_ms` after the true contact
    /// lets the occupant bottom out. The ECU fires on its own cycle, up to one cycle after the
    /// reference's ideal instant: where the reference itself bottoms out when fired then, the
    /// bottoming out is the restraint's margin at that instant, not the ECU's decision.
    fn bottoms_out_with_airbag_at(&self, airbag_ms: f64) -> Result<bool> {
        self.bottoms_out(&physics::RestraintSettings {
            airbag_time_s: airbag_ms * 1e-3,
            ..self.reference
        })
    }
}

/// A variant's scenario text parsed (the text beside the error: it is generated).
fn scenario_of(text: &str) -> Result<world::Scenario> {
    world::Scenario::parse("matrix", text).map_err(|e| anyhow::anyhow!("{e}\n{text}"))
}

fn run_one(cfg: &OfflineConfig, text: &str) -> Result<Outcome> {
    let scenario = scenario_of(text)?;
    let r = run(&scenario, cfg)?;
    let airbag_ms = r.action("airbag_fire").map(|a| a.0);
    let fired = r
        .modules
        .actions
        .iter()
        .filter(|a| a.what == "pretensioner_fire")
        .count();
    let released = r
        .modules
        .actions
        .iter()
        .filter(|a| a.what == "pretensioner_release")
        .count();
    Ok(Outcome {
        airbag_ms,
        pretensioner_kept: fired > released,
        required_ms: r.required_ms,
        stuck_in_crash: r.modes.last().is_some_and(|m| {
            // Modes count from the contact, or from the start without one.
            let end_ms = (scenario.duration_s - r.contact_s.unwrap_or(0.0)) * 1e3;
            m.1 == "CrashDetected" && end_ms - m.0 >= UNFINISHED_MS
        }),
        severity_excess_mps: r.severity_excess_mps,
        clean_margin_ms: None,
        airbag_needed: None,
        reference_bottomed_at_fire: None,
        bottomed_out: r
            .evaluated
            .as_ref()
            .map(|e| e.outcome.adaptive.bottomed_out),
        reference_bottomed_out: r
            .evaluated
            .as_ref()
            .map(|e| e.outcome.reference.bottomed_out),
    })
}

/// `--list`: every family with its requirement and what it samples.
fn list() {
    let width = misuse::FAMILIES
        .iter()
        .map(|f| f.name.len())
        .max()
        .unwrap_or(0);
    println!("{:<width$}  {:<11}  what its variants sample (× 1.5 = the matrix's margin over each physical bound)", "family", "requirement");
    for f in misuse::FAMILIES {
        println!(
            "{:<width$}  {:<11}  {}",
            f.name,
            f.requirement.label(),
            f.envelope
        );
    }
    println!("requirements: no fire = no airbag and no pyrotechnic pretensioner (a reversible pre-crash one must be released), and a crash phase that fired nothing ends; no airbag = the belt may act; must fire = the airbag fires, its time against \"127 mm − 30 ms\" reported; by outcome = where the reference restraint's airbag is what keeps the occupant from bottoming out, what the ECU fired must keep it from bottoming out too; report only = printed, not judged");
}

/// Errors as one line (`misuse-matrix: error: …`), never a Debug dump with a backtrace.
fn main() -> std::process::ExitCode {
    host::default_sigpipe();
    host::exit_code("misuse-matrix", run_matrix())
}

fn run_matrix() -> Result<()> {
    let cli = Cli::parse();
    if cli.list {
        list();
        return Ok(());
    }
    let repo = e2e_tests::repo_or_default(cli.repo.clone())?;
    // Every output path is checked before the run, not at its end.
    for (flag, path) in [("--json", &cli.json), ("--outcomes", &cli.outcomes)] {
        if let Some(p) = path {
            host::check_output_file(p).with_context(|| format!("{flag} {}", p.display()))?;
        }
    }
    // `--config` and `--cycle-config` exclude each other (clap).
    let cfg = OfflineConfig::from_flags(&repo, cli.config.as_deref(), cli.cycle_config.as_deref())?;
    for f in &cli.families {
        anyhow::ensure!(
            misuse::family(f).is_some(),
            "no family {f:?}; the families: {}",
            misuse::names().join(", ")
        );
    }
    let families: Vec<&Family> = misuse::FAMILIES
        .iter()
        .filter(|f| cli.families.is_empty() || cli.families.iter().any(|x| x == f.name))
        .collect();
    let per = cli.variants.div_ceil(families.len()) as u64;
    let jobs: Vec<(usize, u64)> = (0..families.len())
        .flat_map(|f| (0..per).map(move |i| (f, i)))
        .collect();
    let shard = cli.shard.as_deref().map(parse_shard).transpose()?;
    let jobs: Vec<(usize, u64)> = match shard {
        Some((k, n)) => jobs.into_iter().skip(k).step_by(n).collect(),
        None => jobs,
    };
    if let Some(threads) = lut::slurm::cpus_per_task() {
        // Inside a Slurm task: the CPUs it was given, not every core of the node.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global();
    }
    let start = std::time::Instant::now();
    let results: Vec<(usize, u64, Result<Outcome>)> = match cli.slurm {
        Some(n) => run_on_slurm(&cli, &repo, n)?,
        None => {
            let bar = if cli.quiet {
                ProgressBar::hidden()
            } else {
                ProgressBar::new(jobs.len() as u64)
            };
            bar.set_style(ProgressStyle::with_template(
                "{bar:40} {pos}/{len} variants, {elapsed} ({eta} left)",
            )?);
            let done = AtomicU64::new(0);
            let r = jobs
                .par_iter()
                .map(|&(f, i)| {
                    let text = families[f].variant(i, cli.seed);
                    let o = run_variant(&cfg, &text, families[f].requirement);
                    if done.fetch_add(1, Ordering::Relaxed).is_multiple_of(256) {
                        bar.set_position(done.load(Ordering::Relaxed));
                    }
                    (f, i, o)
                })
                .collect();
            bar.finish_and_clear();
            r
        }
    };
    if let (Some(_), Some(path)) = (shard, &cli.outcomes) {
        let rows: Vec<ShardRow> = results
            .into_iter()
            .map(|(family, variant, o)| {
                let (outcome, error) = match o {
                    Ok(o) => (Some(o), None),
                    Err(e) => (None, Some(format!("{e:#}"))),
                };
                ShardRow {
                    family,
                    variant,
                    outcome,
                    error,
                }
            })
            .collect();
        // Written whole, then renamed: a task that dies leaves no half file.
        let tmp = path.with_extension("json.tmp");
        std::fs::write(&tmp, serde_json::to_string(&rows)?)
            .with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, path)?;
        return Ok(());
    }
    let mut out = String::new();
    let mut failures = Vec::new();
    writeln!(
        out,
        "{:<34} {:>8} {:>8} {:>8} {:>8} {:>6} {:>6} {:>6} {:>6}  fire − required (127 mm − 30 ms), ms: p50 / worst [worst − clean twin's]",
        "family", "variants", "airbag!", "pretens!", "missed", "late", "after", "stuck", "errors"
    )?;
    let mut json_rows = Vec::new();
    // Two healthy sensors on real crashes: the must-fire families' largest crash − safing Δv.
    let mut healthy_excess = f64::NEG_INFINITY;
    // Per must-fire family: occupants bottomed out where the reference restraint's would not
    // (a report: the fire time is the family's requirement, this is what it costs).
    let mut worse_than_reference = Vec::new();
    for (f, family) in families.iter().enumerate() {
        let (name, req) = (family.name, family.requirement);
        let open = cli.gate && misuse::OPEN.contains(&name);
        // Gated on "127 mm − 30 ms" as well (`misuse::IN_TIME`).
        let in_time = cli.gate && !open && misuse::IN_TIME.contains(&name);
        let rows: Vec<_> = results.iter().filter(|r| r.0 == f).collect();
        let (mut bad_bag, mut bad_pt, mut missed, mut errors, mut stuck) = (0, 0, 0, 0, 0);
        // Judged by outcome: variants whose airbag is needed, and airbags fired in the others.
        let (mut needed, mut fired_unneeded) = (0, 0);
        // Of those, airbags fired in time whose occupant the reference bottoms out as well
        // when fired at the ECU's instant (the cycle's grid against the ideal one).
        let mut at_margin = 0;
        let mut margins = Vec::new();
        // Fire − required less the clean twin's, where the family has twins.
        let (mut late, mut vs_clean) = (0, f64::NEG_INFINITY);
        // Airbags after their required time.
        let mut after = 0;
        // Occupants bottomed out where the reference restraint's would not.
        let mut bottomed_vs_reference = 0;
        for (_, i, o) in &rows {
            let o = match o {
                Ok(o) => o,
                Err(e) => {
                    errors += 1;
                    failures.push(format!("{name} #{i}: error: {e:#}"));
                    continue;
                }
            };
            // An open family's fires are counted and printed, not judged (`--gate`); its
            // errors are (a variant that does not build is the generator's bug).
            let mut fail = |what: &str| {
                if open {
                    return;
                }
                failures.push(format!(
                    "{name} #{i} (seed {}): {what}\n{}",
                    cli.seed,
                    family.variant(*i, cli.seed)
                ))
            };
            if req == Requirement::MustFire && !misuse::FAULTY_SENSOR_FAMILIES.contains(&name) {
                if let Some(x) = o.severity_excess_mps {
                    healthy_excess = healthy_excess.max(x);
                }
            }
            if judged_by_occupant(req)
                && o.bottomed_out == Some(true)
                && o.reference_bottomed_out == Some(false)
            {
                bottomed_vs_reference += 1;
            }
            match req {
                Requirement::NoFire => {
                    if let Some(t) = o.airbag_ms {
                        bad_bag += 1;
                        fail(&format!("airbag fired at {t:.1} ms"));
                    }
                    if o.pretensioner_kept {
                        bad_pt += 1;
                        fail("pretensioner fired and not released");
                    }
                    if o.stuck_in_crash && o.airbag_ms.is_none() && !o.pretensioner_kept {
                        stuck += 1;
                        fail(
                            "stuck in CrashDetected: a crash phase that fired nothing never ended",
                        );
                    }
                }
                Requirement::Report => {
                    bad_bag += usize::from(o.airbag_ms.is_some());
                    bad_pt += usize::from(o.pretensioner_kept);
                }
                Requirement::NoAirbag => {
                    if let Some(t) = o.airbag_ms {
                        bad_bag += 1;
                        fail(&format!("airbag fired at {t:.1} ms below the no-fire line"));
                    }
                }
                Requirement::MustFire => match (o.airbag_ms, o.required_ms) {
                    (Some(t), Some(req)) => {
                        margins.push(t - req);
                        if t > req {
                            after += 1;
                            if in_time {
                                fail(&format!(
                                    "airbag {:+.1} ms after its required time (127 mm − 30 ms, {req:+.1} ms)",
                                    t - req
                                ));
                            }
                        }
                        if let Some(clean) = o.clean_margin_ms {
                            let d = t - req - clean;
                            vs_clean = vs_clean.max(d);
                            if d > misuse::LATE_VS_CLEAN_MS + 1e-3 {
                                late += 1;
                                fail(&format!(
                                    "airbag {d:+.1} ms later than the clean crash's (bound +{:.0} ms)",
                                    misuse::LATE_VS_CLEAN_MS
                                ));
                            }
                        }
                    }
                    (Some(_), None) => {}
                    (None, _) => {
                        missed += 1;
                        fail("must-fire crash: no airbag");
                    }
                },
                Requirement::ByOutcome => {
                    if o.airbag_needed != Some(true) {
                        fired_unneeded += usize::from(o.airbag_ms.is_some());
                        continue;
                    }
                    needed += 1;
                    if let (Some(t), Some(req)) = (o.airbag_ms, o.required_ms) {
                        margins.push(t - req);
                        after += usize::from(t > req);
                    }
                    if o.bottomed_out == Some(true) && o.reference_bottomed_at_fire == Some(true) {
                        at_margin += 1;
                    } else if o.bottomed_out == Some(true) {
                        missed += 1;
                        fail(&match o.airbag_ms {
                            None => "the reference airbag keeps this occupant from bottoming out; no airbag, bottomed out".to_owned(),
                            Some(t) => match o.required_ms {
                                Some(r) if t > r => format!("the reference airbag keeps this occupant from bottoming out; airbag at {t:+.1} ms, after its required {r:+.1} ms, bottomed out"),
                                _ => format!("the reference airbag keeps this occupant from bottoming out; airbag at {t:+.1} ms, bottomed out where the reference restraint fired then does not"),
                            },
                        });
                    }
                }
            }
        }
        margins.sort_by(f64::total_cmp);
        let timing = if req == Requirement::ByOutcome {
            let m = if margins.is_empty() {
                "—".to_owned()
            } else {
                format!(
                    "{:+.1} / {:+.1}",
                    margins[margins.len() / 2],
                    margins[margins.len() - 1]
                )
            };
            format!("{m} (airbag needed in {needed}, {at_margin} of them fired in time and bottomed out as the reference fired then does; fired in {fired_unneeded} of the others)")
        } else if margins.is_empty() {
            "—".to_owned()
        } else {
            format!(
                "{:+.1} / {:+.1}{}",
                margins[margins.len() / 2],
                margins[margins.len() - 1],
                if vs_clean.is_finite() {
                    format!(" [{vs_clean:+.1}]")
                } else {
                    String::new()
                }
            )
        };
        if req == Requirement::Report {
            writeln!(
                out,
                "{:<34} {:>8} {:>8} {:>8} {:>8} {:>6} {:>6} {:>6} {:>6}  (report, not judged: airbag / pretensioner fires)",
                name,
                rows.len(),
                bad_bag,
                bad_pt,
                "—",
                "—",
                "—",
                "—",
                errors
            )?;
        } else {
            writeln!(
                out,
                "{:<34} {:>8} {:>8} {:>8} {:>8} {:>6} {:>6} {:>6} {:>6}  {timing}{}",
                name,
                rows.len(),
                bad_bag,
                bad_pt,
                missed,
                late,
                after,
                stuck,
                errors,
                if open {
                    "  (open: not gated yet)"
                } else if in_time {
                    "  (in time: gated)"
                } else {
                    ""
                }
            )?;
        }
        json_rows.push(serde_json::json!({
            "family": name, "variants": rows.len(), "airbag_where_none_may": bad_bag,
            "pretensioner_where_none_may": bad_pt, "must_fire_missed": missed, "errors": errors,
            "stuck_in_crash": stuck, "judged": req != Requirement::Report && !open,
            "later_than_clean_twin": late, "after_required": after,
            "gated_in_time": in_time,
            "worst_minus_clean_twin_ms": vs_clean.is_finite().then_some(vs_clean),
            "fire_minus_required_ms_p50": margins.get(margins.len() / 2),
            "fire_minus_required_ms_worst": margins.last(),
            "airbag_needed": (req == Requirement::ByOutcome).then_some(needed),
            "airbag_fired_where_not_needed": (req == Requirement::ByOutcome).then_some(fired_unneeded),
            "bottomed_out_as_reference_at_fire": (req == Requirement::ByOutcome).then_some(at_margin),
            "bottomed_out_where_reference_does_not": judged_by_occupant(req).then_some(bottomed_vs_reference),
        }));
        if bottomed_vs_reference > 0 {
            worse_than_reference.push(format!("{name} {bottomed_vs_reference} of {}", rows.len()));
        }
    }
    if !worse_than_reference.is_empty() {
        writeln!(
            out,
            "occupant bottomed out where the reference restraint's does not (a report, not judged): {}",
            worse_than_reference.join(", ")
        )?;
    }
    if healthy_excess.is_finite() {
        let c = &cfg.cycle;
        writeln!(
            out,
            "severity agreement: two healthy sensors in the must-fire crashes differ by at most {healthy_excess:+.3} m/s (crash − safing Δv); a crash sensor beyond {:.2} m/s + {:.0} % of its Δv is implausible",
            c.severity_tolerance_dv_mps,
            c.severity_tolerance_fraction * 100.0
        )?;
    }
    writeln!(out, "{} variants in {:.1} s (seed {}); airbag! / pretens! = fired where none may (must be 0), missed = must-fire crashes without airbag (must be 0), late = must-fire airbags over {:.0} ms later than their clean twin's (must be 0), after = must-fire airbags after their \"127 mm − 30 ms\" time (must be 0 where gated in time), stuck = crash phases that fired nothing and never ended (must be 0)",
        results.len(), start.elapsed().as_secs_f64(), cli.seed, misuse::LATE_VS_CLEAN_MS)?;
    // `--json -` keeps stdout for the JSON: the table goes to stderr then.
    if cli.json.as_deref().is_some_and(host::results::is_stdout) {
        eprint!("{out}");
    } else {
        print!("{out}");
    }
    if let Some(path) = &cli.json {
        host::results::write_json(
            path,
            &serde_json::to_string_pretty(&serde_json::json!({
                "schema_version": misuse::SCHEMA_VERSION,
                "seed": cli.seed, "families": json_rows, "failures": failures,
            }))?,
        )
        .with_context(|| format!("--json {}", path.display()))?;
    }
    if !failures.is_empty() {
        // --quiet: the table and this count only; every failing variant's scenario is in
        // --json. Otherwise the first 20 in full.
        if !cli.quiet {
            for f in failures.iter().take(20) {
                eprintln!("misuse-matrix: FAIL {f}");
            }
        }
        eprintln!(
            "misuse-matrix: {} failing variants{}",
            failures.len(),
            if cli.json.is_some() {
                ""
            } else {
                " (--json FILE writes each one's scenario)"
            }
        );
        std::process::exit(1);
    }
    Ok(())
}
