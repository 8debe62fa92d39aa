//! The real-time process shell (see the crate docs for the split). Without the `shell` feature,
//! only its command line and configuration.

#[cfg(feature = "shell")]
pub mod app;
pub mod cli;
#[cfg(feature = "shell")]
mod com;
pub mod config;
#[cfg(feature = "shell")]
mod deadline;
#[cfg(feature = "shell")]
mod histogram;
#[cfg(feature = "shell")]
pub mod monitor;
#[cfg(feature = "shell")]
pub mod report;
#[cfg(feature = "shell")]
pub mod rt;
#[cfg(feature = "shell")]
mod run;

pub use cli::{Cli, Command, MonitorArgs, RunArgs};
#[cfg(feature = "shell")]
pub use com::{CanPort, IceoryxIo};
pub use config::{CanConfig, EcuConfig, IpcConfig, Layers, RtConfig};
#[cfg(feature = "shell")]
pub use deadline::{DeadlineGrid, NextSlot};
#[cfg(feature = "shell")]
pub use histogram::{LatencyHistogram, Percentiles};
#[cfg(feature = "shell")]
pub use host::{Clock, MonotonicClock, SimClock};
#[cfg(feature = "shell")]
pub use report::TimingReport;
#[cfg(feature = "shell")]
pub use restraint::{Activity, CycleInfo, CycleIo, IoError, SimIo};
#[cfg(feature = "shell")]
pub use run::{run_activity, LoopConfig, LoopStats};
