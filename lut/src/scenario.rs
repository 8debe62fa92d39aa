//! A pre-crash situation → the ego compartment pulse (simulated ONCE, then reused for every
//! occupant evaluation of the optimiser).

use anyhow::{Context, Result};
use physics::{
    class_for_mass_kg,
    collision::{simulate_collision, CollisionInput, CollisionSummary, DefaultPulseBuffer},
    kph_to_mps, CombinedSpring, CompartmentPulse, MassClass,
};

/// *Default* ego vehicle of the characteristic diagram: the paper's Ford Taurus (1785 kg), whose
/// mass falls in class 4 (1750–2000 kg).
pub const DEFAULT_EGO_MASS_KG: f64 = 1785.0;
/// *Default* ego stiffness class.
pub const DEFAULT_EGO_CLASS: u8 = 4;

/// The ego vehicle (mass and stiffness class).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ego {
    /// Mass [kg].
    pub mass_kg: f64,
    /// Stiffness class.
    pub class: MassClass,
}

impl Default for Ego {
    fn default() -> Self {
        Ego {
            mass_kg: DEFAULT_EGO_MASS_KG,
            // 4 is a valid class number; the fallback keeps this panic-free anyway.
            class: MassClass::new(DEFAULT_EGO_CLASS).expect("class 4 exists"),
        }
    }
}

/// What the ego vehicle hits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Opponent {
    /// Rigid barrier (FMVSS 208 load cases).
    Barrier,
    /// Another car; its stiffness class is looked up from its mass (SPEC: a rough mass
    /// estimate is enough because curves within a class are similar).
    Car {
        /// Opponent mass [kg].
        mass_kg: f64,
    },
}

/// A predicted ego compartment pulse that owns its samples.
pub struct Pulse {
    buf: Box<DefaultPulseBuffer>,
    /// Collision summary of the prediction.
    pub summary: CollisionSummary,
    /// The closing speed it was predicted for [m/s].
    pub closing_mps: f64,
}

impl Pulse {
    /// Predict the pulse of `ego` hitting `opponent` at `closing_kph` (sum of both speeds; for a
    /// barrier the ego speed).
    pub fn predict(ego: &Ego, opponent: Opponent, closing_kph: f64) -> Result<Self> {
        let ego_curve = ego.class.curve();
        let (spring, opp_mass_kg) = match opponent {
            Opponent::Barrier => (CombinedSpring::series(ego_curve, None)?, f64::INFINITY),
            Opponent::Car { mass_kg } => {
                let class = class_for_mass_kg(mass_kg)
                    .with_context(|| format!("opponent mass {mass_kg} kg"))?;
                (
                    CombinedSpring::series(ego_curve, Some(class.curve()))?,
                    mass_kg,
                )
            }
        };
        let input = CollisionInput::with_defaults(
            &spring,
            ego.mass_kg,
            opp_mass_kg,
            kph_to_mps(closing_kph),
        );
        let mut buf = Box::new(DefaultPulseBuffer::new());
        let summary = simulate_collision(&input, &mut buf)
            .with_context(|| format!("collision at {closing_kph} km/h against {opponent:?}"))?;
        Ok(Pulse {
            buf,
            summary,
            closing_mps: kph_to_mps(closing_kph),
        })
    }

    /// The ego compartment pulse.
    pub fn ego(&self) -> CompartmentPulse<'_> {
        self.buf.ego_pulse()
    }

    /// The ego's crush at each sample of [`Self::ego`] [m].
    pub fn ego_crush_m(&self) -> &[f64] {
        self.buf.ego_crush_m()
    }
}
