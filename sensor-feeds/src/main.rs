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
    #[arg(long)]
    scenario: PathBuf,
    /// CAN interface for the vehicle and occupant frames.
    #[arg(long, default_value = "vcan0", conflicts_with = "no_can")]
    can: String,
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

fn run(cli: &Cli) -> Result<()> {
    let scenario = Scenario::load(&cli.scenario)?;
    if !(cli.speedup.is_finite() && cli.speedup >= 0.1 && cli.speedup <= 100.0) {
        anyhow::bail!("--speedup must be within 0.1..=100");
    }
    let truth =
        Truth::new(&scenario).map_err(|e| anyhow::anyhow!("{}: {e}", cli.scenario.display()))?;
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
        println!("{}: valid", cli.scenario.display());
        return Ok(());
    }
    for l in &lines {
        eprintln!("sensor-feeds: {l}");
    }
    let contact_s = truth.contact_s;
    let closing_at_contact_mps = truth.closing_speed_at_contact_mps();

    let stop = host::install_stop_signals().context("installing signal handler")?;

    let names = ServiceNames::with_prefix(&cli.service_prefix);
    let node_name = format!("sensor-feeds-{}", std::process::id());
    let (node, _) = ipc::create_node(&node_name, false)?;
    let mut objects = ObjectPublisher::new(&node, &names)?;
    let mut accel = AccelPublisher::new(&node, &names)?;
    let mut safing = SafingPublisher::new(&node, &names)?;
    let mut satellite_left = SatelliteLeftPublisher::new(&node, &names)?;
    let mut satellite_right = SatelliteRightPublisher::new(&node, &names)?;
    let mut truth_pub = BenchTruthPublisher::new(&node, &names)?;
    let mut can = if cli.no_can {
        None
    } else {
        Some(
            bus::socket::BusSocket::open(&cli.can, &[]).with_context(|| {
                format!(
                    "CAN interface {} (bring it up with ./vcan-setup.sh, or pass --no-can)",
                    cli.can
                )
            })?,
        )
    };

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
    // Machine-readable time base for orchestrators (the fault campaign starts its injectors
    // and restarts killed feeds on it); everything else goes to stderr.
    {
        use std::io::Write;
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "epoch_ns {start_ns}");
        let _ = out.flush();
    }
    if first_tick > 0 {
        eprintln!(
            "sensor-feeds: resuming at t = {:.3} s (epoch {start_ns} ns)",
            first_tick as f64 * 1e-3
        );
    }
    let mut player = Player::new(truth, start_ns, scale, first_tick);
    let mut out = TickOutput::default();
    let mut counts = Counts::default();
    let mut truth_rec = BenchTruth::EMPTY;
    truth_rec.set_scenario_name(&scenario.name);
    truth_rec.start_ns = start_ns;
    truth_rec.ego_mass_kg = scenario.ego.mass_kg as f32;
    truth_rec.opponent_mass_kg = scenario.opponent_mass_kg() as f32;
    let mut contact_announced = false;
    let mut log = FeedLog::open(cli.log.as_deref())?;

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
            if objects.publish(*o).is_err() {
                counts.ipc_errors += 1;
            } else {
                log.write(FeedItem::Object(*o));
            }
        }
        for b in &out.accel {
            if accel.publish(*b).is_err() {
                counts.ipc_errors += 1;
            } else {
                log.write(FeedItem::CrashAccel(*b));
            }
        }
        for b in &out.safing {
            if safing.publish(*b).is_err() {
                counts.ipc_errors += 1;
            } else {
                log.write(FeedItem::SafingAccel(*b));
            }
        }
        let [left, right] = &out.satellites;
        for b in left {
            if satellite_left.publish(*b).is_err() {
                counts.ipc_errors += 1;
            } else {
                log.write(FeedItem::SatelliteLeft(*b));
            }
        }
        for b in right {
            if satellite_right.publish(*b).is_err() {
                counts.ipc_errors += 1;
            } else {
                log.write(FeedItem::SatelliteRight(*b));
            }
        }
        // Every 10 ms: a feed killed mid-run (the fault campaign does) loses ≤ 10 ms of its log.
        if tick % 10 == 0 {
            log.flush();
        }
        if let Some(sock) = can.as_mut() {
            for f in &out.can {
                match sock.send(f) {
                    Ok(()) => counts.can_frames += 1,
                    Err(_) => counts.can_errors += 1,
                }
            }
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
            truth_rec.sequence += 1;
            truth_rec.timestamp_ns = monotonic_ns();
            if truth_pub.publish(truth_rec).is_err() {
                counts.ipc_errors += 1;
            }
        }
    }
    // Done: the final truth (with `done`), a few times so a busy subscriber cannot miss it.
    truth_rec.done = 1;
    for _ in 0..3 {
        truth_rec.sequence += 1;
        truth_rec.timestamp_ns = monotonic_ns();
        if truth_pub.publish(truth_rec).is_err() {
            counts.ipc_errors += 1;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let p = player.counts();
    eprintln!(
        "sensor-feeds: done: {} objects ({} dropped, {} stale repeats), {} accel samples ({} faulty), {} safing samples ({} faulty), {} satellite frames, {} spikes, {} CAN frames, {} CAN errors, {} IPC errors",
        p.objects, p.objects_dropped, p.objects_frozen, p.accel_samples, p.accel_faulty, p.safing_samples, p.safing_faulty, p.satellite_frames, p.spikes, counts.can_frames, counts.can_errors, counts.ipc_errors
    );
    log.finish();
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
