//! Every modelling default of the physics in ONE place.
//!
//! Numbers here are *modelling choices* (SPEC.md "defaults"), not measured facts. Each constant
//! says where it comes from; change them here (and in physics/README.md's table) when a better
//! source turns up. The per-class stiffness curves live in `data/stiffness-classes.toml`.

/// Closed interval of admissible values of one quantity (used for optimiser bounds and input
/// validation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Lower end (inclusive).
    pub min: f64,
    /// Upper end (inclusive).
    pub max: f64,
}

impl Bounds {
    /// True when `value` is finite and inside the interval.
    pub fn contains(&self, value: f64) -> bool {
        value.is_finite() && value >= self.min && value <= self.max
    }
    /// Clamp into the interval; NaN maps to `min` so callers never propagate NaN.
    pub fn clamp(&self, value: f64) -> f64 {
        if value.is_nan() {
            self.min
        } else {
            value.clamp(self.min, self.max)
        }
    }
}

/// Standard gravity [m/s²] (ISO 80000-3), used to express accelerations in g.
pub const STANDARD_GRAVITY_MPS2: f64 = 9.806_65;

// ---------------------------------------------------------------- collision model

/// Coefficient of restitution of the car-to-car contact. SPEC: e = 0.1 at medium/high speed.
pub const RESTITUTION: f64 = 0.1;
/// Fixed integration step [s]. 0.1 ms keeps crush / peak errors < 0.1 % (README "accuracy vs
/// step") and matches the Python prototype named in SPEC.
pub const STEP_S: f64 = 1.0e-4;
/// Length of the predicted compartment pulse [s]: covers the whole contact phase (~80–90 ms at
/// the paper's worst case) plus the occupant's ride-down after separation.
pub const PULSE_DURATION_S: f64 = 0.150;
/// Sample capacity of [`crate::collision::DefaultPulseBuffer`]: 150 ms at 0.1 ms plus margin.
pub const PULSE_CAPACITY: usize = 2048;
/// Admissible restitution coefficients.
pub const RESTITUTION_BOUNDS: Bounds = Bounds { min: 0.0, max: 1.0 };
/// Admissible integration steps [s] (1 µs … 5 ms).
pub const STEP_BOUNDS_S: Bounds = Bounds {
    min: 1.0e-6,
    max: 5.0e-3,
};
/// Longest contact phase we integrate before declaring the input unphysical [s].
pub const MAX_CONTACT_S: f64 = 2.0;

// ---------------------------------------------------------------- published ranges (SPEC Table 2)

/// Closing speed per vehicle the method is meant for [km/h]; below: no-fire, above: no crush data.
pub const SPEED_PER_VEHICLE_KPH: Bounds = Bounds {
    min: 20.0,
    max: 54.0,
};
/// Opponent mass range of the paper [kg].
pub const OPPONENT_MASS_KG: Bounds = Bounds {
    min: 800.0,
    max: 3000.0,
};
/// Occupant mass range of the paper [kg].
pub const OCCUPANT_MASS_KG: Bounds = Bounds {
    min: 30.0,
    max: 125.0,
};
/// Reference occupant of the paper's studies and FMVSS 208 [kg].
pub const OCCUPANT_MASS_REFERENCE_KG: f64 = 75.0;

// ---------------------------------------------------------------- occupant and restraint model

/// Chest to steering wheel / airbag module distance D [m] (seat position). SPEC default 300 mm.
pub const CHEST_TO_WHEEL_M: f64 = 0.300;
/// Admissible chest-to-wheel distances [m] (SPEC 200–450 mm).
pub const CHEST_TO_WHEEL_BOUNDS_M: Bounds = Bounds {
    min: 0.200,
    max: 0.450,
};
/// Compressed airbag module thickness [m]: available ride-down = D − this. SPEC default 60 mm.
pub const MODULE_THICKNESS_M: f64 = 0.060;
/// Belt slack before engagement [m] (SPEC default 25 mm).
pub const BELT_SLACK_M: f64 = 0.025;
/// Lumped belt stiffness, shoulder + lap [N/m] (SPEC default 150 kN/m).
pub const BELT_STIFFNESS_N_PER_M: f64 = 150.0e3;
/// Time the pretensioner needs to remove all slack after its trigger [s] (SPEC ~10 ms).
pub const PRETENSIONER_DURATION_S: f64 = 0.010;
/// Airbag + steering column force per penetration [N/m] (SPEC default 200 kN/m).
pub const AIRBAG_STIFFNESS_N_PER_M: f64 = 200.0e3;
/// Maximum bag depth measured from the wheel [m] (SPEC default up to 280 mm), bounded by D.
pub const AIRBAG_DEPTH_M: f64 = 0.280;
/// Time from airbag trigger to full inflation [s] (SPEC ~30 ms); depth grows linearly.
pub const AIRBAG_INFLATION_S: f64 = 0.030;
/// Seat friction coefficient μ, force μ·m·g (SPEC default 0.3).
pub const SEAT_FRICTION_COEFF: f64 = 0.3;
/// Relative speed over which seat friction ramps from 0 to μ·m·g [m/s]. Regularises the
/// Coulomb law so that the fixed-step integrator does not chatter around zero speed.
pub const SEAT_FRICTION_REGULARISATION_MPS: f64 = 0.05;
/// Stiffness of the chest-to-wheel/dash contact after bottoming out [N/m] ("very stiff").
pub const BOTTOMING_STIFFNESS_N_PER_M: f64 = 5.0e6;
/// Seat-back stiffness for rearward occupant motion [N/m] (keeps rebound bounded).
pub const SEATBACK_STIFFNESS_N_PER_M: f64 = 100.0e3;
/// Longest occupant simulation [s]: pulse length plus ride-down until maximum excursion.
pub const OCCUPANT_MAX_SIM_S: f64 = 0.300;

// ---------------------------------------------------------------- optimisation variables

/// Belt load-limiter level, lumped [N] (SPEC range 1–12 kN).
pub const LOAD_LIMITER_BOUNDS_N: Bounds = Bounds {
    min: 1.0e3,
    max: 12.0e3,
};
/// Airbag + column force level [N] (SPEC range 0 = no fire … 12 kN).
pub const AIRBAG_FORCE_BOUNDS_N: Bounds = Bounds {
    min: 0.0,
    max: 12.0e3,
};
/// Pretensioner trigger time relative to first contact [s] (pre-crash allowed).
pub const PRETENSIONER_TIME_BOUNDS_S: Bounds = Bounds {
    min: -0.100,
    max: 0.020,
};
/// Airbag trigger time relative to first contact [s] (not before crash confirmation).
pub const AIRBAG_TIME_BOUNDS_S: Bounds = Bounds {
    min: 0.003,
    max: 0.040,
};
/// Fire time of the conventional reference restraint after contact [s] (paper: 10 ms).
pub const REFERENCE_FIRE_TIME_S: f64 = 0.010;
