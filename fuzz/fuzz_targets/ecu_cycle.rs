//! The whole ECU decision cycle (`ecu::cycle::RestraintCycle` as an `Activity`) driven through
//! `SimIo` with arbitrary inputs: object states, accelerometer batches and CAN frames (any
//! values, NaN/inf included, any ids/lengths, time that jumps or stands still), cycle after cycle.
//!
//! Input: records of `[kind][fields…]`; kind % 4: 0 = object state (7 f32 + flags), 1 = accel
//! batch (period, count, samples), 2 = CAN frame (id, len, 8 bytes), 3 = run one cycle (time
//! step). Built once per input with the default cycle configuration, the built-in reference
//! restraint and no LUT (the degraded path; the LUT path is covered by `lut_load`). The first
//! byte is reserved.
//!
//! Oracles: no panic, no hang; every CAN frame the ECU sends decodes with `bus::decode`
//! (valid DBC frame, correct CRC, signals in range), whatever it was fed.
#![no_main]

use ecu::cycle::RestraintCycle;
use ecu::runtime::{Activity, CanFrame, CycleInfo, SimIo};
use libfuzzer_sys::fuzz_target;

struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn u8(&mut self) -> Option<u8> {
        let (b, rest) = self.0.split_first()?;
        self.0 = rest;
        Some(*b)
    }
    fn u32(&mut self) -> Option<u32> {
        let b = self.0.get(..4)?;
        let v = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        self.0 = &self.0[4..];
        Some(v)
    }
    fn f32(&mut self) -> Option<f32> {
        self.u32().map(f32::from_bits)
    }
}

fuzz_target!(|data: &[u8]| {
    if data.is_empty() {
        return;
    }
    let Ok(reference) = physics::reference::ReferenceRestraint::builtin() else {
        return;
    };
    let cfg = ecu::cycle::CycleConfig::default();
    let Ok((mut cycle, _notes)) = RestraintCycle::new(cfg, None, &reference.restraint) else {
        panic!("default cycle config must build");
    };
    let mut io = SimIo::new();
    let mut now_ns: u64 = 1_000_000_000;
    if cycle.startup(now_ns, &mut io).is_err() {
        return;
    }
    let mut r = Reader(&data[1..]);
    let mut info = CycleInfo {
        period_ns: 1_000_000,
        ..CycleInfo::default()
    };
    let mut cycles = 0u32;
    while let Some(kind) = r.u8() {
        match kind % 4 {
            0 => {
                let mut o = ipc::ObjectState::default();
                o.timestamp_ns = now_ns.saturating_sub(u64::from(r.u8().unwrap_or(0)) * 100_000);
                o.sequence = u64::from(r.u8().unwrap_or(0));
                o.distance_m = r.f32().unwrap_or(10.0);
                o.closing_speed_mps = r.f32().unwrap_or(10.0);
                o.relative_accel_mps2 = r.f32().unwrap_or(0.0);
                o.opponent_mass_kg = r.f32().unwrap_or(1500.0);
                o.opponent_mass_sigma_kg = r.f32().unwrap_or(100.0);
                o.confidence = r.f32().unwrap_or(1.0);
                o.valid = r.u8().unwrap_or(1) & 1;
                io.objects.push_back(o);
            }
            1 => {
                let mut a = ipc::CrashAccelSample::EMPTY;
                a.first_timestamp_ns =
                    now_ns.saturating_sub(u64::from(r.u8().unwrap_or(0)) * 100_000);
                a.sequence = u64::from(r.u8().unwrap_or(0));
                a.sample_period_ns = r.u32().unwrap_or(100_000);
                a.count = u32::from(r.u8().unwrap_or(0));
                let n = (a.count as usize).min(a.accel_mps2.len()).min(16);
                for s in a.accel_mps2.iter_mut().take(n) {
                    *s = r.f32().unwrap_or(-300.0);
                }
                io.accel.push_back(a);
            }
            2 => {
                let id_lo = r.u8().unwrap_or(0xA0);
                let id_hi = r.u8().unwrap_or(0);
                let len = r.u8().unwrap_or(8);
                let mut data = [0u8; 8];
                for d in &mut data {
                    *d = r.u8().unwrap_or(0);
                }
                io.can_rx.push_back(CanFrame {
                    id: u32::from(u16::from_le_bytes([id_lo, id_hi]) & 0x7FF),
                    extended: id_hi & 0x80 != 0,
                    len,
                    data,
                });
            }
            _ => {
                let step = u64::from(r.u8().unwrap_or(1));
                now_ns = now_ns.saturating_add(step * 250_000);
                info.deadline_ns = now_ns;
                info.now_ns = now_ns;
                cycle.step(&info, &mut io);
                info.cycle += 1;
                info.slot += 1;
                cycles += 1;
                if cycles > 2_000 {
                    break;
                }
            }
        }
    }
    cycle.step(&info, &mut io);
    for f in &io.can_tx {
        if let Err(e) = bus::decode(f.id, f.payload()) {
            // The SecOC authenticators carry no E2E; everything else must decode.
            panic!(
                "ECU sent an invalid frame {:#x} {:?}: {e}",
                f.id,
                f.payload()
            );
        }
    }
});
