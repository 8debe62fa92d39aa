//! Criterion benches (benches/benches/) and the per-cycle budget gate.
//!
//! The library holds what the benches, the instruction-count binaries (`icount-*`) and the gate
//! share, so that the criterion figure and the callgrind figure of a stage measure the *same*
//! code on the *same* inputs:
//!
//! * [`workload`] — the measured work: one cycle's input frames, its command frames, the bench
//!   characteristic diagram.
//! * [`ecu_cycle`] — the real ECU cycle (`restraint::RestraintCycle`) on its worst-case and
//!   common paths, set up once for the `cycle` bench and the `icount-cycle` binary.
//! * [`budgets`] — `benches/budgets.toml`, the one file of budgets.
//! * [`gate`] — reading criterion's `estimates.json` and comparing with the budgets.
//! * [`icount`] — instructions per iteration from two callgrind runs.
//! * [`latency`] — cyclictest histogram and ECU report parsing for the loop harness.
//! * [`worst_case`] — the search space of one cycle's inputs and state, a case run and
//!   measured (the gate's worst-case rows);
//! * [`search`] — the search's operators over cases (`worst-cycle search`).

pub mod budgets;
pub mod ecu_cycle;
pub mod gate;
pub mod icount;
pub mod latency;
pub mod search;
pub mod workload;
pub mod worst_case;
