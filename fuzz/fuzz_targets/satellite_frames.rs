//! The crush-zone satellites' fusion (`restraint::satellites::Satellites`) fed arbitrary PSI5
//! frame batches of either satellite (any words, counts, periods) and arbitrary tunnel
//! velocity changes (NaN and ±inf included), cycle after cycle.
//!
//! Input: records of 7 bytes `[side][count][period][w0 lo][w0 hi][w1 lo][w1 hi]` (side bit 0:
//! left/right, bit 1: a cycle ends after this record; count as given, corrupt ones included;
//! period `p · 50 µs`; the batch's eight words repeat w0, w1) and, with bit 2 of `side`, one
//! more f32 (LE) of tunnel Δv.
//!
//! Oracles: no panic; every relief fraction lies in [0, 1] and a relieved floor is never above
//! the unrelieved one; and the property the fusion exists for — **one satellite alone grants
//! nothing while its twin is in the fusion**: a twin fusion that gets the same left frames and
//! tunnel but a right satellite at rest (data code 0) grants a relief only once that right
//! satellite is out of it (it lagged the tunnel: `Satellites::faulty`), and it keeps the
//! airbag boundary's whole low-crush lift until then (one satellite cannot take it away).
#![no_main]

use libfuzzer_sys::fuzz_target;
use restraint::satellites::{Relief, Satellites};
use restraint::signals::{psi5, SatelliteFrames, SatelliteSide};
use restraint::CycleConfig;

const MS: u64 = 1_000_000;

fuzz_target!(|data: &[u8]| {
    let params = CycleConfig::default().satellite_params();
    let mut fused = Satellites::new(params);
    let mut one_sided = Satellites::new(params);
    let at_rest = SatelliteFrames {
        sample_period_ns: 500_000,
        count: 2,
        frames: [psi5::encode(0); 8],
        ..SatelliteFrames::EMPTY
    };
    let mut now = MS;
    let mut rest = data;
    let mut cycles = 0;
    fused.begin_cycle(now);
    one_sided.begin_cycle(now);
    while rest.len() >= 7 && cycles < 2_000 {
        let (r, tail) = rest.split_at(7);
        rest = tail;
        let side = if r[0] & 1 == 0 {
            SatelliteSide::Left
        } else {
            SatelliteSide::Right
        };
        let w0 = u16::from_le_bytes([r[3], r[4]]);
        let w1 = u16::from_le_bytes([r[5], r[6]]);
        let mut frames = [w0; 8];
        for (i, f) in frames.iter_mut().enumerate() {
            if i % 2 == 1 {
                *f = w1;
            }
        }
        let b = SatelliteFrames {
            first_timestamp_ns: now,
            sequence: u64::from(r[1]),
            sample_period_ns: u32::from(r[2]) * 50_000,
            count: u32::from(r[1]),
            frames,
        };
        fused.on_frames(side, &b, now);
        if side == SatelliteSide::Left {
            one_sided.on_frames(side, &b, now);
        }
        if r[0] & 4 != 0 && rest.len() >= 4 {
            let dv = f32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]);
            rest = &rest[4..];
            fused.on_tunnel_dv(f64::from(dv));
            one_sided.on_tunnel_dv(f64::from(dv));
        }
        if r[0] & 2 != 0 {
            one_sided.on_frames(SatelliteSide::Right, &at_rest, now);
            for (relief, judged) in [(fused.relief(now, true), "fused"), (one_sided.relief(now, true), "one")] {
                assert!((0.0..=1.0).contains(&relief.fraction), "{judged}: {relief:?}");
                assert!(relief.floor_mps(1.25, 0.3) <= Relief::NONE.floor_mps(1.25, 0.3) + 1e-12);
            }
            let one = one_sided.relief(now, true);
            assert!(
                (one.fraction == 0.0 && one.boundary_lift_mps == params.low_crush_lift_mps)
                    || one_sided.faulty(SatelliteSide::Right, now),
                "one satellite granted a relief, or took the low-crush lift away, while its twin \
                 was in the fusion: {one:?}"
            );
            now += MS;
            cycles += 1;
            fused.begin_cycle(now);
            one_sided.begin_cycle(now);
        }
    }
});
