//! Instruction-count workload: `icount-prediction N [MODE]` runs N collision predictions over
//! [`cycle_benches::workload::PredictionWorkload`] (default ego against the default table's
//! opponent masses and closing speeds). Measured under callgrind at two N; see
//! `cycle_benches::icount`. MODE:
//!
//! * `exact` (default; what the budget gate measures): the closed-form summary
//!   `physics::predict_summary` — the per-cycle prediction.
//! * `step`: the fixed-step integration at the ECU's former 0.5 ms step into a 150 ms pulse
//!   buffer — the per-cycle prediction before the closed form.
//! * `diag`: `ExactCollision::solve_in_place` (a kept solution, as the ECU would hold it)
//!   plus the 64 diagnostics points of the ego pulse.
//! * `pulse-exact` / `pulse-step`: the 150 ms pulse at the default 0.1 ms step, closed form /
//!   integrated (the table builder's pulse).

use cycle_benches::{
    icount,
    workload::{PredictionWorkload, FORMER_ECU_STEP_S},
};
use physics::{
    defaults, predict_summary, simulate_collision, simulate_collision_exact, CollisionInput,
    DefaultPulseBuffer, ExactCollision,
};
use std::hint::black_box;

fn main() {
    let n = icount::iterations_from_args();
    let mode = std::env::args().nth(2).unwrap_or_else(|| "exact".into());
    let w = PredictionWorkload::new();
    let ecu_step_s = FORMER_ECU_STEP_S;
    let diag_step_s = defaults::PULSE_DURATION_S / ipc::PULSE_POINTS as f64;
    let mut buf = Box::new(DefaultPulseBuffer::new());
    let mut points = [0.0f32; ipc::PULSE_POINTS];
    let mut kept = Box::new(ExactCollision::new());
    let mut acc = 0.0;
    for i in 0..n as usize {
        let ecu: CollisionInput<'_> = w.input(i, ecu_step_s);
        let fine = w.input(i, defaults::STEP_S);
        let s = match mode.as_str() {
            "step" => simulate_collision(black_box(&ecu), &mut buf),
            "pulse-step" => simulate_collision(black_box(&fine), &mut buf),
            "pulse-exact" => simulate_collision_exact(black_box(&fine), &mut buf),
            "diag" => kept.solve_in_place(black_box(&ecu)).copied().inspect(|_| {
                if let Ok(it) = kept.samples(diag_step_s) {
                    for (dst, p) in points.iter_mut().zip(it) {
                        *dst = p.ego_accel_mps2 as f32;
                    }
                }
            }),
            _ => predict_summary(black_box(&ecu)),
        };
        acc += s.map_or(0.0, |s| s.vehicle.a_mean_mps2) + f64::from(black_box(points[1]));
    }
    println!("{acc}");
}
