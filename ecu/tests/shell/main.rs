//! The ECU's process shell tested for real — iceoryx2 shared memory, the `ecu` binary, vcan —
//! in one test binary: each of these files links iceoryx2 and the whole shell, which as five
//! binaries cost the suite's build ≈ 10 s apiece. The counting allocator of the no-allocation
//! tests counts per thread, so the modules' tests run side by side without disturbing it.

#[path = "../../../restraint/tests/alloc_counter/mod.rs"]
mod alloc_counter;
#[path = "../../../restraint/tests/cycle/cycle_support/mod.rs"]
mod cycle_support;
mod support;
#[path = "../../../bus/tests/support/vcan_rerun.rs"]
mod vcan_rerun;

/// `ecu` on vcan0 (in the QEMU guest where this kernel has no SocketCAN).
mod cycle_vcan;
/// `app::run_ecu` round trip over iceoryx2.
mod iceoryx_e2e;
/// No allocation on the cycle thread with real iceoryx2 traffic.
mod no_alloc;
/// The `ecu` binary: flags, config errors, SIGTERM, report, `ecu monitor`.
mod process;
/// The safing accelerometer's port.
mod safing_port;
