//! Prints the accuracy of the collision model versus the integration step (README table):
//! (a) the Table 5 case with the combined curve against the closed-form solution
//!     (`physics::exact`),
//! (b) a linear spring (e = 1) against the closed-form peak force v√(kμ) and duration π√(μ/k).
//!
//! Run: `cargo run -p physics --release --example accuracy_vs_step`

use physics::{
    collision::{simulate_collision, CollisionInput, PulseBuffer},
    predict_summary, stiffness, CombinedSpring,
};

fn main() {
    let mut buf = Box::new(PulseBuffer::<64>::new());
    let c = &stiffness::COMBINED_CURVE;
    let spring = CombinedSpring::series(c, Some(c)).unwrap();
    let run = |spring: &CombinedSpring, step_s: f64, e: f64, buf: &mut PulseBuffer<64>| {
        let mut input = CollisionInput::with_defaults(spring, 1785.0, 1785.0, 30.0);
        input.step_s = step_s;
        input.restitution = e;
        simulate_collision(&input, buf).unwrap()
    };
    let reference = predict_summary(&CollisionInput::with_defaults(
        &spring, 1785.0, 1785.0, 30.0,
    ))
    .unwrap();
    let k = 1.5e6;
    let linear = CombinedSpring::linear(k).unwrap();
    let mu = 1785.0 / 2.0;
    let (f_exact, t_exact) = (
        30.0 * (k * mu).sqrt(),
        std::f64::consts::PI * (mu / k).sqrt(),
    );
    println!("| step [ms] | crush err | a_max err | a_mean err | contact err | linear: peak err | linear: duration err |");
    println!("|---|---|---|---|---|---|---|");
    for step_ms in [1.0, 0.5, 0.2, 0.1, 0.05, 0.02] {
        let s = run(&spring, step_ms * 1e-3, 0.1, &mut buf);
        let l = run(&linear, step_ms * 1e-3, 1.0, &mut buf);
        let rel = |a: f64, b: f64| 100.0 * (a / b - 1.0);
        println!(
            "| {step_ms} | {:+.4} % | {:+.4} % | {:+.4} % | {:+.4} % | {:+.5} % | {:+.5} % |",
            rel(s.vehicle.crush_m, reference.vehicle.crush_m),
            rel(s.vehicle.a_max_mps2, reference.vehicle.a_max_mps2),
            rel(s.vehicle.a_mean_mps2, reference.vehicle.a_mean_mps2),
            rel(s.contact_duration_s, reference.contact_duration_s),
            rel(l.peak_force_n, f_exact),
            rel(l.contact_duration_s, t_exact),
        );
    }
}
