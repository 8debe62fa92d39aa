//! What travels over shared memory. The ECU's records (object state, accelerometer batch,
//! diagnostics) are the `signals` crate's types, carried in the [`Shm`] transport wrapper so the
//! core never sees iceoryx2; the bench-only [`BenchTruth`] is defined here.

use core::fmt;

use iceoryx2::prelude::ZeroCopySend;
use signals::{CrashAccelSample, EcuDiagnostics, ObjectState, SatelliteFrames};

/// The core's plain records that may live in shared memory: `#[repr(C)]`, `Copy`,
/// pointer-free, every bit pattern of every field valid (flags are `u8`). Sealed: only the
/// types below.
pub trait ShmRecord: Copy + fmt::Debug + 'static + sealed::Sealed {}

mod sealed {
    pub trait Sealed {}
    impl Sealed for signals::ObjectState {}
    impl Sealed for signals::CrashAccelSample {}
    impl Sealed for signals::EcuDiagnostics {}
    impl Sealed for signals::SatelliteFrames {}
}

impl ShmRecord for ObjectState {}
impl ShmRecord for CrashAccelSample {}
impl ShmRecord for EcuDiagnostics {}
impl ShmRecord for SatelliteFrames {}

/// A core record as iceoryx2 carries it (same layout: `repr(transparent)`).
#[repr(transparent)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shm<T: ShmRecord>(pub T);

// SAFETY: `Shm<T>` is `repr(transparent)` over a `ShmRecord`, which is sealed to the core's
// `#[repr(C)]`, `Copy` records made of integers, floats and fixed arrays of them: no pointers,
// no references, no invalid bit patterns, the same layout in every process of the bench
// (they are built from the same crate).
unsafe impl<T: ShmRecord> ZeroCopySend for Shm<T> {}

/// Capacity of [`BenchTruth::scenario_name`] (UTF-8 bytes, zero padded).
pub const SCENARIO_NAME_CAPACITY: usize = 64;

/// What really happened in the played scenario (sensor feeds → actuator stubs, tests).
///
/// The ECU never subscribes to this: it is the bench's ground truth, used to judge the
/// ECU's commands against the true contact instant and the true crash.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
pub struct BenchTruth {
    /// CLOCK_MONOTONIC time of publication, ns.
    pub timestamp_ns: u64,
    /// Publisher sequence counter.
    pub sequence: u64,
    /// CLOCK_MONOTONIC time of scenario t = 0, ns.
    pub start_ns: u64,
    /// CLOCK_MONOTONIC time of the true first contact, ns; 0 = no contact (yet, or avoided).
    pub contact_ns: u64,
    /// True ego mass, kg.
    pub ego_mass_kg: f32,
    /// True opponent mass, kg (`f32::INFINITY` = rigid barrier).
    pub opponent_mass_kg: f32,
    /// True closing speed at contact, m/s (0 until contact).
    pub closing_speed_at_contact_mps: f32,
    /// Number of valid bytes in `scenario_name`.
    pub scenario_name_len: u32,
    /// Scenario name, UTF-8, zero padded.
    pub scenario_name: [u8; SCENARIO_NAME_CAPACITY],
    /// 1 when the scenario has finished playing (no more feeds will follow).
    pub done: u8,
    /// Explicit padding so the layout has no implicit holes.
    pub _reserved: [u8; 7],
}

impl BenchTruth {
    /// Nothing known yet.
    pub const EMPTY: Self = Self {
        timestamp_ns: 0,
        sequence: 0,
        start_ns: 0,
        contact_ns: 0,
        ego_mass_kg: 0.0,
        opponent_mass_kg: 0.0,
        closing_speed_at_contact_mps: 0.0,
        scenario_name_len: 0,
        scenario_name: [0; SCENARIO_NAME_CAPACITY],
        done: 0,
        _reserved: [0; 7],
    };

    /// Stores `name`, truncated at a character boundary to the capacity.
    pub fn set_scenario_name(&mut self, name: &str) {
        let mut end = name.len().min(SCENARIO_NAME_CAPACITY);
        while !name.is_char_boundary(end) {
            end -= 1;
        }
        self.scenario_name = [0; SCENARIO_NAME_CAPACITY];
        self.scenario_name[..end].copy_from_slice(&name.as_bytes()[..end]);
        self.scenario_name_len = end as u32;
    }

    /// The scenario name (invalid UTF-8 or a corrupt length yields the valid prefix).
    pub fn scenario_name(&self) -> &str {
        let n = (self.scenario_name_len as usize).min(SCENARIO_NAME_CAPACITY);
        let bytes = self.scenario_name.get(..n).unwrap_or(&[]);
        let text = match core::str::from_utf8(bytes) {
            Ok(s) => s,
            Err(e) => core::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or(""),
        };
        text.trim_end_matches('\0')
    }

    /// True once the feeds have finished.
    pub fn is_done(&self) -> bool {
        self.done == 1
    }
}

impl Default for BenchTruth {
    fn default() -> Self {
        Self::EMPTY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bench_truth_name_roundtrip_and_truncation() {
        let mut t = BenchTruth::EMPTY;
        t.set_scenario_name("taurus-48-48-abs");
        assert_eq!(t.scenario_name(), "taurus-48-48-abs");
        // 63 ASCII bytes + a 2-byte character: truncated before the character.
        let long = format!("{}é", "a".repeat(63));
        t.set_scenario_name(&long);
        assert_eq!(t.scenario_name(), "a".repeat(63));
        t.scenario_name_len = u32::MAX;
        assert_eq!(t.scenario_name(), "a".repeat(63));
    }
}
