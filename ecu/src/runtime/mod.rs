//! The real-time process shell (see the crate docs for the split).

mod activity;
pub mod app;
mod builtin;
mod clock;
mod com;
pub mod config;
mod deadline;
mod histogram;
pub mod monitor;
pub mod report;
pub mod rt;
mod run;
mod sim;

pub use activity::{Activity, CanFrame, CycleInfo, CycleIo, IoError};
pub use builtin::PassthroughActivity;
pub use clock::{Clock, MonotonicClock, SimClock};
pub use com::{CanPort, IceoryxIo};
pub use config::{CanConfig, Cli, Command, EcuConfig, IpcConfig, MonitorArgs, RtConfig, RunArgs};
pub use deadline::{DeadlineGrid, NextSlot};
pub use histogram::{LatencyHistogram, Percentiles};
pub use report::TimingReport;
pub use run::{run_activity, LoopConfig, LoopStats};
pub use sim::SimIo;
