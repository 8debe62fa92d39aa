//! `sensor-feeds --scenario FILE [--can vcan0 | --no-can] [--speedup F]`: plays a scenario in
//! real time on CLOCK_MONOTONIC (see README.md).
//!
//! One 1 ms tick grid (absolute deadlines, no drift): object list over iceoryx2 at the
//! scenario's period, EgoVehicleState (10 ms) and OccupantClassification (100 ms) over CAN with
//! E2E, the compartment (crash) accelerometer, the independent safing accelerometer and the two
//! crush-zone satellites' PSI5 frames in 1 ms
//! batches on their own services (≥ 1 kHz samples; the TRUE crash pulse after contact, plus the
//! scenario's `[[accel_event]]`s), and BenchTruth every 10 ms for the actuator stubs.

use anyhow::{Context, Result};
use clap::Parser;
use ipc::{
    AccelPublisher, BenchTruth, BenchTruthPublisher, ObjectPublisher, SafingPublisher,
    SatelliteLeftPublisher, SatelliteRightPublisher, ServiceNames,
};
use record::read::Item;
use sensor_feeds::player::TICK_NS;
use sensor_feeds::{monotonic_ns, sleep_until_ns, Player, TickOutput};
use signals::{FeedItem, FeedLogRecord};
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use world::scenario::{AccelEvent, AccelEventKind};
use world::{Scenario, Truth};

/// Scenario player: object, vehicle, occupant and crash-accelerometer feeds.
#[derive(Parser, Debug)]
#[command(name = "sensor-feeds", version)]
struct Cli {
    /// Scenario file (TOML, schema in scenarios/README.md).
    #[arg(long, required_unless_present = "replay", conflicts_with = "replay")]
    scenario: Option<PathBuf>,
    /// Play a recorded run instead of a scenario: its `run.mcap`'s object list, both
    /// accelerometers, the satellites and the CAN frames the ECU received, at their recorded
    /// times moved to now (or to `--epoch-ns`), with a bench truth of its scenario's name and
    /// contact for the actuator stubs (README.md, "Replay").
    #[arg(long, value_name = "RUN.mcap", conflicts_with = "check")]
    replay: Option<PathBuf>,
    /// CAN interface for the vehicle and occupant frames (default: $VCAN or vcan0).
    #[arg(long, value_name = "IFACE", conflicts_with = "no_can")]
    can: Option<String>,
    /// Do not send CAN frames (iceoryx2 feeds only).
    #[arg(long)]
    no_can: bool,
    /// Play faster than real time by this factor (function checks only: the ECU then sees
    /// physically inconsistent timing).
    #[arg(long, default_value_t = 1.0)]
    speedup: f64,
    /// iceoryx2 service prefix (must match the ECU's and the stubs').
    #[arg(long, default_value = ipc::DEFAULT_SERVICE_PREFIX)]
    service_prefix: String,
    /// Only validate the scenario and print the true contact; play nothing.
    #[arg(long)]
    check: bool,
    /// CLOCK_MONOTONIC time [ns] of scenario t = 0 (default: now + 1 ms). A feed restarted
    /// after a crash is given the first run's epoch and resumes on the same time base: the
    /// ticks already past are skipped, exactly as if the feed had been silent meanwhile (the
    /// fault campaign kills and restarts the feeds this way).
    #[arg(long, value_name = "NS")]
    epoch_ns: Option<u64>,
    /// Log every published object state and accelerometer batch with its publish time
    /// (CLOCK_MONOTONIC) to FILE, postcard records back to back (`signals::FeedLogRecord`): the
    /// run's recording puts them on `/sensors/...` and measures sample → command latency from
    /// them. Appends, so a restarted feed continues the log of the run.
    #[arg(long, value_name = "FILE")]
    log: Option<PathBuf>,
}

const TRUTH_PERIOD_TICKS: u64 = 10;

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    host::exit_code("sensor-feeds", run(&cli))
}

fn describe(truth: &Truth) -> String {
    let s = truth.scenario();
    match (truth.contact_s, truth.collision) {
        (Some(tc), Some(c)) => format!(
            "scenario {}: true contact at {:.3} s, closing speed {:.1} km/h (ego {:.1}, opponent {:.1}), ego Δv {:.1} km/h, a_max {:.1} g, a_mean {:.1} g",
            s.name,
            tc,
            truth.closing_speed_at_contact_mps() * 3.6,
            truth.ego_speed_at_contact_mps * 3.6,
            truth.opp_speed_at_contact_mps * 3.6,
            c.vehicle.delta_v_mps * 3.6,
            physics::mps2_to_g(c.vehicle.a_max_mps2),
            physics::mps2_to_g(c.vehicle.a_mean_mps2),
        ),
        _ => format!("scenario {}: no contact within {:.2} s", s.name, s.duration_s),
    }
}

/// One line per `[[accel_event]]` (what `--check` and a run announce besides the contact).
fn describe_event(i: usize, e: &AccelEvent) -> String {
    let what = match e.kind {
        AccelEventKind::HalfSine => format!(
            "half_sine {} g × {} ms",
            e.peak_g.unwrap_or(0.0),
            e.duration_ms.unwrap_or(0.0)
        ),
        AccelEventKind::Spike => format!("spike {} g", e.peak_g.unwrap_or(0.0)),
        AccelEventKind::RoughRoad => format!(
            "rough_road {} g rms until {:.3} s",
            e.rms_g.unwrap_or(0.0),
            e.end_s.unwrap_or(0.0)
        ),
        AccelEventKind::Offset => format!(
            "offset {} g until {:.3} s",
            e.peak_g.unwrap_or(0.0),
            e.end_s.unwrap_or(0.0)
        ),
        AccelEventKind::Ringing => format!(
            "ringing ±{} g at {} Hz × {} ms, net Δv {} m/s",
            e.peak_g.unwrap_or(0.0),
            e.frequency_hz.unwrap_or(0.0),
            e.duration_ms.unwrap_or(0.0),
            e.net_dv_mps.unwrap_or(0.0)
        ),
    };
    format!(
        "accel_event[{i}]: {what} from {:.4} s on {}",
        e.start_s,
        e.sensor.name()
    )
}

/// Where the feeds go: the iceoryx2 publishers, the CAN socket and the publish log.
struct Transports {
    objects: ObjectPublisher,
    accel: AccelPublisher,
    safing: SafingPublisher,
    satellite_left: SatelliteLeftPublisher,
    satellite_right: SatelliteRightPublisher,
    truth: BenchTruthPublisher,
    can: Option<bus::socket::BusSocket>,
    log: FeedLog,
    counts: Counts,
    // Last: the publishers above are dropped before their node.
    _node: ipc::IpcNode,
}

impl Transports {
    fn open(cli: &Cli) -> Result<Self> {
        let names = ServiceNames::with_prefix(&cli.service_prefix);
        let node_name = format!("sensor-feeds-{}", std::process::id());
        let (node, _) = ipc::create_node(&node_name, false)?;
        let can = if cli.no_can {
            None
        } else {
            let iface = bus::socket::interface(cli.can.as_deref());
            Some(bus::socket::BusSocket::open(&iface, &[]).with_context(|| {
                format!(
                    "CAN interface {iface} (bring it up with ./vcan-setup.sh, or pass --no-can)"
                )
            })?)
        };
        Ok(Self {
            objects: ObjectPublisher::new(&node, &names)?,
            accel: AccelPublisher::new(&node, &names)?,
            safing: SafingPublisher::new(&node, &names)?,
            satellite_left: SatelliteLeftPublisher::new(&node, &names)?,
            satellite_right: SatelliteRightPublisher::new(&node, &names)?,
            truth: BenchTruthPublisher::new(&node, &names)?,
            can,
            log: FeedLog::open(cli.log.as_deref())?,
            counts: Counts::default(),
            _node: node,
        })
    }

    /// Publishes one feed record and logs it (a failed publish is counted, not logged).
    fn publish(&mut self, item: FeedItem) {
        let sent = match item {
            FeedItem::Object(o) => self.objects.publish(o).is_ok(),
            FeedItem::CrashAccel(b) => self.accel.publish(b).is_ok(),
            FeedItem::SafingAccel(b) => self.safing.publish(b).is_ok(),
            FeedItem::SatelliteLeft(b) => self.satellite_left.publish(b).is_ok(),
            FeedItem::SatelliteRight(b) => self.satellite_right.publish(b).is_ok(),
        };
        if sent {
            self.log.write(item);
        } else {
            self.counts.ipc_errors += 1;
        }
    }

    fn send_can(&mut self, f: &bus::RawFrame) {
        if let Some(sock) = self.can.as_mut() {
            match sock.send(f) {
                Ok(()) => self.counts.can_frames += 1,
                Err(_) => self.counts.can_errors += 1,
            }
        }
    }

    fn publish_truth(&mut self, t: &mut BenchTruth) {
        t.sequence += 1;
        t.timestamp_ns = monotonic_ns();
        if self.truth.publish(*t).is_err() {
            self.counts.ipc_errors += 1;
        }
    }

    /// The final truth (with `done`), a few times so a busy subscriber cannot miss it, then
    /// the publishers stay a moment so subscribers can read the last samples.
    fn finish(&mut self, t: &mut BenchTruth) {
        t.done = 1;
        for _ in 0..3 {
            self.publish_truth(t);
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        self.log.finish();
    }
}

/// Prints the time base for orchestrators on stdout (the fault campaign starts its injectors
/// and restarts killed feeds on it); everything else goes to stderr.
fn announce_epoch(start_ns: u64) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "epoch_ns {start_ns}");
    let _ = out.flush();
}

/// `--replay`: the recorded run's publications at their recorded times, moved to now.
fn replay(cli: &Cli, path: &std::path::Path) -> Result<()> {
    let bytes = std::fs::read(path).with_context(|| format!("--replay {}", path.display()))?;
    let rec =
        record::read::feeds(&bytes).with_context(|| format!("--replay {}", path.display()))?;
    let last_ns = rec.items.last().map_or(rec.start_ns, |(t, _)| *t);
    eprintln!(
        "sensor-feeds: replaying {}: scenario {}, {} messages over {:.3} s, {}",
        path.display(),
        rec.scenario,
        rec.items.len(),
        last_ns.saturating_sub(rec.start_ns) as f64 * 1e-9,
        rec.contact_ns.map_or("no contact".to_owned(), |c| format!(
            "contact at {:.3} s",
            c.saturating_sub(rec.start_ns) as f64 * 1e-9
        ))
    );
    let stop = host::install_stop_signals().context("installing signal handler")?;
    let mut io = Transports::open(cli)?;
    let start_ns = cli.epoch_ns.unwrap_or(monotonic_ns() + TICK_NS);
    let offset_ns = start_ns as i64 - rec.start_ns as i64;
    announce_epoch(start_ns);
    let mut truth = BenchTruth::EMPTY;
    truth.set_scenario_name(&rec.scenario);
    truth.start_ns = start_ns;
    let contact_ns = rec.contact_ns.map(|c| c.saturating_add_signed(offset_ns));
    let mut next_truth_ns = start_ns;
    let mut truth_due = |io: &mut Transports, until_ns: u64, truth: &mut BenchTruth| {
        while next_truth_ns <= until_ns {
            sleep_until_ns(next_truth_ns);
            if let Some(c) = contact_ns.filter(|c| *c <= next_truth_ns) {
                truth.contact_ns = c;
            }
            io.publish_truth(truth);
            next_truth_ns += TRUTH_PERIOD_TICKS * TICK_NS;
        }
    };
    for (t, item) in &rec.items {
        if stop.load(Ordering::Relaxed) {
            eprintln!("sensor-feeds: replay stopped by signal");
            break;
        }
        let at_ns = t.saturating_add_signed(offset_ns);
        truth_due(&mut io, at_ns, &mut truth);
        sleep_until_ns(at_ns);
        match item.shifted(offset_ns) {
            Item::Feed(f) => io.publish(f),
            Item::Can(f) => io.send_can(&f),
        }
    }
    truth_due(
        &mut io,
        last_ns.saturating_add_signed(offset_ns),
        &mut truth,
    );
    if let Some(c) = contact_ns {
        truth.contact_ns = c;
    }
    io.finish(&mut truth);
    eprintln!(
        "sensor-feeds: replay done: {} messages, {} CAN frames, {} CAN errors, {} IPC errors",
        rec.items.len(),
        io.counts.can_frames,
        io.counts.can_errors,
        io.counts.ipc_errors
    );
    std::thread::sleep(std::time::Duration::from_millis(50));
    Ok(())
}

fn run(cli: &Cli) -> Result<()> {
    if let Some(path) = &cli.replay {
        return replay(cli, path);
    }
    let path = cli.scenario.as_ref().context("--scenario or --replay")?;
    let scenario = Scenario::load(path)?;
    if !(cli.speedup.is_finite() && cli.speedup >= 0.1 && cli.speedup <= 100.0) {
        anyhow::bail!("--speedup must be within 0.1..=100");
    }
    let truth = Truth::new(&scenario).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let mut lines = vec![describe(&truth)];
    lines.extend(
        scenario
            .accel_events
            .iter()
            .enumerate()
            .map(|(i, e)| describe_event(i, e)),
    );
    if cli.check {
        // The check's verdict is its output: stdout, with a last line a script can test.
        for l in &lines {
            println!("{l}");
        }
        println!("{}: valid", path.display());
        return Ok(());
    }
    for l in &lines {
        eprintln!("sensor-feeds: {l}");
    }
    let contact_s = truth.contact_s;
    let closing_at_contact_mps = truth.closing_speed_at_contact_mps();

    let stop = host::install_stop_signals().context("installing signal handler")?;

    let mut io = Transports::open(cli)?;

    let scale = 1.0 / cli.speedup;
    let to_ns = |t_s: f64| (t_s * 1e9 * scale).round() as u64;
    let now_ns = monotonic_ns();
    let start_ns = cli.epoch_ns.unwrap_or(now_ns + TICK_NS);
    // Resuming (epoch in the past): start at the first tick not yet due.
    let first_tick = if now_ns > start_ns {
        ((now_ns - start_ns) as f64 / (TICK_NS as f64 * scale)).ceil() as u64
    } else {
        0
    };
    let total_ticks = (scenario.duration_s * 1e3).round() as u64;
    if first_tick > total_ticks {
        anyhow::bail!(
            "--epoch-ns {start_ns} lies {:.3} s in the past: the scenario ({} s) is over",
            (now_ns - start_ns) as f64 * 1e-9,
            scenario.duration_s
        );
    }
    announce_epoch(start_ns);
    if first_tick > 0 {
        eprintln!(
            "sensor-feeds: resuming at t = {:.3} s (epoch {start_ns} ns)",
            first_tick as f64 * 1e-3
        );
    }
    let mut player = Player::new(truth, start_ns, scale, first_tick);
    let mut out = TickOutput::default();
    let mut truth_rec = BenchTruth::EMPTY;
    truth_rec.set_scenario_name(&scenario.name);
    truth_rec.start_ns = start_ns;
    truth_rec.ego_mass_kg = scenario.ego.mass_kg as f32;
    truth_rec.opponent_mass_kg = scenario.opponent_mass_kg() as f32;
    let mut contact_announced = false;

    for tick in first_tick..=total_ticks {
        if stop.load(Ordering::Relaxed) {
            eprintln!("sensor-feeds: stopped by signal at t = {} ms", tick);
            break;
        }
        let t = tick as f64 * 1e-3;
        sleep_until_ns(start_ns + to_ns(t));
        player
            .tick(tick, &mut out)
            .map_err(|e| anyhow::anyhow!("{e:?}"))?;
        for o in &out.objects {
            io.publish(FeedItem::Object(*o));
        }
        for b in &out.accel {
            io.publish(FeedItem::CrashAccel(*b));
        }
        for b in &out.safing {
            io.publish(FeedItem::SafingAccel(*b));
        }
        let [left, right] = &out.satellites;
        for b in left {
            io.publish(FeedItem::SatelliteLeft(*b));
        }
        for b in right {
            io.publish(FeedItem::SatelliteRight(*b));
        }
        // Every 10 ms: a feed killed mid-run (the fault campaign does) loses ≤ 10 ms of its log.
        if tick % 10 == 0 {
            io.log.flush();
        }
        for f in &out.can {
            io.send_can(f);
        }
        // Bench truth.
        let mut announce = false;
        if let Some(tc) = contact_s.filter(|tc| t >= *tc && !contact_announced) {
            contact_announced = true;
            announce = true;
            truth_rec.contact_ns = start_ns + to_ns(tc);
            truth_rec.closing_speed_at_contact_mps = closing_at_contact_mps as f32;
        }
        if announce || tick % TRUTH_PERIOD_TICKS == 0 {
            io.publish_truth(&mut truth_rec);
        }
    }
    io.finish(&mut truth_rec);
    let counts = &io.counts;
    let p = player.counts();
    eprintln!(
        "sensor-feeds: done: {} objects ({} dropped, {} stale repeats), {} accel samples ({} faulty), {} safing samples ({} faulty), {} satellite frames, {} spikes, {} CAN frames, {} CAN errors, {} IPC errors",
        p.objects, p.objects_dropped, p.objects_frozen, p.accel_samples, p.accel_faulty, p.safing_samples, p.safing_faulty, p.satellite_frames, p.spikes, counts.can_frames, counts.can_errors, counts.ipc_errors
    );
    // Keep the publishers alive a moment so subscribers can read the last samples.
    std::thread::sleep(std::time::Duration::from_millis(50));
    Ok(())
}

/// `--log`: what was published, when. Written after each publish (it never delays one); a
/// write error stops the log, is reported once at the end and never stops the play.
struct FeedLog {
    w: Option<std::io::BufWriter<std::fs::File>>,
    error: Option<String>,
    records: u64,
}

impl FeedLog {
    fn open(path: Option<&std::path::Path>) -> Result<Self> {
        let w = match path {
            Some(p) => Some(std::io::BufWriter::with_capacity(
                1 << 16,
                std::fs::OpenOptions::new()
                    .create(true)
                    .append(true)
                    .open(p)
                    .with_context(|| format!("--log {}", p.display()))?,
            )),
            None => None,
        };
        Ok(Self {
            w,
            error: None,
            records: 0,
        })
    }

    fn write(&mut self, item: FeedItem) {
        let Some(w) = self.w.as_mut() else { return };
        let rec = FeedLogRecord {
            published_ns: monotonic_ns(),
            item,
        };
        // Not flushed per record (host::NoFlush): the buffer is flushed every 10 ms.
        match postcard::to_io(&rec, host::NoFlush(&mut *w)) {
            Ok(_) => self.records += 1,
            Err(e) => {
                self.error = Some(e.to_string());
                self.w = None;
            }
        }
    }

    fn flush(&mut self) {
        use std::io::Write;
        if let Some(Err(e)) = self.w.as_mut().map(Write::flush) {
            self.error = Some(e.to_string());
            self.w = None;
        }
    }

    fn finish(&mut self) {
        self.flush();
        self.w = None;
        if let Some(e) = &self.error {
            eprintln!(
                "sensor-feeds: --log incomplete after {} records: {e}",
                self.records
            );
        }
    }
}

/// What the transports did with the player's output.
#[derive(Default)]
struct Counts {
    can_frames: u64,
    can_errors: u64,
    ipc_errors: u64,
}
