//! Writes the committed seed corpora, `corpus/<target>/seed-*`, from the project's own encoders
//! (so every seed is a valid input that reaches deep code, and stays valid when formats change:
//! rerun it). Run from `fuzz/`:
//!
//! ```sh
//! cargo run --example make_seeds --no-default-features
//! ```
//!
//! Seeds are deliberately few and small; libFuzzer grows its own corpus from them.

use std::fs;
use std::path::Path;

use bus::codec::{
    AirbagStageCmdArm, AirbagStageCmdCmdSource, AirbagStageCmdFire, AirbagStageCmdStage,
    BeltLimiterCmdCmdSource, BeltLimiterCmdPretensionerCmd, EgoVehicleStateBrakeState,
};
use bus::{AirbagStageCmd, BeltLimiterCmd, E2eProtector, EgoVehicleState, RawFrame};

fn write(target: &str, name: &str, bytes: &[u8]) {
    let dir = Path::new("corpus").join(target);
    fs::create_dir_all(&dir).expect("create corpus dir");
    fs::write(dir.join(format!("seed-{name}")), bytes).expect("write seed");
}

fn frames() -> Vec<RawFrame> {
    let mut tx = E2eProtector::new();
    let mut v = Vec::new();
    for i in 0..3 {
        v.push(
            tx.seal(
                AirbagStageCmd::encode(
                    AirbagStageCmdArm::Armed,
                    if i == 2 {
                        AirbagStageCmdFire::Fire
                    } else {
                        AirbagStageCmdFire::NoFire
                    },
                    AirbagStageCmdCmdSource::Adaptive,
                    AirbagStageCmdStage::Stage1,
                    6.5,
                    12.0,
                )
                .expect("valid airbag command"),
            ),
        );
        v.push(
            tx.seal(
                BeltLimiterCmd::encode(
                    BeltLimiterCmdPretensionerCmd::Fire,
                    BeltLimiterCmdCmdSource::Reference,
                    4.0,
                    -20.0,
                )
                .expect("valid belt command"),
            ),
        );
        v.push(
            tx.seal(
                EgoVehicleState::encode(EgoVehicleStateBrakeState::AbsActive, 14.4, -7.5)
                    .expect("valid ego state"),
            ),
        );
    }
    v
}

fn bus_seeds(frames: &[RawFrame]) {
    for (i, f) in frames.iter().enumerate() {
        // bus_decode: id (LE u16), flag byte, payload.
        let mut b = (f.id as u16).to_le_bytes().to_vec();
        b.push(0);
        b.extend_from_slice(f.payload());
        write("bus_decode", &format!("{i:02}-{:03x}", f.id), &b);
    }
    // e2e_check: max_lost, then records [0xF0][id LE][len][bytes] (explicit ids).
    let mut seq = vec![0u8];
    for f in frames {
        seq.push(0xF0);
        seq.extend_from_slice(&(f.id as u16).to_le_bytes());
        seq.push(f.len);
        seq.extend_from_slice(f.payload());
    }
    write("e2e_check", "stream", &seq);
    let mut tolerant = seq.clone();
    tolerant[0] = 2;
    write("e2e_check", "stream-tolerant", &tolerant);
}

fn secoc_seeds() {
    // secoc_verify: stream bit, then ops (see the target's docs).
    let mut ops = vec![0u8];
    for i in 0..4u8 {
        ops.push(0);
        ops.extend_from_slice(&[0x5A, 0x10 + i, 0x06, 0, 0x82, 0x00, 0, 0]);
    }
    ops.extend_from_slice(&[3, 1, 1]); // replay pair 1
    ops.extend_from_slice(&[2, 70]); // lose 70 authenticators (beyond the window)
    ops.push(0);
    ops.extend_from_slice(&[1; 8]);
    ops.extend_from_slice(&[4, 200, 8]); // 51 ms pass
    ops.extend_from_slice(&[5, 8, 1, 2, 3, 4, 5, 6, 7, 8]); // attacker command
    ops.extend_from_slice(&[6, 8, 1, 0, 0, 9, 9, 9, 9, 9]); // attacker authenticator
    ops.extend_from_slice(&[7, 0x31, 0x00, 8, 2, 0, 0, 1, 2, 3, 4, 5]); // via the router
    write("secoc_verify", "session", &ops);
    let mut belt = ops.clone();
    belt[0] = 1;
    write("secoc_verify", "session-belt", &belt);
}

fn lut_seeds() {
    use diagram::{AirbagThresholds, Axes, BuildInfo, Cell, Diagram, EgoVehicle, Header};
    let header = Header {
        ego: EgoVehicle {
            mass_kg: 1785.0,
            class: 4,
            description: "fuzz seed".into(),
        },
        build: BuildInfo::default(),
        airbag_thresholds: AirbagThresholds::DEFAULT,
    };
    let axes = Axes::new(
        vec![40.0, 80.0, 108.0],
        vec![800.0, 1785.0, 3000.0],
        vec![30.0, 125.0],
        vec![200.0, 450.0],
    );
    let d = Diagram::from_fn(header, axes, |p| {
        let s = p.index as f32;
        Cell {
            belt_limiter_kn: 1.0 + (s % 11.0),
            airbag_level_kn: s % 12.0,
            pretensioner_time_ms: -10.0,
            airbag_time_ms: 10.0,
            a_max_g: 30.0,
            a_mean_g: 20.0,
            excursion_mm: 150.0,
            bottoming_out: 0.0,
            a_ideal_g: 15.0,
        }
    })
    .expect("valid seed table");
    write("lut_load", "small.lut", &d.to_bytes());
    write("lut_load", "small.json", d.to_json_string().as_bytes());
}

fn config_seeds() {
    let ecu_toml = fs::read("../ecu/ecu.toml").expect("ecu/ecu.toml");
    write("ecu_config", "ecu.toml", &ecu_toml);
    write(
        "ecu_config",
        "minimal.toml",
        b"period_us = 1000\n[can]\nenabled = false\n",
    );
}

fn scenario_seeds() {
    let mut names: Vec<_> = fs::read_dir("../scenarios")
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    names.retain(|p| p.extension().is_some_and(|e| e == "toml"));
    names.sort();
    for p in names.iter().take(3) {
        let name = p
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("scenario.toml");
        write("scenario_parse", name, &fs::read(p).expect("scenario file"));
    }
}

/// ecu_cycle, raw records only (see the target): flag byte 0 (no LUT), an object closing in,
/// the vehicle's CAN state, cycles, then a crash pulse on the accelerometer.
fn cycle_seed_raw(frames: &[RawFrame]) -> Vec<u8> {
    let mut b = vec![0u8];
    let f32s =
        |b: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
    for k in 0..20u8 {
        b.extend_from_slice(&[0, 0, k]);
        f32s(
            &mut b,
            &[8.0 - 0.3 * f32::from(k), 15.0, -2.0, 1500.0, 150.0, 0.95],
        );
        b.push(1);
        if let Some(f) = frames.get(usize::from(k) % frames.len()) {
            b.push(2);
            b.extend_from_slice(&(f.id as u16).to_le_bytes());
            b.push(f.len);
            b.extend_from_slice(&f.data);
        }
        b.extend_from_slice(&[3, 40]); // 10 ms
    }
    for k in 0..5u8 {
        b.extend_from_slice(&[1, 0, k]);
        b.extend_from_slice(&100_000u32.to_le_bytes());
        b.push(8);
        f32s(&mut b, &[-300.0; 8]);
        b.extend_from_slice(&[3, 4]); // 1 ms
    }
    for _ in 0..3 {
        b.extend_from_slice(&[3, 40]); // 10 ms: the scheduled fires happen
    }
    b
}

/// Record kinds of the ecu_cycle target's generators (see its header).
const TRACK: u8 = 4;
const CAN_GEN: u8 = 5;
const PULSE: u8 = 6;
const RUN_MS: u8 = 7;

/// Appends "run `ms` cycles of 1 ms" records.
fn run_ms(b: &mut Vec<u8>, mut ms: u32) {
    while ms > 0 {
        let n = ms.min(256);
        b.extend_from_slice(&[RUN_MS, (n - 1) as u8]);
        ms -= n;
    }
}

/// The live accelerometer (kind 6 with `n ≥ 128`): on with a crash ramp of `0.1·slope_b` g/ms
/// from now on (0: quiet), or off (a dead sensor).
fn live_accel(b: &mut Vec<u8>, on: bool, slope_b: u8) {
    b.extend_from_slice(&[PULSE, slope_b, if on { 0x80 } else { 0xC0 }, 0]);
}

/// ecu_cycle with the generators: a buckled 75 kg mid adult at 300 mm, ego at 15.2 m/s, a
/// live accelerometer; an opponent of `opp_b` (800 + 9·b kg, σ 100 kg) closing at `speed_b`
/// (10 + b·20/255 m/s) with contact 400 ms after the start; then either a 20 g crash pulse at
/// contact (1 kHz, 3 × 8 samples: a step, not the predicted ramp — the generic thresholds
/// confirm after 3 samples, Δv 0.2 m/s each) or, 150 ms before contact, the track ends
/// (avoided); then 80 ms more.
fn cycle_seed_generated(flags: u8, speed_b: u8, opp_b: u8, crash: bool) -> Vec<u8> {
    let mut b = vec![flags];
    // 15.2 m/s; 74.8 kg; 300 mm; flags: buckle 1 (buckled) | class 3 (mid adult) << 2.
    b.extend_from_slice(&[CAN_GEN, 38, 112, 100, 1 | 3 << 2]);
    live_accel(&mut b, true, 0);
    b.push(TRACK);
    b.extend_from_slice(&400u16.to_le_bytes());
    b.extend_from_slice(&[speed_b, opp_b, 100, 0]);
    if crash {
        run_ms(&mut b, 400);
        for _ in 0..3 {
            // 40 · 0.5 g = 20 g, 8 samples, period (1 + 7) · 125 µs = 1 ms.
            b.extend_from_slice(&[PULSE, 40, 7, 7]);
            run_ms(&mut b, 8);
        }
    } else {
        // 150 ms before contact (PRE-CRASH) the object turns away: its track stops.
        run_ms(&mut b, 250);
        b.extend_from_slice(&[TRACK, 0, 0, 0, 0, 0, 0]);
        run_ms(&mut b, 300);
    }
    run_ms(&mut b, 80);
    b
}

/// The opponent's approach (as in [`cycle_seed_generated`]) until contact at 400 ms, then
/// what `at_contact` appends, then 80 ms more.
fn cycle_seed_approach(flags: u8, speed_b: u8, opp_b: u8, at_contact: impl Fn(&mut Vec<u8>)) -> Vec<u8> {
    let mut b = vec![flags];
    b.extend_from_slice(&[CAN_GEN, 38, 112, 100, 1 | 3 << 2]);
    live_accel(&mut b, true, 0);
    b.push(TRACK);
    b.extend_from_slice(&400u16.to_le_bytes());
    b.extend_from_slice(&[speed_b, opp_b, 100, 0]);
    at_contact(&mut b);
    run_ms(&mut b, 80);
    b
}

fn cycle_seeds(frames: &[RawFrame]) {
    let raw = cycle_seed_raw(frames);
    write("ecu_cycle", "approach-crash", &raw);
    let mut raw_lut = raw;
    raw_lut[0] = 1;
    write("ecu_cycle", "approach-crash-lut", &raw_lut);
    // 25.1 m/s (90 km/h), 1502 kg: PRE-CRASH with LUT lookups, crash confirmed, airbag fired
    // with the adaptive settings.
    write(
        "ecu_cycle",
        "lut-precrash-crash-fire",
        &cycle_seed_generated(1, 192, 78, true),
    );
    // 20 m/s, 1502 kg: the table's optimum has no airbag (belt only) at this point.
    write(
        "ecu_cycle",
        "lut-crash-belt-only",
        &cycle_seed_generated(1, 128, 78, true),
    );
    // The same with a V2X station reporting 2 400 kg (15 · 160): the lookups plan for it.
    let mut v2x = cycle_seed_generated(1, 192, 78, true);
    v2x.splice(1..6, [CAN_GEN, 38, 112, 100, 1 | 3 << 2 | 0x80, 15]);
    write("ecu_cycle", "lut-v2x-crash-fire", &v2x);
    // The same without a LUT: DEGRADED, reference restraint fires.
    write(
        "ecu_cycle",
        "nolut-crash-fire",
        &cycle_seed_generated(0, 128, 78, true),
    );
    // 30 m/s into 3095 kg (top of the table's speed axis, conservative mass beyond its
    // opponent axis: out-of-range lookups → reference).
    write(
        "ecu_cycle",
        "lut-fast-heavy-crash",
        &cycle_seed_generated(1, 255, 255, true),
    );
    // 10 m/s into 800 kg: ego EBS ≈ 11 km/h < 20 km/h, low-speed no-fire.
    write(
        "ecu_cycle",
        "lut-low-speed-crash",
        &cycle_seed_generated(1, 0, 0, true),
    );
    // PRE-CRASH, then the object is lost: avoided, pretensioner released.
    write(
        "ecu_cycle",
        "lut-precrash-avoided",
        &cycle_seed_generated(1, 128, 78, false),
    );
    // 25.1 m/s into 1502 kg (class 3): at contact the onset ramp of that crash (k·v/m_ego ≈
    // 3.1 g/ms) — the prediction-matched confirmation, the re-plan, the adaptive airbag.
    write(
        "ecu_cycle",
        "lut-matched-crash",
        &cycle_seed_approach(1, 192, 78, |b| {
            run_ms(b, 400);
            live_accel(b, true, 31);
            run_ms(b, 20);
        }),
    );
    // The same crash with the accelerometer dead from 300 ms before contact: degraded, the
    // vehicle-dynamics deceleration on CAN (−8 g) confirms at the predicted contact (backup).
    write(
        "ecu_cycle",
        "lut-dead-accel-backup",
        &cycle_seed_approach(1, 192, 78, |b| {
            run_ms(b, 100);
            live_accel(b, false, 0);
            run_ms(b, 300);
            b.extend_from_slice(&[CAN_GEN, 38, 112, 100, 1 | 3 << 2 | 0x40]);
            run_ms(b, 20);
        }),
    );
    // No object at all and a 4.5 g bump for 24 ms (3 pulse records of 8 samples at 1 ms): the
    // generic thresholds confirm, the accelerometer-only algorithm stays under its boundary.
    let mut bump = vec![1];
    bump.extend_from_slice(&[CAN_GEN, 38, 112, 100, 1 | 3 << 2]);
    live_accel(&mut bump, true, 0);
    run_ms(&mut bump, 200);
    live_accel(&mut bump, false, 0);
    for _ in 0..3 {
        bump.extend_from_slice(&[PULSE, 9, 7, 7]);
        run_ms(&mut bump, 8);
    }
    live_accel(&mut bump, true, 0);
    run_ms(&mut bump, 100);
    write("ecu_cycle", "lut-bump-no-fire", &bump);
    // The accelerometer stuck at 0.3 g: the same reading in 8-sample batches for 40 ms.
    let mut stuck = vec![1];
    stuck.extend_from_slice(&[CAN_GEN, 38, 112, 100, 1 | 3 << 2]);
    for _ in 0..40 {
        stuck.extend_from_slice(&[PULSE, 1, 7, 0]);
        run_ms(&mut stuck, 1);
    }
    write("ecu_cycle", "lut-stuck-accel", &stuck);
}

/// A PSI5 frame of data code `code`: 10-bit two's complement with even parity in bit 10
/// (the encoding `signals::psi5::encode` implements; written out here because the seed
/// generator builds without the ECU).
fn psi5_frame(code: i16) -> u16 {
    let data = (code as u16) & 0x3FF;
    data | (u16::from(data.count_ones() % 2 == 1) << 10)
}

fn satellite_seeds() {
    // satellite_frames: records [side][count][period][w0 LE][w1 LE] (+ f32 tunnel Δv with bit 2).
    let record = |side: u8, code: i16, dv: Option<f32>| {
        let w = psi5_frame(code).to_le_bytes();
        let mut r = vec![side | if dv.is_some() { 4 } else { 0 }, 2, 10, w[0], w[1], w[0], w[1]];
        if let Some(dv) = dv {
            r.extend_from_slice(&dv.to_le_bytes());
        }
        r
    };
    // A crash: both satellites at 120 g (code 240) over a tunnel at 10 g, 10 cycles.
    let mut crash = Vec::new();
    for _ in 0..10 {
        crash.extend(record(0, 240, None));
        crash.extend(record(1 | 2, 240, Some(0.098)));
    }
    write("satellite_frames", "crash", &crash);
    // A pothole the whole car feels: satellites and tunnel alike.
    let mut pothole = Vec::new();
    for _ in 0..10 {
        pothole.extend(record(0, 40, None));
        pothole.extend(record(1 | 2, 40, Some(0.196)));
    }
    write("satellite_frames", "pothole", &pothole);
    // One satellite saturated, the other at rest, a corrupt word.
    let mut one = Vec::new();
    for _ in 0..10 {
        one.extend(record(0, 480, None));
        one.extend(record(1 | 2, 0, Some(0.0)));
    }
    one.extend_from_slice(&[2, 2, 10, 0x01, 0x00, 0x01, 0x00]);
    write("satellite_frames", "one-sided", &one);
}

fn main() {
    let f = frames();
    satellite_seeds();
    bus_seeds(&f);
    secoc_seeds();
    lut_seeds();
    config_seeds();
    scenario_seeds();
    cycle_seeds(&f);
    println!("seeds written under fuzz/corpus/");
}
