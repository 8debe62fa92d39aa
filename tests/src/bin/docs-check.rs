//! `docs-check`: runs every command of the repository's Markdown files and compares every
//! printed number with what the command prints now (markers and rules in
//! `e2e_tests::docs`). `./test.sh` runs it; `docs-check --fix` rewrites stale output blocks.
//!
//! Exit 0 when every block holds, 1 naming each one that does not (file:line, command, the
//! first differing line), 2 when the check itself cannot run.

use std::path::PathBuf;
use std::time::Duration;

use clap::Parser;
use e2e_tests::docs::{apply_fixes, markdown_files, Checker};

#[derive(Parser, Debug)]
#[command(
    name = "docs-check",
    version,
    about = "Run every README command; compare every output block with what its command prints"
)]
struct Cli {
    /// Markdown files (default: every *.md of the repository outside target/ and out/).
    files: Vec<PathBuf>,
    /// Rewrite output blocks that differ with what their command prints now.
    #[arg(long)]
    fix: bool,
    /// Repository root (default: the checkout around the current folder, found by walking up).
    #[arg(long)]
    repo: Option<PathBuf>,
    /// Time limit of one command, s.
    #[arg(long, default_value_t = 600, value_name = "S")]
    timeout_s: u64,
    /// Print each command before it runs.
    #[arg(long, short)]
    verbose: bool,
}

fn main() -> std::process::ExitCode {
    host::default_sigpipe();
    host::check_exit_code("docs-check", run(Cli::parse()))
}

fn run(cli: Cli) -> anyhow::Result<bool> {
    let repo = e2e_tests::repo_or_default(cli.repo)?;
    let files = if cli.files.is_empty() {
        markdown_files(&repo)?
    } else {
        cli.files
    };
    let mut checker = Checker::new(&repo, Duration::from_secs(cli.timeout_s));
    let (mut failed, mut fixed) = (0usize, 0usize);
    let t0 = std::time::Instant::now();
    for rel in &files {
        let verbose = cli.verbose;
        let (problems, mut fixes) = checker.check_file(rel, &mut |what: &str| {
            if verbose {
                eprintln!("docs-check: {what}");
            }
        });
        for p in &problems {
            println!("{}: {}", p.at, p.what);
        }
        if cli.fix && !fixes.is_empty() {
            let path = repo.join(rel);
            let text = std::fs::read_to_string(&path)?;
            std::fs::write(&path, apply_fixes(&text, &mut fixes))?;
            fixed += fixes.len();
            failed += problems.len() - fixes.len();
        } else {
            failed += problems.len();
        }
    }
    println!(
        "docs-check: {} files, {failed} problem(s){} in {:.0} s",
        files.len(),
        if fixed > 0 {
            format!(", {fixed} output block(s) rewritten")
        } else {
            String::new()
        },
        t0.elapsed().as_secs_f64()
    );
    Ok(failed == 0)
}
