//! The restraint cycle end to end through the core's `SimIo`: crash paths, cyclic timing,
//! diagnostics, the estimate, the table's planning margin, no panic on any input, the library's scenarios, SecOC and single
//! faults. One test binary (one compile of the core's generic code and of the scripted bench in
//! `cycle_support`), not one per file; the allocation-counting test stays its own binary
//! (`cycle_no_alloc.rs`: its global allocator would count every test beside it).

mod cycle_support;

mod crash_paths;
mod cyclic_timing;
mod diagnostics;
mod estimate;
mod lut_margin;
mod no_panic;
mod scenarios;
mod secoc;
mod single_fault;
mod v2x;
