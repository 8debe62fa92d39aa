//! `benches/budgets.toml`: the one file that says what each stage of the ECU cycle may cost.
//!
//! Two kinds of budget, because this machine is a noisy shared 2-vCPU VM:
//! * `[[criterion]]` — wall-clock µs per criterion benchmark id (statistical, can flake);
//! * `[[icount]]` — instructions per iteration under callgrind (deterministic, the hard gate).

use serde::Deserialize;
use std::path::Path;

/// Which criterion estimate is compared with the budget.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Statistic {
    /// Median of the per-iteration sample times (robust to scheduler outliers).
    Median,
    /// Mean (sensitive to outliers; stricter on a noisy VM).
    Mean,
}

/// Point estimate or the upper end of its 95 % bootstrap confidence interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    /// The point estimate.
    Point,
    /// Upper confidence bound: a PASS then means "the budget holds with 97.5 % confidence".
    UpperBound,
}

/// `[gate]` table.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GateConfig {
    /// Estimate used.
    pub statistic: Statistic,
    /// Point or upper CI bound.
    pub compare: Bound,
}

/// One `[[criterion]]` row: a stage, the criterion benchmark that measures it, its budget.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CriterionBudget {
    /// Human name of the stage.
    pub stage: String,
    /// `cargo bench --bench <bench>` target of the cycle-benches package.
    pub bench: String,
    /// Criterion full benchmark id (as in `benchmark.json` `full_id`).
    pub id: String,
    /// Budget, µs per iteration.
    pub budget_us: f64,
    /// Why this budget (printed nowhere; kept next to the number).
    #[serde(default)]
    pub note: String,
}

/// One `[[icount]]` row: an instrumented binary and its instruction budget per iteration.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IcountBudget {
    /// Human name of the path.
    pub stage: String,
    /// Binary of the cycle-benches package (`src/bin/<bin>.rs`), called as `<bin> <iterations>`.
    pub bin: String,
    /// Budget, instructions per iteration.
    pub budget_instructions: f64,
    /// Iteration counts of the two callgrind runs (difference excludes start-up).
    #[serde(default = "default_iterations")]
    pub iterations: [u64; 2],
    /// Instead of two runs: one run of `bin args…` in which callgrind collects only inside
    /// this function (its demangled path); the row measures the most expensive call
    /// (`icount::collected_totals`). For paths whose set-up is not a loop of the same
    /// iteration, e.g. the searched worst-case cycle.
    #[serde(default)]
    pub collect: Option<String>,
    /// Arguments of `bin` for a `collect` row (paths relative to the budgets file's folder).
    #[serde(default)]
    pub args: Vec<String>,
    /// Why this budget.
    #[serde(default)]
    pub note: String,
}

fn default_iterations() -> [u64; 2] {
    [1_000, 3_000]
}

/// The whole file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Budgets {
    /// Which estimate to compare.
    pub gate: GateConfig,
    /// Wall-clock budgets.
    #[serde(default)]
    pub criterion: Vec<CriterionBudget>,
    /// Instruction-count budgets.
    #[serde(default)]
    pub icount: Vec<IcountBudget>,
}

impl Budgets {
    /// Parses budgets from TOML text; rejects unknown keys and non-positive budgets.
    ///
    /// # Errors
    /// Syntax, schema or value errors, with the offending row named.
    pub fn parse(text: &str) -> anyhow::Result<Self> {
        let b: Budgets = toml::from_str(text)?;
        for c in &b.criterion {
            anyhow::ensure!(
                c.budget_us.is_finite() && c.budget_us > 0.0,
                "criterion budget of `{}` must be a positive number of µs",
                c.id
            );
        }
        for i in &b.icount {
            anyhow::ensure!(
                i.budget_instructions.is_finite() && i.budget_instructions > 0.0,
                "icount budget of `{}` must be positive",
                i.bin
            );
            anyhow::ensure!(
                i.iterations[1] > i.iterations[0],
                "icount `{}`: iterations must be [small, large]",
                i.bin
            );
        }
        Ok(b)
    }

    /// The instruction line of the `worst-cycle` row that evaluates the case file `seed` (its
    /// `args` name the file; compared by file name): the one place the searched rows' lines are
    /// written, for `worst-cycle search --budgets`.
    pub fn worst_cycle_line(&self, seed: &Path) -> Option<f64> {
        let name = seed.file_name()?;
        self.icount
            .iter()
            .find(|r| {
                r.bin == "worst-cycle"
                    && r.args
                        .iter()
                        .any(|a| Path::new(a).file_name() == Some(name))
            })
            .map(|r| r.budget_instructions)
    }

    /// Reads and parses a budgets file.
    ///
    /// # Errors
    /// I/O or parse errors, naming the file.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", path.display()))?;
        Self::parse(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_budgets_file_parses_and_has_the_required_limits() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("budgets.toml");
        let b = Budgets::load(&path).unwrap();
        let lut = b
            .criterion
            .iter()
            .find(|c| c.id == "diagram/lookup_varied")
            .unwrap();
        assert!(
            lut.budget_us <= 0.1,
            "the LUT lookup's wall-clock budget: ≤ 0.1 µs"
        );
        let full: Vec<_> = b.criterion.iter().filter(|c| c.bench == "cycle").collect();
        assert!(!full.is_empty(), "the full-cycle bench must be budgeted");
        assert!(
            full.iter().all(|c| c.budget_us <= 10.0),
            "the full cycle's wall-clock budget: ≤ 10 µs"
        );
        assert!(!b.icount.is_empty());
    }

    #[test]
    fn rejects_zero_budget_and_unknown_keys() {
        let base = "[gate]\nstatistic = \"median\"\ncompare = \"upper_bound\"\n";
        let zero =
            format!("{base}[[criterion]]\nstage=\"s\"\nbench=\"b\"\nid=\"i\"\nbudget_us=0.0\n");
        assert!(Budgets::parse(&zero).is_err());
        let typo = format!("{base}[[criterion]]\nstage=\"s\"\nbench=\"b\"\nid=\"i\"\nbudget=1.0\n");
        assert!(Budgets::parse(&typo).is_err());
        assert!(Budgets::parse(base).is_ok());
    }

    #[test]
    fn a_searched_row_s_line_is_found_by_its_seed_file() {
        let b = Budgets::parse(
            "[gate]\nstatistic = \"median\"\ncompare = \"point\"\n\
             [[icount]]\nstage = \"a\"\nbin = \"worst-cycle\"\nbudget_instructions = 9350\n\
             collect = \"f\"\nargs = [\"eval\", \"worst-case/seed.json\"]\n\
             [[icount]]\nstage = \"b\"\nbin = \"worst-cycle\"\nbudget_instructions = 11980\n\
             collect = \"f\"\nargs = [\"eval\", \"worst-case/seed-secoc.json\"]\n",
        )
        .unwrap();
        let line = |p: &str| b.worst_cycle_line(Path::new(p));
        assert_eq!(line("benches/worst-case/seed.json"), Some(9350.0));
        assert_eq!(line("seed-secoc.json"), Some(11980.0));
        assert_eq!(line("benches/worst-case/other.json"), None);
    }
}
