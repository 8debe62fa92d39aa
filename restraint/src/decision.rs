//! The decision state machine: when to preset, arm, fire, release and fall back.
//!
//! ```text
//! Monitoring ──valid object, TTC < horizon, EBS ≥ no-fire──▶ PreCrash (preset, armed,
//!     ▲   ▲                                                  pretensioner at contact + t_pt)
//!     │   └──────── avoided (lost / receding / contact + margin passed): release, disarm
//!     │
//!  Degraded (stale/invalid inputs, E2E burst, no LUT): reference restraint
//!
//! any of the three ──accelerometer confirms──▶ Crash: airbag at max(confirm, contact + t_ab)
//!                                                        ──all fired──▶ PostCrash (latched)
//! ```
//!
//! Inputs are the estimate ([`Situation`], the looked-up plan), the input monitor's object
//! facts and crash confirmation, and whether the inputs are degraded; outputs are the phase,
//! the active plan and the pretensioner/airbag commands ([`Decision`]'s accessors).

use crate::config::{ms_to_ns, CycleConfig};
use crate::confirm::CrashDetector;
use crate::estimate::Situation;
use crate::plan::RestraintPlan;
use crate::signals::EcuMode;

/// Decision phase (what the state machine is doing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Inputs fine, no imminent collision.
    Monitoring,
    /// Collision predicted: settings preset, airbag armed, pretensioner at its planned time.
    PreCrash,
    /// Inputs degraded: the reference restraint is armed.
    Degraded,
    /// Crash confirmed by the accelerometer; fires pending.
    Crash,
    /// Everything commanded has fired (latched until restart).
    PostCrash,
}

impl Phase {
    /// The diagnostics mode of this phase.
    pub fn mode(self) -> EcuMode {
        match self {
            Self::Monitoring => EcuMode::Monitoring,
            Self::PreCrash => EcuMode::PreCrash,
            Self::Degraded => EcuMode::Degraded,
            Self::Crash => EcuMode::Crash,
            Self::PostCrash => EcuMode::PostCrash,
        }
    }
}

/// State of the reversible pretensioner as commanded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pretensioner {
    /// Not commanded.
    Idle,
    /// Fired (slack removed).
    Fired,
    /// Released after an avoided collision.
    Released,
}

/// What the state machine reads from the estimate and the input monitor in one cycle.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DecisionInputs<'d> {
    /// Any degrading reason is set.
    pub degraded: bool,
    /// Newest situation estimate (`None`: no object, no contact, or stale).
    pub situation: Option<Situation>,
    /// A new object sample arrived this cycle.
    pub new_object: bool,
    /// The newest object sample tracks an object.
    pub object_present: bool,
    /// Crash confirmation.
    pub detector: &'d CrashDetector,
}

/// State of the decision.
#[derive(Debug, Clone)]
pub struct Decision {
    horizon_ns: u64,
    exit_horizon_ns: u64,
    avoided_margin_ns: u64,
    reference: RestraintPlan,
    /// The preset plan (adaptive or reference).
    pub(crate) plan: RestraintPlan,
    crash_plan: RestraintPlan,
    phase: Phase,
    pretensioner: Pretensioner,
    pretensioner_at_ns: Option<u64>,
    airbag_fire_at_ns: Option<u64>,
    airbag_fired: bool,
    armed: bool,
    contact_ns: Option<u64>,
}

fn time_ms_to_ns(t_ms: f32) -> i64 {
    (f64::from(t_ms) * 1.0e6) as i64
}

fn at(base_ns: u64, offset_ms: f32) -> u64 {
    base_ns.saturating_add_signed(time_ms_to_ns(offset_ms))
}

impl Decision {
    /// Monitoring, reference restraint preset.
    pub fn new(cfg: &CycleConfig, reference: RestraintPlan) -> Self {
        let horizon_ns = ms_to_ns(cfg.preset_horizon_ms);
        Self {
            horizon_ns,
            exit_horizon_ns: horizon_ns.saturating_add(ms_to_ns(cfg.preset_exit_hysteresis_ms)),
            avoided_margin_ns: ms_to_ns(cfg.avoided_margin_ms),
            reference,
            plan: reference,
            crash_plan: reference,
            phase: Phase::Monitoring,
            pretensioner: Pretensioner::Idle,
            pretensioner_at_ns: None,
            airbag_fire_at_ns: None,
            airbag_fired: false,
            armed: false,
            contact_ns: None,
        }
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }
    /// The preset plan (adaptive or reference).
    pub fn plan(&self) -> RestraintPlan {
        self.plan
    }
    /// The plan latched at crash confirmation.
    pub fn crash_plan(&self) -> RestraintPlan {
        self.crash_plan
    }
    /// The reference restraint plan.
    pub fn reference_plan(&self) -> RestraintPlan {
        self.reference
    }
    /// Pretensioner state.
    pub fn pretensioner(&self) -> Pretensioner {
        self.pretensioner
    }
    /// Whether the airbag fire command has been given.
    pub fn airbag_fired(&self) -> bool {
        self.airbag_fired
    }
    /// Whether the airbag is armed.
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// The plan the commands carry in the current phase.
    pub fn active_plan(&self) -> RestraintPlan {
        match self.phase {
            Phase::Crash | Phase::PostCrash => self.crash_plan,
            Phase::PreCrash => self.plan,
            Phase::Monitoring | Phase::Degraded => self.reference,
        }
    }

    fn release_pretensioner(&mut self) {
        if self.pretensioner == Pretensioner::Fired {
            self.pretensioner = Pretensioner::Released;
        }
        self.pretensioner_at_ns = None;
    }

    fn enter_crash(&mut self, confirm_ns: u64, x: &DecisionInputs<'_>) {
        // Measured contact (accelerometer wake-up) is a better contact estimate than the
        // pre-crash TTC; fall back to the prediction, then to the confirmation instant.
        let contact = x
            .detector
            .onset_ns()
            .or(self.contact_ns)
            .unwrap_or(confirm_ns);
        let fresh_low_speed = x.situation.is_some_and(|s| {
            s.low_speed && s.contact_ns.abs_diff(contact) <= self.avoided_margin_ns
        });
        let plan = if self.phase == Phase::PreCrash && !x.degraded {
            self.plan
        } else if fresh_low_speed && !x.degraded {
            // Low-speed no-fire: belt per reference, no airbag.
            self.reference.without_airbag()
        } else {
            self.reference
        };
        self.crash_plan = plan;
        self.contact_ns = Some(contact);
        self.armed = true;
        if self.pretensioner != Pretensioner::Fired {
            self.pretensioner_at_ns = Some(at(contact, plan.pretensioner_time_ms).max(confirm_ns));
        }
        self.airbag_fire_at_ns = plan
            .airbag_fires()
            .then(|| at(contact, plan.airbag_time_ms).max(confirm_ns));
        self.phase = Phase::Crash;
    }

    /// One step of the state machine at `now`, then the scheduled fires that are due.
    pub(crate) fn step(&mut self, now: u64, x: &DecisionInputs<'_>) {
        if let (Some(confirm), Phase::Monitoring | Phase::PreCrash | Phase::Degraded) =
            (x.detector.confirmed_at_ns(), self.phase)
        {
            self.enter_crash(confirm, x);
        }
        match self.phase {
            Phase::Monitoring => {
                if x.degraded {
                    self.phase = Phase::Degraded;
                    self.armed = true;
                    self.plan = self.reference;
                } else if let Some(s) = x.situation.filter(|s| {
                    !s.low_speed
                        && s.contact_ns.saturating_sub(now) < self.horizon_ns
                        && s.contact_ns.saturating_add(self.avoided_margin_ns) > now
                }) {
                    self.phase = Phase::PreCrash;
                    self.armed = true;
                    self.contact_ns = Some(s.contact_ns);
                    self.schedule_precrash_pretensioner();
                }
            }
            Phase::PreCrash => {
                if x.degraded {
                    // Keep a fired pretensioner until the predicted contact has passed.
                    self.phase = Phase::Degraded;
                    self.plan = self.reference;
                    return;
                }
                let avoided = match x.situation {
                    None => x.new_object || !x.object_present,
                    Some(s) => {
                        s.low_speed
                            || s.contact_ns.saturating_sub(now) > self.exit_horizon_ns
                            || now > s.contact_ns.saturating_add(self.avoided_margin_ns)
                    }
                };
                if avoided {
                    self.phase = Phase::Monitoring;
                    self.armed = false;
                    self.release_pretensioner();
                    self.plan = self.reference;
                    self.contact_ns = None;
                } else if let Some(s) = x.situation {
                    self.contact_ns = Some(s.contact_ns);
                    self.schedule_precrash_pretensioner();
                }
            }
            Phase::Degraded => {
                // A pretensioner fired during PRE-CRASH is released once the predicted
                // contact plus margin has passed without a crash.
                if self.pretensioner == Pretensioner::Fired
                    && self
                        .contact_ns
                        .is_none_or(|c| now > c.saturating_add(self.avoided_margin_ns))
                {
                    self.release_pretensioner();
                    self.contact_ns = None;
                }
                if !x.degraded {
                    self.phase = Phase::Monitoring;
                    self.armed = false;
                    if self.pretensioner == Pretensioner::Fired {
                        self.release_pretensioner();
                    }
                }
            }
            Phase::Crash | Phase::PostCrash => {}
        }
        // Scheduled fires (pre-crash pretensioner, crash fires).
        if let Some(t) = self.pretensioner_at_ns {
            if now >= t {
                self.pretensioner = Pretensioner::Fired;
                self.pretensioner_at_ns = None;
            }
        }
        if let Some(t) = self.airbag_fire_at_ns {
            if now >= t {
                self.airbag_fired = true;
                self.airbag_fire_at_ns = None;
            }
        }
        if self.phase == Phase::Crash
            && self.pretensioner_at_ns.is_none()
            && self.airbag_fire_at_ns.is_none()
        {
            self.phase = Phase::PostCrash;
        }
    }

    /// In PRE-CRASH only a pre-crash (negative) pretensioner time fires before confirmation.
    fn schedule_precrash_pretensioner(&mut self) {
        if self.pretensioner == Pretensioner::Fired {
            return;
        }
        match self.contact_ns {
            Some(c) if self.plan.pretensioner_time_ms < 0.0 => {
                self.pretensioner_at_ns = Some(at(c, self.plan.pretensioner_time_ms));
            }
            _ => self.pretensioner_at_ns = None,
        }
    }
}
