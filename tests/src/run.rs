//! One bench run: the processes of a scenario (candump, stubs, ECU, feeds), started in order,
//! disturbed if the caller asks, stopped, and what they left.

use super::*;
use actuator_stubs::report::Report;
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// What one run needs.
#[derive(Clone, Debug)]
pub struct RunConfig {
    /// Scenario file.
    pub scenario: PathBuf,
    /// Output root (the run writes `out/<scenario name>/`).
    pub out: PathBuf,
    /// CAN interface ("" = no CAN: only the host-timing runs, which have no stubs).
    pub can: String,
    /// Folder with the `ecu`, `sensor-feeds` and `actuator-stubs` binaries.
    pub bin_dir: PathBuf,
    /// iceoryx2 service prefix for this run.
    pub service_prefix: String,
    /// Extra arguments for the ECU.
    pub ecu_args: Vec<String>,
    /// Working directory of the ECU (its config paths `data/default.lut`,
    /// `data/reference-restraint.toml` are relative to the repository root).
    pub ecu_cwd: PathBuf,
    /// Extra arguments for the actuator stubs (see [`default_stubs_args`]).
    pub stubs_args: Vec<String>,
    /// A recorded run (`run.mcap`) the feeds replay instead of playing `scenario`
    /// (`sensor-feeds --replay`); the stubs still judge against `scenario`.
    pub replay: Option<PathBuf>,
}

/// The ECU as it is meant to run: SCHED_FIFO 80 and locked memory. Without the privileges
/// it says so on stderr and in its report (`rt`) and runs on. In the guest (PREEMPT_RT kernel)
/// as on a real bench, this is what keeps a busy neighbour (candump writing a flooded bus to
/// disk) from delaying the cycle.
pub fn default_ecu_args() -> Vec<String> {
    ["--sched-fifo", "80", "--mlockall"]
        .map(str::to_owned)
        .to_vec()
}

/// A fire command may arrive this much after its planned time: crash confirmation needs a few
/// accelerometer samples (≈ 5.5 ms after contact), plus the ECU cycle and the CAN hop.
pub const FIRE_LATE_ALLOWANCE_MS: f64 = 15.0;

/// The stubs' bench arguments: receive until stopped after the ECU, so every command it sent
/// is received and counted. The SecOC windows are the defaults on every route (10 ms pairing,
/// 100 ms freshness): the QEMU guest's real kernel delivers in time (see [`route`]).
pub fn default_stubs_args() -> Vec<String> {
    vec!["--until-signal".to_owned()]
}

/// What a run needs to know to disturb it (fault campaign).
pub struct RunCtx<'a> {
    /// The run's configuration.
    pub cfg: &'a RunConfig,
    /// The scenario being played.
    pub scenario: &'a world::Scenario,
    /// The run's output folder.
    pub dir: PathBuf,
    /// CLOCK_MONOTONIC ns of scenario t = 0 (the feeds' `--epoch-ns`).
    pub epoch_ns: u64,
}

impl RunCtx<'_> {
    /// Path of a bench binary.
    pub fn bin(&self, name: &str) -> PathBuf {
        self.cfg.bin_dir.join(name)
    }

    /// The sensor-feeds command of this run (on the run's epoch, so a restart resumes and
    /// continues the run's feed log).
    pub fn feeds_command(&self) -> Command {
        feeds_command(
            self.cfg,
            Some(self.epoch_ns),
            Some(&self.dir.join(record::FEEDS_LOG)),
        )
    }

    /// Sleeps until scenario time `t_s`.
    pub fn sleep_until_s(&self, t_s: f64) {
        sensor_feeds::sleep_until_ns(self.epoch_ns + (t_s * 1e9) as u64);
    }
}

/// Something done to a run: before it, beside it, or to its sensor feeds. The plain bench run
/// is [`Undisturbed`].
pub trait Disturbance {
    /// Before any bench process starts (e.g. leave a stale iceoryx2 service behind).
    fn prepare(&mut self, _cfg: &RunConfig, _dir: &Path) -> Result<()> {
        Ok(())
    }
    /// Processes started once the feeds have fixed the time base (bus injectors, floods),
    /// stdout piped. After the feeds, the ECU is stopped; then each is given 5 s to end by
    /// itself (or stopped at once if it runs until stopped), then SIGTERM; their stdout is
    /// returned in [`RunResult::disturbance_output`].
    fn start(&mut self, _ctx: &RunCtx) -> Result<Vec<SideProcess>> {
        Ok(Vec::new())
    }
    /// While the feeds play (`feeds` is running); the default waits for them to finish.
    fn feeds_running(
        &mut self,
        _ctx: &RunCtx,
        feeds: &mut Child,
    ) -> Result<std::process::ExitStatus> {
        feeds.wait().context("waiting for sensor-feeds")
    }
}

/// A process a [`Disturbance`] runs beside the bench.
pub struct SideProcess {
    /// Name for messages and [`RunResult::disturbance_output`].
    pub name: String,
    /// The process (stdout piped if its output matters).
    pub child: Child,
    /// Runs until stopped (e.g. `cangen`): SIGTERM as soon as the feeds are done.
    pub until_stopped: bool,
}

/// The plain bench run.
pub struct Undisturbed;

impl Disturbance for Undisturbed {}

/// What one run produced.
#[derive(Debug)]
pub struct RunResult {
    /// Scenario name.
    pub name: String,
    /// Output folder.
    pub dir: PathBuf,
    /// The stubs' report.
    pub report: Report,
    /// The ECU's JSON report (if it wrote one).
    pub ecu_report: Option<serde_json::Value>,
    /// Readable summary (also in summary.txt).
    pub summary: String,
    /// Process problems (non-zero exits), empty when all went well.
    pub problems: Vec<String>,
    /// CLOCK_MONOTONIC ns of scenario t = 0.
    pub epoch_ns: u64,
    /// The scenario file played.
    pub scenario: PathBuf,
    /// What the disturbance processes printed, by name.
    pub disturbance_output: Vec<(String, String)>,
}

fn spawn(cmd: &mut Command, what: &str) -> Result<Child> {
    cmd.spawn()
        .with_context(|| format!("starting {what} ({cmd:?})"))
}

pub(crate) fn terminate(
    child: &mut Child,
    what: &str,
    grace: Duration,
) -> Result<std::process::ExitStatus> {
    if let Ok(Some(st)) = child.try_wait() {
        return Ok(st);
    }
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM);
    if let Some(st) = wait_timeout::ChildExt::wait_timeout(child, grace)? {
        return Ok(st);
    }
    let _ = child.kill();
    let st = child.wait()?;
    eprintln!("hil-bench: {what} did not stop on SIGTERM within {grace:?}; killed");
    Ok(st)
}

/// Forwards a child's piped stderr to ours line by line (and to `log` if given); if `ready`
/// is given, the returned receiver gets a message when a line starting with it was seen.
fn forward_stderr(
    child: &mut Child,
    log: Option<PathBuf>,
    ready: Option<&'static str>,
) -> (
    Option<std::thread::JoinHandle<()>>,
    std::sync::mpsc::Receiver<()>,
) {
    let (tx, rx) = std::sync::mpsc::channel();
    let thread = child.stderr.take().map(|pipe| {
        std::thread::spawn(move || {
            use std::io::{BufRead, Write};
            let mut file = log.and_then(|p| std::fs::File::create(p).ok());
            for line in std::io::BufReader::new(pipe).lines().map_while(Result::ok) {
                eprintln!("{line}");
                if let Some(f) = file.as_mut() {
                    let _ = writeln!(f, "{line}");
                }
                if ready.is_some_and(|r| line.starts_with(r)) {
                    let _ = tx.send(());
                }
            }
        })
    });
    (thread, rx)
}

/// Waits for a child's ready line (see [`forward_stderr`]); an error if it exits first or
/// takes longer than a slow start in an emulated guest on a busy host could explain.
fn wait_ready(ready: std::sync::mpsc::Receiver<()>, child: &mut Child, what: &str) -> Result<()> {
    let until = Instant::now() + Duration::from_secs(30);
    while Instant::now() < until {
        match ready.recv_timeout(Duration::from_millis(20)) {
            Ok(()) => return Ok(()),
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                bail!("{what} exited before it was ready: {}", child.wait()?)
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
        }
        if let Some(st) = child.try_wait()? {
            bail!("{what} exited before it was ready: {st}");
        }
    }
    bail!("{what} did not get ready within 30 s")
}

/// The sensor-feeds command of a run: CAN or `--no-can`, the run's services, the time base
/// (`None`: the feeds choose it and announce it) and the log of what they publish (`--log`).
pub fn feeds_command(cfg: &RunConfig, epoch_ns: Option<u64>, log: Option<&Path>) -> Command {
    let mut c = Command::new(cfg.bin_dir.join("sensor-feeds"));
    match &cfg.replay {
        Some(run) => c.arg("--replay").arg(run),
        None => c.arg("--scenario").arg(&cfg.scenario),
    };
    if cfg.can.is_empty() {
        c.arg("--no-can");
    } else {
        c.args(["--can", &cfg.can]);
    }
    c.args(["--service-prefix", &cfg.service_prefix]);
    if let Some(e) = epoch_ns {
        c.arg("--epoch-ns").arg(e.to_string());
    }
    if let Some(l) = log {
        c.arg("--log").arg(l);
    }
    c
}

/// Reads the feeds' "epoch_ns N" line (their first line on stdout).
pub fn read_epoch(feeds: &mut Child) -> Result<u64> {
    use std::io::BufRead;
    let out = feeds.stdout.take().context("sensor-feeds stdout")?;
    let mut line = String::new();
    std::io::BufReader::new(out)
        .read_line(&mut line)
        .context("reading sensor-feeds' epoch")?;
    line.trim()
        .strip_prefix("epoch_ns ")
        .and_then(|n| n.parse().ok())
        .with_context(|| format!("sensor-feeds did not announce its epoch (got {line:?})"))
}

/// Runs one scenario through the real processes.
pub fn run_scenario(cfg: &RunConfig) -> Result<RunResult> {
    run_disturbed(cfg, &mut Undisturbed)
}

/// Runs one scenario through the real processes, disturbed by `dist`.
pub fn run_disturbed(cfg: &RunConfig, dist: &mut dyn Disturbance) -> Result<RunResult> {
    let run_started = std::time::Instant::now();
    let scenario = world::Scenario::load(&cfg.scenario)?;
    let dir = cfg.out.join(&scenario.name);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    for stale in [
        "report.json",
        "ecu-report.json",
        record::ECU_CONFIG,
        "ecu-stderr.txt",
        "candump.log",
        "commands.jsonl",
        "outcome.png",
        "summary.txt",
        // Appended to by every feeds process of the run (a restart continues it).
        record::FEEDS_LOG,
        record::pending::PENDING,
        actuator_stubs::plot::PLOT_LATER,
        record::RUN_MCAP,
        record::RUN_MF4,
    ] {
        let _ = std::fs::remove_file(dir.join(stale));
    }
    let bin = |name: &str| cfg.bin_dir.join(name);
    for b in ["ecu", "sensor-feeds", "actuator-stubs"] {
        if !bin(b).exists() {
            bail!(
                "{} missing: build with `cargo build --release --workspace --bins`",
                bin(b).display()
            );
        }
    }
    let mut problems = Vec::new();
    // Absolute paths: the ECU runs in the repository root.
    let dir = std::path::absolute(&dir)?;
    dist.prepare(cfg, &dir)?;
    let candump_log = std::fs::File::create(dir.join("candump.log"))?;
    let mut candump = spawn(
        // An 8 MiB receive queue like the stubs': with the default one candump drops frames
        // under the campaign's flood (it recorded ~ 1/4 of them), and its log is what the
        // flood and the recorded fire pair are counted from.
        Command::new("candump")
            // Every frame (`0:0`) and every error class (`#FFFFFFFF`): the controller's error
            // reports are part of the bus's record (run.mf4's CAN_ErrorFrame group).
            .args(["-L", "-r", "8388608", &format!("{},0:0,#FFFFFFFF", cfg.can)])
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit()),
        "candump (install can-utils)",
    )?;
    // candump flushes its output after every frame: written straight to the log, that is one
    // write per frame, and in a guest each is a round trip to the host's shared folder. Copied
    // through a buffer instead (by hand: std::io::copy would splice pipe to file, one write per
    // frame again); the copy ends when candump does and writes the rest.
    let candump_copy = candump.stdout.take().map(|mut from| {
        std::thread::spawn(move || -> std::io::Result<()> {
            use std::io::{Read, Write};
            let mut to = std::io::BufWriter::with_capacity(1 << 16, candump_log);
            let mut chunk = [0u8; 4096];
            loop {
                match from.read(&mut chunk) {
                    Ok(0) => break,
                    Ok(n) => to.write_all(&chunk[..n])?,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => return Err(e),
                }
            }
            to.flush()
        })
    });
    let mut stubs = spawn(
        Command::new(bin("actuator-stubs"))
            .arg("--scenario")
            .arg(&cfg.scenario)
            .args([
                "--can",
                &cfg.can,
                "--service-prefix",
                &cfg.service_prefix,
                "--timeout-s",
            ])
            .arg(format!("{}", scenario.duration_s + 30.0))
            .arg("--out")
            .arg(&dir)
            .args(&cfg.stubs_args)
            // Where the recording is left to the host, so is the outcome picture (0.6–1.0 s of
            // an emulated guest's time, on the run's critical path).
            .args(record::pending::deferred().then_some("--plot-later"))
            .stderr(Stdio::piped()),
        "actuator-stubs",
    )?;
    // The ECU starts only once the stubs listen on the bus: its first commands would otherwise
    // go out before the receiver's socket exists (under load, or in an emulated guest where a
    // process takes up to a second to start, that was several cycles of commands).
    let (stubs_stderr, stubs_ready) =
        forward_stderr(&mut stubs, None, Some(actuator_stubs::READY_PREFIX));
    if let Err(e) = wait_ready(stubs_ready, &mut stubs, "actuator-stubs") {
        let _ = terminate(&mut stubs, "actuator-stubs", Duration::from_secs(2));
        let _ = terminate(&mut candump, "candump", Duration::from_secs(2));
        return Err(e);
    }
    let ecu_log = std::fs::File::create(dir.join("ecu-stdout.txt"))?;
    let mut ecu = spawn(
        Command::new(bin("ecu"))
            .args([
                "--can",
                &cfg.can,
                "--service-prefix",
                &cfg.service_prefix,
                "--quiet",
            ])
            .arg("--node-name")
            .arg(format!("ecu-{}", std::process::id()))
            .arg("--json")
            .arg(dir.join("ecu-report.json"))
            .args(&cfg.ecu_args)
            .current_dir(&cfg.ecu_cwd)
            .stdout(ecu_log)
            .stderr(Stdio::piped()),
        "ecu",
    )?;
    // The ECU's start-up messages (LUT/keys accepted or rejected) go to the console as before
    // and into ecu-stderr.txt, where the fault campaign reads them.
    // The scenario starts once the ECU receives (its ports open, its loop running): the feeds'
    // first samples are not lost, and no fixed wait (400 ms of each run before) is spent.
    let (ecu_stderr, ecu_ready) = forward_stderr(
        &mut ecu,
        Some(dir.join("ecu-stderr.txt")),
        Some(ecu::runtime::app::READY_LINE),
    );
    // An ECU that did not start aborts the run: the scenario played without it would be judged
    // as an ECU that fired nothing ("airbag not fired, WORSE"), with the cause one file away.
    if let Err(e) = wait_ready(ecu_ready, &mut ecu, "ecu") {
        let _ = terminate(&mut ecu, "ecu", Duration::from_secs(2));
        let _ = ecu_stderr.map(std::thread::JoinHandle::join);
        // Killed, not stopped: a stopped judge would write a report of a run that was not made.
        let _ = stubs.kill();
        let _ = stubs.wait();
        let _ = terminate(&mut candump, "candump", Duration::from_secs(2));
        let console = std::fs::read_to_string(dir.join("ecu-stderr.txt")).unwrap_or_default();
        let last = console.lines().last().unwrap_or("nothing on its console");
        bail!("the ECU did not start ({e:#}); its last line: {last}");
    }
    // The feeds fix scenario t = 0 when they are ready and print it ("epoch_ns N").
    let mut feeds = spawn(
        feeds_command(cfg, None, Some(&dir.join(record::FEEDS_LOG))).stdout(Stdio::piped()),
        "sensor-feeds",
    )?;
    let epoch_ns = match read_epoch(&mut feeds) {
        Ok(e) => e,
        Err(e) => {
            let _ = feeds.kill();
            let _ = feeds.wait();
            let _ = terminate(&mut ecu, "ecu", Duration::from_secs(5));
            let _ = terminate(&mut stubs, "actuator-stubs", Duration::from_secs(5));
            let _ = terminate(&mut candump, "candump", Duration::from_secs(2));
            return Err(e);
        }
    };
    let ctx = RunCtx {
        cfg,
        scenario: &scenario,
        dir: dir.clone(),
        epoch_ns,
    };
    let mut side = match dist.start(&ctx) {
        Ok(s) => s,
        Err(e) => {
            problems.push(format!("disturbance: {e:#}"));
            Vec::new()
        }
    };
    match dist.feeds_running(&ctx, &mut feeds) {
        Ok(st) if st.success() => {}
        Ok(st) => problems.push(format!("sensor-feeds: {st}")),
        Err(e) => problems.push(format!("sensor-feeds: {e:#}")),
    }
    // The ECU stops first, then the side processes, then the stubs (which read everything the
    // ECU sent before they judge: --until-signal).
    let st = terminate(&mut ecu, "ecu", Duration::from_secs(5))?;
    if !st.success() {
        problems.push(format!("ecu: {st}"));
    }
    let _ = ecu_stderr.map(std::thread::JoinHandle::join);
    let mut disturbance_output = Vec::new();
    for p in side.iter_mut() {
        let grace = if p.until_stopped {
            Duration::ZERO
        } else {
            Duration::from_secs(5)
        };
        if wait_timeout::ChildExt::wait_timeout(&mut p.child, grace)?.is_none() {
            terminate(&mut p.child, &p.name, Duration::from_secs(2))?;
        }
    }
    for p in side {
        let o = p.child.wait_with_output()?;
        disturbance_output.push((p.name, String::from_utf8_lossy(&o.stdout).into_owned()));
    }
    // The ECU is gone, so everything it sent is queued at the stubs: stop them (with
    // --until-signal they read the queue first and judge).
    let st = terminate(&mut stubs, "actuator-stubs", Duration::from_secs(20))?;
    if !st.success() {
        problems.push(format!("actuator-stubs: {st}"));
    }
    let _ = stubs_stderr.map(std::thread::JoinHandle::join);
    std::thread::sleep(Duration::from_millis(50));
    let _ = terminate(&mut candump, "candump", Duration::from_secs(2))?;
    match candump_copy.map(std::thread::JoinHandle::join) {
        Some(Ok(Ok(_))) => {}
        Some(Ok(Err(e))) => problems.push(format!("candump.log: {e}")),
        Some(Err(_)) => problems.push("candump.log: its copy panicked".to_owned()),
        None => problems.push("candump.log: candump had no output pipe".to_owned()),
    }

    let report_path = dir.join("report.json");
    let report: Report = serde_json::from_str(
        &std::fs::read_to_string(&report_path)
            .with_context(|| format!("reading {}", report_path.display()))?,
    )
    .with_context(|| format!("parsing {}", report_path.display()))?;
    let ecu_report: Option<serde_json::Value> =
        std::fs::read_to_string(dir.join("ecu-report.json"))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok());
    // The configuration the ECU ran with, beside its report (and in the recording's metadata).
    if let Some(text) = ecu_report
        .as_ref()
        .and_then(|e| e.get("config"))
        .and_then(|c| c.as_str())
    {
        let path = dir.join(record::ECU_CONFIG);
        if let Err(e) = std::fs::write(&path, text) {
            problems.push(format!("{}: {e}", path.display()));
        }
    }
    // The run's recording (record crate): everything above on one clock, for Foxglove and
    // any MCAP reader. A run that cannot be recorded is a problem of the run, not lost silently.
    let route = crate::Route::current();
    let meta = record::RunMeta {
        route: route.name().to_owned(),
        timing_emulated: Some(route.timing_emulated()),
        scenario: Some(cfg.scenario.clone()),
        simulated_start_ns: None,
    };
    // The realtime − monotonic offset the recording measured (None: it is written later).
    let mut written_offset: Option<Option<i64>> = None;
    let recording = if record::pending::deferred() {
        // The caller writes it on the host when the guest has ended (record::pending).
        record::pending::defer(&dir, &meta).map(|()| {
            format!(
                "recording: {} to be written on the host after the run ({}=1)",
                dir.join(record::RUN_MCAP).display(),
                record::pending::RECORD_ON_HOST
            )
        })
    } else {
        let recording_started = std::time::Instant::now();
        record::write_run(&dir, &dir.join(record::RUN_MCAP), &meta).map(|s| {
            written_offset = Some(s.realtime_minus_monotonic_ns);
            // Its cost, on the clock the run ran on (the guest's own on an emulated route),
            // against the whole run's (≤ 5 %).
            let recording_s = recording_started.elapsed().as_secs_f64();
            let run_s = run_started.elapsed().as_secs_f64();
            let cost = format!(
                "written in {recording_s:.2} s = {:.1} % of the run's {run_s:.1} s",
                100.0 * recording_s / run_s
            );
            record::pending::summary_line(&dir, &s, &cost)
        })
    };
    let recording = recording
        .map_err(|e| problems.push(format!("recording: {e:#}")))
        .ok();
    // The summary puts the contact on candump's clock with the recording's offset, measured
    // from the run folder only when the recording has not been written yet.
    let clock_offset_ns =
        || written_offset.unwrap_or_else(|| record::run_clock_offset_ns(&dir).ok().flatten());
    let mut summary = summarise(
        &scenario,
        &report,
        ecu_report.as_ref(),
        &dir,
        &clock_offset_ns,
        &problems,
    );
    if let Some(line) = recording {
        let _ = writeln!(summary, "{line}");
    }
    std::fs::write(dir.join("summary.txt"), &summary)?;
    Ok(RunResult {
        name: scenario.name,
        dir,
        report,
        ecu_report,
        summary,
        problems,
        epoch_ns,
        scenario: cfg.scenario.clone(),
        disturbance_output,
    })
}
