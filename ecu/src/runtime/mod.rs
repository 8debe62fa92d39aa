//! The real-time process shell (see the crate docs for the split).

pub mod app;
pub mod cli;
mod com;
pub mod config;
mod deadline;
mod histogram;
pub mod monitor;
pub mod report;
pub mod rt;
mod run;

pub use cli::{Cli, Command, MonitorArgs, RunArgs};
pub use com::{CanPort, IceoryxIo};
pub use config::{CanConfig, EcuConfig, IpcConfig, Layers, RtConfig};
pub use deadline::{DeadlineGrid, NextSlot};
pub use histogram::{LatencyHistogram, Percentiles};
pub use host::{Clock, MonotonicClock, SimClock};
pub use report::TimingReport;
pub use restraint::{Activity, CycleInfo, CycleIo, IoError, SimIo};
pub use run::{run_activity, LoopConfig, LoopStats};
