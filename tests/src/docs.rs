//! The docs check: every command in a README is run, or — where running it
//! takes a bench, root or an hour — its tool and flags are checked against the tool's own
//! `--help`; every number a command prints is the command's output, regenerated and compared,
//! never retyped.
//!
//! A fenced `sh` block says which by the HTML comment on the line before it (invisible on the
//! rendered page):
//!
//! * `<!-- docs: run -->` — each command runs from the repository root (`target/release` and
//!   the cantools venv `target/pyenv/bin` first on `PATH`) and must exit 0;
//! * `<!-- docs: output -->` — the block's one command runs and its stdout must equal the
//!   ```` ```text ```` block right after it (`docs-check --fix` rewrites that block);
//! * `<!-- docs: not run: REASON -->` — each command's program must exist and every `--flag`
//!   must be one its `--help` (or, for a script, its source) knows;
//! * `<!-- docs: synopsis -->` — a usage line: its flags are checked the same way.
//!
//! A command block with no marker is itself a failure: nothing in a README goes unchecked.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use wait_timeout::ChildExt;

/// What the check does with a block.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Marker {
    /// Run every command; each must exit 0.
    Run,
    /// Run the one command; its stdout is the next (text) block.
    Output,
    /// Check programs and flags only, for the reason given.
    NotRun(String),
    /// A usage synopsis: check its flags.
    Synopsis,
}

impl Marker {
    fn parse(line: &str) -> Option<Result<Self, String>> {
        let inner = line
            .trim()
            .strip_prefix("<!--")?
            .strip_suffix("-->")?
            .trim()
            .strip_prefix("docs:")?
            .trim();
        Some(match inner {
            "run" => Ok(Self::Run),
            "output" => Ok(Self::Output),
            "synopsis" => Ok(Self::Synopsis),
            _ => match inner.strip_prefix("not run:") {
                Some(why) if !why.trim().is_empty() => Ok(Self::NotRun(why.trim().to_owned())),
                _ => Err(format!(
                    "unknown docs marker {inner:?} (run, output, synopsis, not run: REASON)"
                )),
            },
        })
    }
}

/// One fenced code block of a Markdown file.
#[derive(Debug, Clone)]
pub struct Block {
    /// 1-based line of the opening fence.
    pub line: usize,
    /// 1-based line of the closing fence.
    pub end_line: usize,
    /// The fence's info string (`sh`, `text`, …).
    pub info: String,
    /// The lines between the fences.
    pub body: Vec<String>,
    /// The docs marker on the line before the fence (blank lines between are allowed).
    pub marker: Option<Result<Marker, String>>,
}

impl Block {
    /// A shell block (the ones that hold commands).
    pub fn is_shell(&self) -> bool {
        matches!(self.info.as_str(), "sh" | "bash" | "console" | "shell")
    }
}

/// Every fenced block of `text`, in order.
pub fn blocks(text: &str) -> Vec<Block> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let Some(info) = lines[i].strip_prefix("```") else {
            i += 1;
            continue;
        };
        let start = i;
        let body_end = (i + 1..lines.len())
            .find(|&j| lines[j].starts_with("```"))
            .unwrap_or(lines.len());
        let marker = lines[..start]
            .iter()
            .rev()
            .find(|l| !l.trim().is_empty())
            .and_then(|l| Marker::parse(l));
        out.push(Block {
            line: start + 1,
            end_line: body_end + 1,
            info: info.trim().to_owned(),
            body: lines[start + 1..body_end.min(lines.len())]
                .iter()
                .map(|l| (*l).to_owned())
                .collect(),
            marker,
        });
        i = body_end + 1;
    }
    out
}

/// The commands of a shell block: continuation lines joined, comments and blank lines dropped.
pub fn commands(body: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    let mut current = String::new();
    for line in body {
        let code = strip_comment(line);
        if let Some(head) = code.trim_end().strip_suffix('\\') {
            current.push_str(head.trim_end());
            current.push(' ');
            continue;
        }
        current.push_str(code.trim());
        let cmd = std::mem::take(&mut current);
        if !cmd.trim().is_empty() {
            out.push(cmd.trim().to_owned());
        }
    }
    if !current.trim().is_empty() {
        out.push(current.trim().to_owned());
    }
    out
}

/// `cmd   # comment` → `cmd`; a `#` inside a word (`030#1122`) or quotes is kept.
fn strip_comment(line: &str) -> &str {
    let mut quote: Option<char> = None;
    let mut prev_space = true;
    for (i, c) in line.char_indices() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None if c == '\'' || c == '"' => quote = Some(c),
            None if c == '#' && prev_space => return &line[..i],
            None => {}
        }
        prev_space = c.is_whitespace();
    }
    line
}

/// Every `--flag` a word names (`[--quick]`, `--out=DIR`, `--can|--no-can` …).
pub fn flags_in(word: &str) -> Vec<String> {
    let mut out = Vec::new();
    let b = word.as_bytes();
    let mut i = 0;
    while i + 2 < b.len() {
        if b[i..].starts_with(b"--")
            && (i == 0 || !b[i - 1].is_ascii_alphanumeric())
            && b.get(i + 2).is_some_and(u8::is_ascii_lowercase)
        {
            let end = (i + 2..b.len())
                .find(|&j| !(b[j].is_ascii_alphanumeric() || b[j] == b'-'))
                .unwrap_or(b.len());
            out.push(word[i..end].trim_end_matches('-').to_owned());
            i = end;
        } else {
            i += 1;
        }
    }
    out
}

/// Shell keywords and builtins a flag check passes over.
const SHELL_WORDS: [&str; 12] = [
    "for", "do", "done", "in", "if", "then", "fi", "while", "echo", "export", "cd", "true",
];

/// How the check runs commands: from the repository root with the bench's tools first on PATH.
pub struct Checker {
    repo: PathBuf,
    path: String,
    timeout: Duration,
    helps: HashMap<(String, String), String>,
}

/// One failure, with where it is.
#[derive(Debug)]
pub struct Problem {
    /// `README.md:97`.
    pub at: String,
    /// What is wrong.
    pub what: String,
}

/// An output block whose text a `--fix` replaces.
#[derive(Debug)]
pub struct Fix {
    /// First and last body line (1-based, inclusive; `last < first` for an empty block).
    pub lines: (usize, usize),
    /// The command's output.
    pub text: String,
}

impl Checker {
    /// A checker for the repository at `repo`; every run is killed after `timeout`.
    pub fn new(repo: &Path, timeout: Duration) -> Self {
        let mut path = format!(
            "{}:{}",
            repo.join("target/release").display(),
            repo.join("target/pyenv/bin").display()
        );
        if let Some(p) = std::env::var_os("PATH") {
            path.push(':');
            path.push_str(&p.to_string_lossy());
        }
        Self {
            repo: repo.to_path_buf(),
            path,
            timeout,
            helps: HashMap::new(),
        }
    }

    /// Runs `cmd` with `sh -c` from the repository root: (exit code, stdout, stderr, seconds).
    pub fn run(&self, cmd: &str) -> Result<(Option<i32>, String, String, f64)> {
        // One folder per run: checkers in several threads of one process (the tests) must not
        // share (or delete) each other's output files.
        static RUNS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("docs-check-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let (out_path, err_path) = (dir.join("stdout"), dir.join("stderr"));
        let t0 = Instant::now();
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(cmd)
            .current_dir(&self.repo)
            .env("PATH", &self.path)
            .stdin(Stdio::null())
            .stdout(std::fs::File::create(&out_path)?)
            .stderr(std::fs::File::create(&err_path)?)
            .spawn()
            .with_context(|| format!("starting sh -c {cmd:?}"))?;
        let status = match child.wait_timeout(self.timeout)? {
            Some(st) => st,
            None => {
                let _ = child.kill();
                let _ = child.wait();
                bail!("did not finish within {} s", self.timeout.as_secs());
            }
        };
        let read =
            |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned();
        let (out, err) = (read(&out_path), read(&err_path));
        let _ = std::fs::remove_dir_all(&dir);
        Ok((status.code(), out, err, t0.elapsed().as_secs_f64()))
    }

    /// `tool [sub] --help` (cached).
    fn help(&mut self, tool: &Path, sub: &str) -> String {
        let key = (tool.display().to_string(), sub.to_owned());
        if let Some(h) = self.helps.get(&key) {
            return h.clone();
        }
        let mut c = Command::new(tool);
        c.args(sub.split_whitespace());
        let h = c
            .arg("--help")
            .output()
            .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
            .unwrap_or_default();
        self.helps.insert(key, h.clone());
        h
    }

    /// The bench tool a program word names (`target/release/lut`, `lut`), if it is one.
    fn tool(&self, program: &str) -> Option<PathBuf> {
        let name = program.strip_prefix("target/release/").unwrap_or(program);
        if name.contains('/') {
            return None;
        }
        let p = self.repo.join("target/release").join(name);
        p.is_file().then_some(p)
    }

    /// A prose code span that is a bench-tool command with flags (`ecu --no-can`,
    /// `target/release/lut plot … --field a_max_g`), not a bare name (`ecu`).
    fn tool_span(&self, span: &str) -> bool {
        let mut words = span.split_whitespace();
        let first = words.next().unwrap_or("");
        self.tool(first).is_some() && span.contains("--")
    }

    /// Problems of one command not run: each program exists, each flag is known.
    pub fn check_flags(&mut self, cmd: &str) -> Vec<String> {
        let Some(words) = shlex::split(cmd) else {
            return vec![format!(
                "cannot split {cmd:?} as sh would (unbalanced quotes)"
            )];
        };
        let mut problems = Vec::new();
        for segment in words.split(|w| matches!(w.as_str(), "|" | "||" | "&&" | ";")) {
            self.check_segment(segment, &mut problems);
        }
        problems
    }

    fn check_segment(&mut self, words: &[String], problems: &mut Vec<String>) {
        // Environment assignments before the program (`ECU_RT__CPU=1 ecu …`).
        let words: Vec<&str> = words
            .iter()
            .map(String::as_str)
            .skip_while(|w| w.contains('=') && !w.starts_with('-'))
            .collect();
        let Some((&program, args)) = words.split_first() else {
            return;
        };
        // A placeholder (`CMD ARGS…`) or a stray option is no program to look for.
        if program.starts_with('-') || program.chars().all(|c| !c.is_ascii_lowercase()) {
            return;
        }
        if SHELL_WORDS.contains(&program) {
            if program == "cd" {
                if let Some(d) = args.first() {
                    if !self.repo.join(d).is_dir() {
                        problems.push(format!("cd {d}: no such folder in the repository"));
                    }
                }
            }
            return;
        }
        // `cargo run … --bin X -- ARGS` is the tool X with ARGS.
        if program == "cargo" && args.first() == Some(&"run") {
            let bin = args
                .iter()
                .position(|w| *w == "--bin")
                .and_then(|i| args.get(i + 1));
            let rest = args
                .iter()
                .position(|w| *w == "--")
                .map_or(&[][..], |i| &args[i + 1..]);
            if let Some(bin) = bin {
                let mut seg = vec![bin.to_string()];
                seg.extend(rest.iter().map(|s| s.to_string()));
                self.check_segment(&seg, problems);
            }
            return;
        }
        if let Some(tool) = self.tool(program) {
            // Flags up to a bare `--` (what follows is another program's).
            let own: Vec<&str> = args.iter().copied().take_while(|w| *w != "--").collect();
            // The subcommand path (`lut study estimation`): words that the help so far lists
            // under `Commands:`.
            let mut sub = String::new();
            let mut help = self.help(&tool, "");
            for w in own
                .iter()
                .filter(|w| !w.starts_with('-') && !w.starts_with('['))
            {
                if !subcommands(&help).iter().any(|s| s == w) {
                    break;
                }
                sub = format!("{sub} {w}").trim().to_owned();
                help = self.help(&tool, &sub);
            }
            for flag in own.iter().flat_map(|w| flags_in(w)) {
                if !flags_in(&help).contains(&flag) {
                    problems.push(format!("{program} {sub}: no flag {flag} (see its --help)"));
                }
            }
            return;
        }
        if program.ends_with(".sh") {
            let script = self.repo.join(program);
            let Ok(source) = std::fs::read_to_string(&script) else {
                problems.push(format!("{program}: no such script"));
                return;
            };
            let own: Vec<&str> = args.iter().copied().take_while(|w| *w != "--").collect();
            for flag in own.iter().flat_map(|w| flags_in(w)) {
                if !flags_in(&source).contains(&flag) {
                    problems.push(format!("{program}: does not take {flag}"));
                }
            }
            // `vcan-setup.sh --run -- CMD …`: CMD is checked too.
            if let Some(i) = args.iter().position(|w| *w == "--") {
                let rest: Vec<String> = args[i + 1..].iter().map(|s| s.to_string()).collect();
                self.check_segment(&rest, problems);
            }
            return;
        }
        let found = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "command -v {}",
                shlex::try_quote(program).unwrap_or_default()
            ))
            .env("PATH", &self.path)
            .stdout(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !found {
            problems.push(format!(
                "{program}: not installed (tests/setup-host.sh should install it)"
            ));
        }
    }

    /// Checks one Markdown file: problems, and the output blocks `--fix` would rewrite.
    pub fn check_file(
        &mut self,
        rel: &Path,
        progress: &mut dyn FnMut(&str),
    ) -> (Vec<Problem>, Vec<Fix>) {
        let mut problems = Vec::new();
        let mut fixes = Vec::new();
        let text = match std::fs::read_to_string(self.repo.join(rel)) {
            Ok(t) => t,
            Err(e) => {
                problems.push(Problem {
                    at: rel.display().to_string(),
                    what: format!("cannot read: {e}"),
                });
                return (problems, fixes);
            }
        };
        // Commands in the prose (`lut plot FILE --field a_max_g …` in a sentence or a table):
        // each code span that starts with a bench tool has its flags checked.
        for (line, span) in inline_commands(&text) {
            if !self.tool_span(&span) {
                continue;
            }
            let cleaned = span.replace("\\|", "|").replace('…', " ");
            let words: Vec<String> = cleaned.split_whitespace().map(str::to_owned).collect();
            let mut problems_here = Vec::new();
            self.check_segment(&words, &mut problems_here);
            for p in problems_here {
                problems.push(Problem {
                    at: format!("{}:{line}", rel.display()),
                    what: format!("`{span}`: {p}"),
                });
            }
        }
        let all = blocks(&text);
        for (k, b) in all.iter().enumerate() {
            let at = format!("{}:{}", rel.display(), b.line);
            let mut fail = |what: String| {
                problems.push(Problem {
                    at: at.clone(),
                    what,
                })
            };
            let marker = match &b.marker {
                Some(Ok(m)) => m.clone(),
                Some(Err(e)) => {
                    fail(e.clone());
                    continue;
                }
                None if b.is_shell() => {
                    fail("a command block without a docs marker (<!-- docs: run | output | synopsis | not run: REASON -->)".into());
                    continue;
                }
                None => continue,
            };
            let cmds = commands(&b.body);
            match marker {
                Marker::Run => {
                    for c in &cmds {
                        progress(&format!("{at}: run {c}"));
                        match self.run(c) {
                            Ok((Some(0), ..)) => {}
                            Ok((code, _, err, _)) => fail(format!(
                                "`{c}` exited {}: {}",
                                code.map_or("on a signal".into(), |c| c.to_string()),
                                last_lines(&err, 3)
                            )),
                            Err(e) => fail(format!("`{c}`: {e:#}")),
                        }
                    }
                }
                Marker::Output => {
                    let (Some(out_block), [c]) = (all.get(k + 1), cmds.as_slice()) else {
                        fail("an output marker needs one command and a text block after it".into());
                        continue;
                    };
                    progress(&format!("{at}: output of {c}"));
                    match self.run(c) {
                        Ok((Some(0), out, _, _)) => {
                            let want = normalise(&out);
                            if normalise(&out_block.body.join("\n")) != want {
                                fail(format!(
                                    "the text block at line {} is not what `{c}` prints now (docs-check --fix rewrites it):\n{}",
                                    out_block.line,
                                    first_difference(&out_block.body.join("\n"), &want)
                                ));
                                fixes.push(Fix {
                                    lines: (out_block.line + 1, out_block.end_line - 1),
                                    text: want,
                                });
                            }
                        }
                        Ok((code, _, err, _)) => {
                            fail(format!("`{c}` exited {code:?}: {}", last_lines(&err, 3)))
                        }
                        Err(e) => fail(format!("`{c}`: {e:#}")),
                    }
                }
                Marker::Synopsis => {
                    // One usage text (continuation lines, `[--a | --b]` alternatives): the
                    // first word is the tool, every flag anywhere must be one of its.
                    let text = b.body.join(" ");
                    let tool = text.split_whitespace().next().unwrap_or("");
                    let flags = flags_in(&text);
                    let mut seg = vec![tool.to_owned()];
                    seg.extend(flags);
                    let mut found = Vec::new();
                    self.check_segment(&seg, &mut found);
                    for p in found {
                        fail(format!("synopsis: {p}"));
                    }
                    if self.tool(tool).is_none() {
                        fail(format!("synopsis of {tool:?}, which is not a bench tool"));
                    }
                }
                Marker::NotRun(_) => {
                    for c in &cmds {
                        for p in self.check_flags(c) {
                            fail(format!("`{c}`: {p}"));
                        }
                    }
                }
            }
        }
        (problems, fixes)
    }
}

/// The code spans of the prose (outside fenced blocks) with their 1-based line.
pub fn inline_commands(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    for (i, line) in text.lines().enumerate() {
        if line.starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let mut parts = line.split('`');
        parts.next();
        while let (Some(code), Some(_)) = (parts.next(), parts.next()) {
            out.push((i + 1, code.to_owned()));
        }
    }
    out
}

/// The subcommands a clap `--help` lists under `Commands:`.
pub fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_owned)
        .collect()
}

/// Lines without trailing blanks, no trailing empty lines.
fn normalise(s: &str) -> String {
    let lines: Vec<&str> = s.lines().map(str::trim_end).collect();
    let n = lines
        .iter()
        .rposition(|l| !l.is_empty())
        .map_or(0, |i| i + 1);
    lines[..n].join("\n")
}

fn first_difference(have: &str, want: &str) -> String {
    let (h, w): (Vec<&str>, Vec<&str>) = (have.lines().collect(), want.lines().collect());
    let i = (0..h.len().max(w.len()))
        .find(|&i| h.get(i).map(|l| l.trim_end()) != w.get(i).map(|l| l.trim_end()))
        .unwrap_or(0);
    format!(
        "  line {} of the block: {:?}\n  the command prints:  {:?}",
        i + 1,
        h.get(i).copied().unwrap_or("(end of block)"),
        w.get(i).copied().unwrap_or("(end of output)")
    )
}

fn last_lines(s: &str, n: usize) -> String {
    let lines: Vec<&str> = s.lines().collect();
    lines[lines.len().saturating_sub(n)..].join(" | ")
}

/// Writes the fixes into `text` (a file's content), bottom up so line numbers hold.
pub fn apply_fixes(text: &str, fixes: &mut [Fix]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    fixes.sort_by_key(|f| std::cmp::Reverse(f.lines.0));
    for f in fixes.iter() {
        let (a, b) = (f.lines.0 - 1, f.lines.1);
        let new: Vec<String> = f.text.lines().map(str::to_owned).collect();
        lines.splice(a..b.max(a), new);
    }
    let mut s = lines.join("\n");
    s.push('\n');
    s
}

/// The Markdown files the check reads: every `*.md` of the repository outside build output.
pub fn markdown_files(repo: &Path) -> Result<Vec<PathBuf>> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
        for e in std::fs::read_dir(dir).with_context(|| dir.display().to_string())? {
            let p = e?.path();
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            if p.is_dir() {
                if !matches!(name, "target" | "out" | ".git" | "corpus" | "artifacts") {
                    walk(root, &p, out)?;
                }
            } else if name.ends_with(".md") {
                out.push(p.strip_prefix(root).unwrap_or(&p).to_path_buf());
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(repo, repo, &mut out)?;
    out.sort();
    Ok(out)
}

/// The `schema_version` docs/using.md, "JSON results", documents for `document` (the first
/// column's text, e.g. "`report.json`"); `None` when the table does not name it.
pub fn documented_schema_version(repo: &Path, document: &str) -> Option<u32> {
    let text = std::fs::read_to_string(repo.join("docs/using.md")).ok()?;
    let table = text
        .split("## JSON results")
        .nth(1)?
        .split("\n## ")
        .next()?;
    table.lines().find_map(|line| {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // | document | written by | schema_version | its fields |
        (cells.len() >= 5 && cells[1].starts_with(document))
            .then(|| cells[3].parse().ok())
            .flatten()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_carry_the_marker_above_them() {
        let md = "text\n<!-- docs: run -->\n\n```sh\na --x   # note\nb \\\n  --y 030#11\n```\n\n```text\nout\n```\n<!-- docs: not run: needs root -->\n```sh\nc\n```\n<!-- docs: bogus -->\n```sh\n```\n";
        let b = blocks(md);
        assert_eq!(b.len(), 4);
        assert_eq!(b[0].marker, Some(Ok(Marker::Run)));
        assert_eq!((b[0].line, b[0].end_line), (4, 8));
        assert_eq!(commands(&b[0].body), ["a --x", "b --y 030#11"]);
        assert_eq!(b[1].marker, None);
        assert_eq!(b[1].info, "text");
        assert_eq!(b[2].marker, Some(Ok(Marker::NotRun("needs root".into()))));
        assert!(matches!(b[3].marker, Some(Err(_))));
    }

    #[test]
    fn flags_are_found_in_synopses_and_help_text() {
        assert_eq!(flags_in("[--quick]"), ["--quick"]);
        assert_eq!(flags_in("--out=DIR"), ["--out"]);
        assert_eq!(flags_in("[--can|--no-can]"), ["--can", "--no-can"]);
        assert_eq!(flags_in("-p"), Vec::<String>::new());
        assert_eq!(flags_in("a--b"), Vec::<String>::new());
        assert_eq!(flags_in("`--sched-fifo`,"), ["--sched-fifo"]);
    }

    #[test]
    fn fixes_replace_only_the_output_block() {
        let md = "a\n```text\nold 1\nold 2\n```\nb\n";
        let mut f = [Fix {
            lines: (3, 4),
            text: "new".into(),
        }];
        assert_eq!(apply_fixes(md, &mut f), "a\n```text\nnew\n```\nb\n");
        let md = "```text\n```\n";
        let mut f = [Fix {
            lines: (2, 1),
            text: "x\ny".into(),
        }];
        assert_eq!(apply_fixes(md, &mut f), "```text\nx\ny\n```\n");
    }
}
