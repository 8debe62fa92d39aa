//! The restraint cycle never panics: arbitrary CAN frames (ids, DLC, bytes, also valid
//! E2E-sealed frames with extreme physical values), arbitrary object states and
//! accelerometer batches (NaN, ±inf, huge, garbage timestamps/counts/periods) and arbitrary
//! timing (jumps, standstill, time running backwards), with and without a LUT.
//! Outputs stay well-formed: every frame sent decodes with the bus crate.

use crate::cycle_support::{Bench, MS};
use bus::RawFrame;
use proptest::prelude::*;
use restraint::{Activity, CrashAccelSample, CycleInfo, ObjectState};

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(f32::MAX),
        Just(f32::MIN),
        Just(0.0f32),
        -1.0e4f32..1.0e4,
        any::<f32>(),
    ]
}

#[derive(Debug, Clone)]
enum Event {
    Object(ObjectState, bool),
    Accel(CrashAccelSample, bool),
    Raw(RawFrame),
    Vehicle(f32),
    Occupant(f32, u16),
    Time(u64, bool),
}

fn object() -> impl Strategy<Value = (ObjectState, bool)> {
    (
        any::<u64>(),
        any::<u64>(),
        [
            any_f32(),
            any_f32(),
            any_f32(),
            any_f32(),
            any_f32(),
            any_f32(),
        ],
        any::<u8>(),
        any::<bool>(),
    )
        .prop_map(|(ts, seq, f, valid, ts_now)| {
            (
                ObjectState {
                    timestamp_ns: ts,
                    sequence: seq,
                    distance_m: f[0],
                    closing_speed_mps: f[1],
                    relative_accel_mps2: f[2],
                    opponent_mass_kg: f[3],
                    opponent_mass_sigma_kg: f[4],
                    confidence: f[5],
                    object_id: 1,
                    valid: if valid < 200 { 1 } else { valid },
                    _reserved: [0; 3],
                },
                ts_now,
            )
        })
}

fn accel() -> impl Strategy<Value = (CrashAccelSample, bool)> {
    (
        any::<u64>(),
        any::<u32>(),
        any::<u32>(),
        prop::array::uniform8(any_f32()),
        any::<bool>(),
    )
        .prop_map(|(ts, period, count, s, ts_now)| {
            (
                CrashAccelSample {
                    first_timestamp_ns: ts,
                    sequence: 1,
                    sample_period_ns: period,
                    count,
                    accel_mps2: s,
                },
                ts_now,
            )
        })
}

fn event() -> impl Strategy<Value = Event> {
    prop_oneof![
        object().prop_map(|(o, n)| Event::Object(o, n)),
        accel().prop_map(|(a, n)| Event::Accel(a, n)),
        (any::<u32>(), any::<bool>(), any::<u8>(), any::<[u8; 8]>()).prop_map(
            |(id, ext, len, data)| Event::Raw(RawFrame {
                id: if ext {
                    id | bus::CAN_EFF_FLAG
                } else {
                    id & 0x7FF
                },
                len,
                data
            })
        ),
        (0.0f32..100.0).prop_map(Event::Vehicle),
        (0.0f32..250.0, 0u16..1000).prop_map(|(m, d)| Event::Occupant(m, d)),
        (any::<u64>(), any::<bool>()).prop_map(|(t, small)| Event::Time(t, small)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]
    #[test]
    fn cycle_never_panics(events in prop::collection::vec(event(), 1..200), with_lut: bool) {
        let mut b = Bench::new(with_lut.then(crate::cycle_support::test_lut));
        b.send_vehicle = false;
        b.send_occupant = false;
        let mut now = crate::cycle_support::T0;
        for (i, e) in events.into_iter().enumerate() {
            match e {
                Event::Object(mut o, ts_now) => {
                    if ts_now { o.timestamp_ns = now; }
                    b.io.push_object(o);
                }
                Event::Accel(mut a, ts_now) => {
                    if ts_now { a.first_timestamp_ns = now; }
                    b.io.push_accel(a);
                    // Every other arbitrary batch goes to the safing channel too.
                    if a.sequence % 2 == 1 { b.io.push_safing(a); }
                }
                Event::Raw(f) => b.io.push_can(f),
                Event::Vehicle(v) => {
                    let f = b.vehicle_frame(v);
                    b.io.push_can(f);
                }
                Event::Occupant(m, d) => {
                    b.occupant_mass_kg = m;
                    b.chest_mm = d;
                    let f = b.occupant_frame();
                    b.io.push_can(f);
                }
                Event::Time(t, small) => {
                    now = if small { now.wrapping_add(t % (50 * MS)) } else { t };
                }
            }
            let info = CycleInfo { cycle: i as u64, now_ns: now, period_ns: MS, ..CycleInfo::default() };
            let before = b.io.can_tx_total;
            b.ecu.step(&info, &mut b.io);
            for f in b.io.sent_since(before) {
                prop_assert!(bus::decode(f.id, f.payload()).is_ok(), "malformed output {f:?}");
            }
            now = now.wrapping_add(MS);
        }
        let mut c = Vec::new();
        b.ecu.report_counters(&mut |n, v| c.push((n, v)));
        prop_assert!(c.iter().any(|(n, _)| *n == "encode_errors"));
        prop_assert_eq!(b.ecu.counters().encode_errors, 0);
    }
}
