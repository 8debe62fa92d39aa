//! A restraint plan (levels + trigger times) and where it came from.

use diagram::{AirbagStage, AirbagThresholds, Lookup};

/// The conventional reference restraint as numbers (the shell reads them from
/// `data/reference-restraint.toml`; levels kN, times ms relative to first contact): physics'
/// one type, the file's own.
pub use physics::ReferenceSettings;

/// Where the settings of a plan came from (sent as `CmdSource` on CAN).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlanSource {
    /// Interpolated from the characteristic diagram for the predicted situation.
    Adaptive,
    /// The conventional reference restraint (fallback, or situation outside the table).
    Reference,
}

/// Restraint settings to apply. Times relative to first contact, ms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestraintPlan {
    /// Belt load-limiter level, kN.
    pub belt_limiter_kn: f32,
    /// Airbag / column force level, kN (0 when `airbag_stage` is `NoFire`).
    pub airbag_level_kn: f32,
    /// Discrete inflator decision.
    pub airbag_stage: AirbagStage,
    /// Pretensioner trigger, ms relative to contact (negative = pre-crash, reversible).
    pub pretensioner_time_ms: f32,
    /// Airbag trigger, ms after contact (never before crash confirmation).
    pub airbag_time_ms: f32,
    /// Source of the belt's numbers (pretensioner and load limiter).
    pub source: PlanSource,
    /// Source of the airbag's numbers: the belt's, or the reference restraint's airbag a
    /// belt-only plan gets when the measured pulse proves the crash must-fire
    /// ([`Self::with_airbag_of`]).
    pub airbag_source: PlanSource,
}

impl RestraintPlan {
    /// The conventional reference restraint (levels kN, times ms), its stage derived with
    /// the same thresholds as the LUT's (so a reference level below the no-fire threshold
    /// does not fire).
    pub fn reference(
        belt_limiter_kn: f32,
        airbag_level_kn: f32,
        pretensioner_time_ms: f32,
        airbag_time_ms: f32,
        thresholds: &AirbagThresholds,
    ) -> Self {
        let stage = thresholds.stage(airbag_level_kn);
        Self {
            belt_limiter_kn,
            airbag_level_kn: if stage == AirbagStage::NoFire {
                0.0
            } else {
                airbag_level_kn
            },
            airbag_stage: stage,
            pretensioner_time_ms,
            airbag_time_ms,
            source: PlanSource::Reference,
            airbag_source: PlanSource::Reference,
        }
    }

    /// From the reference-restraint settings.
    pub fn from_reference_settings(r: &ReferenceSettings, thresholds: &AirbagThresholds) -> Self {
        Self::reference(
            r.belt_limiter_kn as f32,
            r.airbag_level_kn as f32,
            r.pretensioner_time_ms as f32,
            r.airbag_time_ms as f32,
            thresholds,
        )
    }

    /// From one LUT interpolation with the table's airbag thresholds.
    ///
    /// **Between firing and non-firing cells the airbag fires** at the lowest firing level: an
    /// interpolated level above 0 but under `no_fire_below_kn` means at least one corner cell
    /// fires the bag (no-fire cells store 0 kN). Those cells sit on their ride-down constraint
    /// (the optimum uses the ride-down up to the reserve), and the interpolated belt settings
    /// without the bag can overshoot it: over the default table with opponents misreported by
    /// ±1200 kg (`mass_misreport_kg` planning), the occupant bottomed out where the reference
    /// restraint did not in 39 of 29 862 cases without the bag and in 2 with it, at an
    /// unchanged mean outcome (README "Robust planning").
    pub fn from_lookup(l: &Lookup, thresholds: &AirbagThresholds) -> Self {
        let straddles = !l.airbag_fires() && l.values.airbag_level_kn > 0.0;
        let (level, stage) = if straddles {
            let level = thresholds.no_fire_below_kn;
            (level, thresholds.stage(level))
        } else {
            (l.airbag_command_kn(), l.airbag_stage)
        };
        Self {
            belt_limiter_kn: l.values.belt_limiter_kn,
            airbag_level_kn: level,
            airbag_stage: stage,
            pretensioner_time_ms: l.values.pretensioner_time_ms,
            airbag_time_ms: l.values.airbag_time_ms,
            source: PlanSource::Adaptive,
            airbag_source: PlanSource::Adaptive,
        }
    }

    /// The same plan without airbag deployment (low-speed no-fire).
    pub fn without_airbag(mut self) -> Self {
        self.airbag_stage = AirbagStage::NoFire;
        self.airbag_level_kn = 0.0;
        self
    }

    /// The same belt settings with `other`'s airbag (level, stage and time): the airbag a
    /// belt-only plan gets when the measured pulse proves the crash must-fire.
    pub fn with_airbag_of(mut self, other: &Self) -> Self {
        self.airbag_stage = other.airbag_stage;
        self.airbag_level_kn = other.airbag_level_kn;
        self.airbag_time_ms = other.airbag_time_ms;
        self.airbag_source = other.airbag_source;
        self
    }

    /// True if the airbag is to be fired.
    pub fn airbag_fires(&self) -> bool {
        self.airbag_stage != AirbagStage::NoFire
    }
}
