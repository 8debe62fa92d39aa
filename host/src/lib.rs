//! What the bench processes (ECU, sensor feeds, actuator stubs) take from the Linux host, in
//! one place so that every process reads time the same way:
//!
//! * [`clock`] — CLOCK_MONOTONIC (the bench's one time base for timestamps and deadlines,
//!   shared by every process on the machine), the synchronized time of SecOC freshness
//!   (CLOCK_REALTIME µs), absolute sleeps, and the simulated clock of deterministic tests;
//! * [`stop`] — the SIGTERM/SIGINT stop flag (and SIGPIPE's default for the command-line
//!   tools);
//! * [`files`] — where a tool finds the repository's files from any folder, output paths
//!   checked before the work, and [`NoFlush`] for logs that flush on their own schedule;
//! * [`exit`] — how every command-line tool ends: exit codes 0 / 1 / 2 and a one-line error;
//! * [`results`] — the JSON results the tools write, each with its `schema_version`.

pub mod clock;
pub mod exit;
pub mod files;
pub mod results;
pub mod stop;

pub use clock::{
    monotonic_ns, realtime_ns, sleep_through_signals_until_ns, sleep_until_ns, sync_time_us, Clock,
    MonotonicClock, SimClock, SleepOutcome,
};
pub use exit::{check_exit_code, exit_code, CheckFailed};
pub use files::{check_output_dir, check_output_file, find_repo, find_upwards, NoFlush};
pub use stop::{default_sigpipe, install_stop_signals};
