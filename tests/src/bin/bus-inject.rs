//! `bus-inject`: a bus attacker / faulty node for the fault campaign.
//!
//! * `bus-inject mirror --mode crc|counter|replay|delay --message EgoVehicleState --epoch-ns N --from-s A --to-s B`
//!   watches a message on the live bus and, for every genuine frame seen inside the window
//!   (scenario seconds on the feeds' time base), puts a faulty frame next to it:
//!   - `crc`: the same payload with the CRC byte inverted (a corrupted frame);
//!   - `counter`: the alive counter advanced by 5 and the CRC recomputed (a node whose counter
//!     jumped: the CRC is right, the sequence is not);
//!   - `replay`: the identical frame again right away (a replay: repeated counter);
//!   - `delay`: the identical frame again `--delay-ms` later (a delayed / stale frame);
//!   - `errors`: an error frame instead of a copy — the controller's report of a transmission
//!     attempt that failed in its CRC sequence (protocol violation, bus error, the receive
//!     error counter), the genuine frame being the retransmission that got through.
//!
//!   It prints one JSON line `{"injected": n, "seen": m, "first_s": a, "last_s": b}` (scenario
//!   times of the first and last injected frame) when the window is over.
//! * `bus-inject forge-fire --counter C [--freshness F]` prints, for `cansend`, an
//!   `AirbagStageCmd` that requests Armed + Fire with a *valid* E2E CRC and alive counter `C`,
//!   followed by an `AirbagStageAuth` with freshness `F` and a MAC the attacker has to guess —
//!   exactly what someone with the public DBC but without the key can put on the bus.
//!
//! * `bus-inject encode MESSAGE SIGNAL=VALUE … [--counter N] [--count K] [--candump]` prints a
//!   frame the ECU accepts — every signal but the E2E ones given (a physical value in the DBC's
//!   unit, or a value name such as `BrakeState=Released`), the alive counter `N` and the CRC
//!   filled in — as a `cansend` argument (`0A0#…`), or `K` consecutive frames (counters
//!   N, N+1, … mod 16) one per line, or as candump `-L` lines (`--candump`, for `canplayer`).
//!
//! E2E positions come from the DBC, through `bus::RawFrame`'s `corrupt_crc`,
//! `set_e2e_counter` and `reseal`: nothing here types a byte position.

use anyhow::{bail, Context, Result};
use bus::RawFrame;
use clap::{Parser, Subcommand, ValueEnum};
use std::collections::VecDeque;
use std::time::Duration;

#[derive(Parser, Debug)]
#[command(
    name = "bus-inject",
    version,
    about = "Bus attacker / faulty node for the fault campaign"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Put a faulty copy next to every genuine frame of one message inside a time window.
    Mirror {
        /// CAN interface.
        #[arg(long, default_value = "vcan0")]
        can: String,
        /// What the copy gets wrong.
        #[arg(long, value_enum)]
        mode: Mode,
        /// The message to mirror: its DBC name (`EgoVehicleState`), or its id (0x0A0 / 160);
        /// it must be E2E protected in the DBC.
        #[arg(long, alias = "id", value_name = "NAME|ID", value_parser = parse_message)]
        message: u32,
        /// CLOCK_MONOTONIC ns of scenario t = 0 (the feeds' --epoch-ns).
        #[arg(long)]
        epoch_ns: u64,
        /// Window start, scenario seconds.
        #[arg(long)]
        from_s: f64,
        /// Window end, scenario seconds.
        #[arg(long)]
        to_s: f64,
        /// Delay of the copies in `delay` mode, ms.
        #[arg(long, default_value_t = 200.0)]
        delay_ms: f64,
    },
    /// Print a frame the ECU accepts: signals from the command line, the E2E counter and CRC
    /// filled in (cansend `ID#HEX`, or candump -L lines with --candump).
    Encode {
        /// The message: its DBC name (`EgoVehicleState`), or its id (0x0A0 / 160).
        #[arg(value_name = "MESSAGE", value_parser = parse_message)]
        message: u32,
        /// `SIGNAL=VALUE` for every signal of the message but `Crc` and `AliveCounter`: a
        /// physical value in the DBC's unit (`EgoSpeed=13.9`) or a value name
        /// (`BrakeState=Released`).
        #[arg(value_name = "SIGNAL=VALUE")]
        signals: Vec<String>,
        /// Alive counter of the (first) frame, 0..=15: one more than the sender's last, for a
        /// stream the receiver already follows.
        #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..=15))]
        counter: u8,
        /// Print this many consecutive frames (the counter advancing mod 16), one per line.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
        count: u32,
        /// Print candump `-L` lines (`(seconds) IFACE ID#HEX`, one per --period-ms) for
        /// `canplayer`, instead of `cansend` arguments.
        #[arg(long)]
        candump: bool,
        /// Interface named in the candump lines.
        #[arg(long, default_value = "vcan0")]
        can: String,
        /// Spacing of the candump lines' time stamps, ms (default: the DBC's cycle time).
        #[arg(long, value_name = "MS")]
        period_ms: Option<f64>,
    },
    /// Print a forged Armed+Fire AirbagStageCmd and a guessed authenticator as `cansend` args.
    ForgeFire {
        /// Alive counter to put in the forged command (0..=15).
        #[arg(long)]
        counter: u8,
        /// Freshness value (low 24 bits) of the forged authenticator.
        #[arg(long, default_value_t = 1)]
        freshness: u32,
        /// The attacker's MAC guess (40 bits).
        #[arg(long, default_value_t = 0x5A5A_5A5A_5A)]
        mac: u64,
    },
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
enum Mode {
    Crc,
    Counter,
    Replay,
    Delay,
    Errors,
}

/// A DBC message name (the bus's one source of truth) or a numeric id, to the message's id.
fn parse_message(s: &str) -> Result<u32, String> {
    if let Some(m) = bus::MESSAGES.iter().find(|m| m.name == s) {
        return Ok(m.id);
    }
    let r = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u32::from_str_radix(h, 16),
        None => s.parse(),
    };
    r.map_err(|_| {
        let names: Vec<&str> = bus::MESSAGES.iter().map(|m| m.name).collect();
        format!(
            "{s:?} is neither a DBC message ({}) nor a CAN id",
            names.join(", ")
        )
    })
}

fn main() -> std::process::ExitCode {
    host::default_sigpipe();
    host::exit_code("bus-inject", run(Cli::parse()))
}

use bus::candump::cansend_arg;

/// What a mirror put on the bus: how many frames, and the scenario times of the first and
/// the last (NaN before the first).
struct Injected {
    count: u64,
    first_s: f64,
    last_s: f64,
}

impl Default for Injected {
    fn default() -> Self {
        Self {
            count: 0,
            first_s: f64::NAN,
            last_s: f64::NAN,
        }
    }
}

impl Injected {
    /// One more frame, sent `since_epoch_ns` after scenario t = 0.
    fn add(&mut self, since_epoch_ns: u64) {
        let t_s = since_epoch_ns as f64 * 1e-9;
        self.count += 1;
        if self.count == 1 {
            self.first_s = t_s;
        }
        self.last_s = t_s;
    }
}

/// The faulty copy of a genuine E2E frame for `mode` (`delay`/`replay`: the frame itself).
fn faulty_copy(mode: Mode, genuine: &RawFrame) -> RawFrame {
    let mut f = *genuine;
    match mode {
        Mode::Crc => {
            f.corrupt_crc();
        }
        Mode::Counter => {
            let c = f.e2e_counter().unwrap_or(0).wrapping_add(5);
            f.set_e2e_counter(c);
        }
        Mode::Replay | Mode::Delay | Mode::Errors => {}
    }
    f
}

/// The controller's report of the `n`-th failed attempt (1, 2, …): a bit error in the CRC
/// sequence, a bus error, and the receive error counter (which the retransmission that got
/// through brings down again, so it stays low; capped below error-passive, 128).
fn crc_error_report(n: u64) -> socketcan::CanError {
    use socketcan::errors::{ErrorCause, Location, ViolationTypes};
    socketcan::CanError::from_multiple(
        ErrorCause::Protocol {
            types: ViolationTypes::BIT,
            location: Location::CrcSequence,
        },
        [
            ErrorCause::BusError,
            ErrorCause::Counters {
                tx: 0,
                rx: n.clamp(1, 127) as u8,
            },
        ],
    )
}

/// A forged Armed+Fire `AirbagStageCmd` with a valid E2E CRC and alive counter `counter`, and
/// an `AirbagStageAuth` carrying `freshness` and the guessed `mac`.
fn forge_fire(counter: u8, freshness: u32, mac: u64) -> Result<(RawFrame, RawFrame)> {
    if counter > 15 || freshness > 0xFF_FFFF || mac >= 1 << 40 {
        bail!("counter 0..=15, freshness < 2^24, mac < 2^40");
    }
    // Crc, AliveCounter, Arm, Fire, CmdSource (adaptive), Stage (both), ForceLevel, FireTime.
    let mut cmd = bus::encode_values(
        bus::AirbagStageCmd::RAW_ID,
        &[0.0, f64::from(counter), 1.0, 1.0, 0.0, 3.0, 6.0, 0.0],
    )
    .map_err(|e| anyhow::anyhow!("encoding the forged command: {e:?}"))?;
    anyhow::ensure!(cmd.reseal(), "AirbagStageCmd has E2E protection in the DBC");
    let auth = bus::encode_values(
        bus::AirbagStageAuth::RAW_ID,
        &[f64::from(freshness), mac as f64],
    )
    .map_err(|e| anyhow::anyhow!("encoding the forged authenticator: {e:?}"))?;
    Ok((cmd, auth))
}

/// The frame of message `id` with `assignments` (`SIGNAL=VALUE`), alive counter `counter` and
/// its CRC (an unprotected message: as given).
fn encode(id: u32, assignments: &[String], counter: u8) -> Result<RawFrame> {
    let info = bus::message_info(id).with_context(|| format!("0x{id:03X} is not in the DBC"))?;
    let sigs = bus::signals_of(id).with_context(|| format!("{} has no signals", info.name))?;
    let e2e = info.e2e_data_id.is_some();
    let computed = |n: &str| e2e && (n == "Crc" || n == "AliveCounter");
    let mut values: Vec<Option<f64>> = vec![None; sigs.len()];
    for a in assignments {
        let (name, value) = a
            .split_once('=')
            .with_context(|| format!("{a:?} is not SIGNAL=VALUE"))?;
        let Some(i) = sigs.iter().position(|s| s.name == name) else {
            let names: Vec<&str> = sigs
                .iter()
                .map(|s| s.name)
                .filter(|n| !computed(n))
                .collect();
            bail!(
                "{} has no signal {name:?} (its signals: {})",
                info.name,
                names.join(", ")
            );
        };
        let s = &sigs[i];
        if computed(s.name) {
            bail!("{} is computed here (the alive counter: --counter)", s.name);
        }
        let v = match s.values.iter().find(|(_, n)| *n == value) {
            Some(&(raw, _)) => raw as f64 * s.factor + s.offset,
            None => value.parse::<f64>().map_err(|_| {
                let names: Vec<&str> = s.values.iter().map(|(_, n)| *n).collect();
                let hint = if names.is_empty() {
                    format!("a number in {} … {} {}", s.min, s.max, s.unit)
                } else {
                    format!("one of {} or its number", names.join(", "))
                };
                anyhow::anyhow!("{}.{}: {value:?} is not {hint}", info.name, s.name)
            })?,
        };
        if values[i].replace(v).is_some() {
            bail!("{}.{} is given twice", info.name, s.name);
        }
    }
    let missing: Vec<&str> = sigs
        .iter()
        .zip(&values)
        .filter(|(s, v)| v.is_none() && !computed(s.name))
        .map(|(s, _)| s.name)
        .collect();
    if !missing.is_empty() {
        bail!("{} needs a value for {}", info.name, missing.join(", "));
    }
    let raw: Vec<f64> = values.iter().map(|v| v.unwrap_or(0.0)).collect();
    let mut f = bus::encode_values(id, &raw).map_err(|e| {
        let s = sigs.iter().find(|s| s.name == e.signal);
        match s {
            Some(s) => anyhow::anyhow!(
                "{}.{} is outside the DBC's {} … {} {}",
                e.message,
                e.signal,
                s.min,
                s.max,
                s.unit
            ),
            None => anyhow::Error::new(e),
        }
    })?;
    if e2e {
        f.set_e2e_counter(counter);
    }
    Ok(f)
}

fn run(cli: Cli) -> Result<()> {
    match cli.cmd {
        Cmd::Encode {
            message,
            signals,
            counter,
            count,
            candump,
            can,
            period_ms,
        } => {
            let period_s = period_ms
                .or_else(|| bus::message_info(message)?.cycle_time_ms.map(f64::from))
                .unwrap_or(10.0)
                * 1e-3;
            if !(period_s.is_finite() && period_s > 0.0) {
                bail!("--period-ms must be positive");
            }
            // The signals are parsed and checked once; each frame of the stream differs only in
            // its alive counter (and so its CRC).
            let mut f = encode(message, &signals, counter)?;
            for k in 0..count {
                f.set_e2e_counter(((u32::from(counter) + k) % 16) as u8);
                if candump {
                    println!("({:.6}) {can} {}", f64::from(k) * period_s, cansend_arg(&f));
                } else {
                    println!("{}", cansend_arg(&f));
                }
            }
            Ok(())
        }
        Cmd::ForgeFire {
            counter,
            freshness,
            mac,
        } => {
            let (cmd, auth) = forge_fire(counter, freshness, mac)?;
            println!("{} {}", cansend_arg(&cmd), cansend_arg(&auth));
            Ok(())
        }
        Cmd::Mirror {
            can,
            mode,
            message: id,
            epoch_ns,
            from_s,
            to_s,
            delay_ms,
        } => {
            if !(from_s.is_finite() && to_s.is_finite() && to_s > from_s && from_s >= 0.0) {
                bail!("window must satisfy 0 <= from_s < to_s");
            }
            anyhow::ensure!(
                bus::message_info(id).is_some_and(|i| i.e2e_data_id.is_some()),
                "0x{id:03X} is not an E2E-protected DBC message"
            );
            let mut sock = bus::socket::BusSocket::open(&can, &[id])
                .with_context(|| format!("opening {can}"))?;
            let at = |s: f64| epoch_ns.saturating_add((s * 1e9) as u64);
            let (start, end) = (at(from_s), at(to_s));
            let delay_ns = (delay_ms * 1e6) as u64;
            let mut queue: VecDeque<(u64, RawFrame)> = VecDeque::new();
            let mut seen = 0u64;
            let mut injected = Injected::default();
            loop {
                let now = sensor_feeds::monotonic_ns();
                while let Some(rx) = sock.recv().context("CAN receive")? {
                    let t = sensor_feeds::monotonic_ns();
                    if rx.frame.id != id || t < start || t >= end {
                        continue;
                    }
                    seen += 1;
                    if mode == Mode::Errors {
                        match sock.send_error(crc_error_report(injected.count + 1)) {
                            Ok(()) => injected.add(t.saturating_sub(epoch_ns)),
                            Err(e) => eprintln!("bus-inject: send error frame: {e}"),
                        }
                        continue;
                    }
                    let due = if mode == Mode::Delay { t + delay_ns } else { t };
                    queue.push_back((due, faulty_copy(mode, &rx.frame)));
                }
                while queue.front().is_some_and(|(due, _)| *due <= now) {
                    if let Some((_, f)) = queue.pop_front() {
                        match sock.send(&f) {
                            Ok(()) => injected.add(now.saturating_sub(epoch_ns)),
                            Err(e) => eprintln!("bus-inject: send: {e}"),
                        }
                    }
                }
                if now >= end && queue.is_empty() {
                    break;
                }
                std::thread::sleep(Duration::from_micros(200));
            }
            let json_s = |t: f64| {
                if t.is_finite() {
                    format!("{t:.4}")
                } else {
                    "null".to_owned()
                }
            };
            println!(
                "{{\"injected\": {}, \"seen\": {seen}, \"first_s\": {}, \"last_s\": {}}}",
                injected.count,
                json_s(injected.first_s),
                json_s(injected.last_s)
            );
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A genuine EgoVehicleState with alive counter 3 and a correct CRC.
    fn genuine() -> RawFrame {
        // Crc, AliveCounter, BrakeState, EgoSpeed, EgoLongAccel.
        let mut f = bus::encode_values(bus::EgoVehicleState::RAW_ID, &[0.0, 3.0, 0.0, 13.0, 0.0])
            .expect("encode");
        assert!(f.reseal());
        f
    }

    #[test]
    fn each_fault_is_rejected_for_its_own_reason() {
        use bus::RejectReason as R;
        let g = genuine();
        for (mode, want) in [
            (Mode::Crc, Some(R::CrcMismatch)),
            (Mode::Counter, Some(R::CounterSkipped)),
            (Mode::Replay, Some(R::CounterRepeated)),
        ] {
            let mut checker = bus::E2eChecker::new();
            checker.check_frame(&g).expect("genuine frame accepted");
            let bad = faulty_copy(mode, &g);
            let got = checker.check_frame(&bad).err().map(|e| e.reason());
            assert_eq!(got, want, "{mode:?}");
        }
    }

    #[test]
    fn messages_are_named_as_in_the_dbc() {
        assert_eq!(parse_message("EgoVehicleState"), Ok(0x0A0));
        assert_eq!(parse_message("0x0A0"), Ok(0x0A0));
        assert_eq!(parse_message("160"), Ok(0x0A0));
        let e = parse_message("EgoVehicle").unwrap_err();
        assert!(e.contains("AirbagStageCmd"), "{e}");
    }

    #[test]
    fn forged_fire_frame_passes_e2e_and_asks_to_fire() {
        let (cmd, auth) = forge_fire(7, 1, 0x12_3456_789A).expect("forge");
        let text = cansend_arg(&cmd);
        let (id, hex) = text.split_once('#').expect("ID#HEX");
        assert_eq!(id, "030");
        let bytes: Vec<u8> = (0..hex.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).expect("hex"))
            .collect();
        assert_eq!(cansend_arg(&auth).split_once('#').map(|p| p.0), Some("031"));
        let mut checker = bus::E2eChecker::new();
        let msg = checker
            .check(bus::AirbagStageCmd::RAW_ID, &bytes)
            .expect("valid E2E");
        match msg {
            bus::Messages::AirbagStageCmd(m) => {
                assert!(
                    matches!(m.arm(), bus::codec::AirbagStageCmdArm::Armed)
                        && matches!(m.fire(), bus::codec::AirbagStageCmdFire::Fire),
                    "{m:?}"
                );
                assert_eq!(m.alive_counter(), 7);
            }
            other => panic!("{other:?}"),
        }
    }
}
