//! The crash modes' pulses side by side: the paper's Taurus class (1 785 kg, class 4) in each
//! mode at the speeds of the crash-sensing matrix, with each pulse's peak, its time, the
//! contact's duration, the x velocity change and the airbag's required fire time
//! ("127 mm − 30 ms"). `cargo run -p physics --release --example crash_modes`.

use physics::crash_mode::{odb_face_curve, CrashMode, DEFAULT_WIDTH_M};
use physics::{
    class_for_mass_kg, deadline, defaults, simulate_collision, CollisionInput, CombinedSpring,
    DefaultPulseBuffer, PhysicsError,
};

fn main() -> Result<(), PhysicsError> {
    let ego_kg = 1785.0;
    let class = class_for_mass_kg(ego_kg)?.curve();
    let odb = odb_face_curve(0.4 * DEFAULT_WIDTH_M)?;
    let angle = CrashMode::Angular {
        angle_rad: 30f64.to_radians(),
    };
    let offset = CrashMode::Offset { overlap: 0.4 };
    let cases = [
        (
            "full frontal, rigid wall",
            CrashMode::FullFrontal,
            56.0,
            None,
            f64::INFINITY,
        ),
        (
            "full frontal, rigid wall",
            CrashMode::FullFrontal,
            40.0,
            None,
            f64::INFINITY,
        ),
        (
            "full frontal, rigid wall",
            CrashMode::FullFrontal,
            16.0,
            None,
            f64::INFINITY,
        ),
        (
            "40 % offset deformable barrier",
            offset,
            64.0,
            Some(odb),
            f64::INFINITY,
        ),
        (
            "40 % offset deformable barrier",
            offset,
            40.0,
            Some(odb),
            f64::INFINITY,
        ),
        (
            "40 % offset deformable barrier",
            offset,
            24.0,
            Some(odb),
            f64::INFINITY,
        ),
        ("30° angled rigid wall", angle, 32.0, None, f64::INFINITY),
        (
            "centre pole (254 mm)",
            CrashMode::Pole,
            32.0,
            None,
            f64::INFINITY,
        ),
        (
            "centre pole (254 mm)",
            CrashMode::Pole,
            20.0,
            None,
            f64::INFINITY,
        ),
        (
            "underride, 12 t truck standing",
            CrashMode::Underride,
            40.0,
            None,
            12_000.0,
        ),
    ];
    println!(
        "{:32} {:>6} {:>14} {:>12} {:>11} {:>12}",
        "mode", "km/h", "peak g (at ms)", "contact ms", "Δv_x m/s", "required ms"
    );
    for (name, mode, kph, face, opp_kg) in cases {
        let e = mode.engage(class, DEFAULT_WIDTH_M)?;
        let spring = CombinedSpring::series(&e.curve, face.as_ref())?;
        let mut input =
            CollisionInput::with_defaults(&spring, ego_kg, opp_kg, kph / 3.6 * e.axis_cos);
        input.duration_s = 0.2;
        let mut pulse = Box::new(DefaultPulseBuffer::new());
        let s = simulate_collision(&input, &mut pulse)?;
        pulse.project_ego_onto_axis(e.axis_cos);
        let (k, peak) = pulse
            .ego_accel_mps2()
            .iter()
            .enumerate()
            .fold((0, 0.0), |m, (k, a)| if -a > m.1 { (k, -a) } else { m });
        let required = deadline::required_fire_s(&pulse.ego_pulse())
            .map_or("—".to_owned(), |t| format!("{:.1}", t * 1e3));
        println!(
            "{name:32} {kph:>6.0} {:>6.1} ({:>5.1}) {:>12.1} {:>11.2} {required:>12}",
            peak / defaults::STANDARD_GRAVITY_MPS2,
            k as f64 * pulse.step_s() * 1e3,
            s.contact_duration_s * 1e3,
            s.vehicle.delta_v_mps * e.axis_cos,
        );
    }
    Ok(())
}
