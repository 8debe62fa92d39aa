//! Recordings of bench runs in the formats of the field's measurement tools: one MCAP file per
//! run (`run.mcap`, for Foxglove and every MCAP reader), written from what the run left in its
//! folder.
//!
//! | topic | from | one message per |
//! |---|---|---|
//! | `/can/raw` | `candump.log` | frame: id, extended, dlc, data bytes, interface, DBC name |
//! | `/can/<DBC message>` | `candump.log` + `bus/restraint.dbc` | frame of that id: every signal's physical value |
//! | `/stubs/commands` | `commands.jsonl` | frame the actuator stubs received, with its E2E / SecOC verdict |
//! | `/stubs/actions` | `report.json` | action of a module (airbag fire, pretensioner fire / release …) |
//! | `/stubs/verdict` | `report.json` | run: the occupant outcome, the modes, the required fire time and the airbag's margin |
//! | `/ecu/diagnostics`, `/ecu/predicted_pulse` | `diagnostics.postcard` (the stubs' log) | cycle; change of the prediction |
//! | `/ecu/log` (`foxglove.Log`) | `diagnostics.postcard` | change of mode or degraded reasons |
//! | `/sensors/object`, `/sensors/crash_accel`, `/sensors/safing_accel`, `/sensors/satellite_left`, `/sensors/satellite_right` | `feeds.postcard` (`sensor-feeds --log`) | publication |
//! | `/truth/world` | the scenario file | ms of the scenario |
//!
//! **One clock.** Every message's `log_time` is UTC (CLOCK_REALTIME, ns), as the same run's
//! `run.mf4` is stamped: candump stamps frames with the kernel's CLOCK_REALTIME arrival time
//! and a frame's `log_time` and `publish_time` are that stamp (µs → ns); everything the bench
//! processes time — the ECU's cycles and diagnostics, the stubs' receive times, the feeds'
//! publications, the truth — is on CLOCK_MONOTONIC, keeps that time as its `publish_time` and
//! in its own fields, and is logged at it plus the run's realtime − monotonic offset. The
//! offset is measured from the run itself: the stubs log the same kernel arrival time of every
//! command frame on CLOCK_MONOTONIC (`commands.jsonl`), so it is the median of candump − stubs
//! over the frames both saw. The file's `bench` metadata names the clock (`log_time_clock`),
//! the offset (`realtime_minus_monotonic_ns`: a bench time is a log time less it), the route
//! and whether the timing is emulated. A simulated run (the offline bench) has one clock and
//! keeps it; a run whose offset could not be measured logs its frames at candump's stamps and
//! everything else at its bench time, and says so.
//!
//! Message encoding is JSON; every schema is a JSON Schema, the CAN ones generated from the
//! DBC's signal tables (`bus::signals_of`), never typed by hand.

mod diag_fields;
pub mod latency;
mod mf4;
pub mod pending;
pub mod read;
mod run_folder;
pub mod schema;
pub mod write;

pub use mf4::{summary_line as mf4_summary_line, write_run_mf4, Mf4Summary, RUN_MF4};
pub use run_folder::run_clock_offset_ns;
pub use write::{write_run, RunMeta, WriteSummary};

/// The sensor feeds' log of what they published in a run folder (`sensor-feeds --log`,
/// postcard `signals::FeedLogRecord`s back to back).
pub const FEEDS_LOG: &str = "feeds.postcard";

/// The actuator stubs' log of the ECU's diagnostics in a run folder (postcard
/// `signals::EcuDiagnostics` back to back). The stubs write it under their own name for it,
/// `actuator_stubs::DIAGNOSTICS_LOG`: this crate reads run folders without linking the stubs,
/// and a test of the bench checks that the two names are one.
pub const DIAGNOSTICS_LOG: &str = "diagnostics.postcard";

/// File name of a run's recording in its folder.
pub const RUN_MCAP: &str = "run.mcap";

/// The configuration the ECU ran with in a run folder (`ecu --show-config`'s TOML, from its
/// report): the recording carries it as the `ecu_config` metadata (key `toml`).
pub const ECU_CONFIG: &str = "ecu-config.toml";
