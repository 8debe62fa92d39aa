//! The estimate: what the object track says about the coming collision, and what the
//! restraint should do about it.
//!
//! Per new object sample: the track filter ([`track`]: distance, closing speed and closing
//! acceleration, latency-corrected, outliers gated, opponent mass fused) → time to contact,
//! closing speed at contact and opponent mass with their σ at the cycle's time
//! ([`Situation`]) → the characteristic-diagram query ([`Lut`]) → the plan. That is the
//! decision's path, done in the sample's cycle.
//!
//! The collision prediction in closed form ([`physics::ExactCollision`]: no step size) and
//! its diagnostics pulse ([`pulse`]) are not on that path — no decision reads them; the
//! diagnostics and the crash-phase work do — so they run in the following cycles that have
//! time ([`Estimator::background`]: cycles without a new sample, outside CRASH): the pending
//! prediction first (≈ 1 100 instructions), then the pulse a chunk per cycle. With object
//! samples ≥ 5 ms apart the prediction of a sample is there 1 ms after it. Everything is
//! built in [`Estimator::new`]; nothing here allocates.

pub mod pulse;
pub mod track;

use diagram::{AirbagThresholds, DiagramView, Query};
use physics::{CollisionInput, CollisionSummary, CombinedSpring, ExactCollision, MassClass};

use crate::config::CycleConfig;
use crate::counters::CycleCounters;
use crate::inputs::{InputMonitor, V2xStation};
use crate::plan::RestraintPlan;
use crate::settings::ms_to_ns;
use crate::settings::ConfigError;
use pulse::DiagnosticsPulse;
use track::{TrackEstimate, TrackEvent, TrackFilter};

/// Predicted contact of a constant-relative-acceleration approach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Time from the measurement to first contact, s (≥ 0).
    pub ttc_s: f64,
    /// Closing speed at contact, m/s (≥ 0).
    pub closing_speed_mps: f64,
}

/// Time to contact from distance `d` (m), closing speed `v` (m/s, positive approaching) and
/// relative acceleration `a` (m/s², rate of change of the closing speed): the smallest
/// t ≥ 0 with d − v t − ½ a t² = 0, i.e. t = 2d / (v + √(v² + 2ad)) (the cancellation-free
/// form of the quadratic root; exact for a = 0: t = d/v). `None` when the object stops
/// closing before it reaches us (v² + 2ad < 0), recedes, or any input is not finite.
/// d ≤ 0 means contact now at the current closing speed.
pub fn time_to_contact(d_m: f64, v_mps: f64, a_mps2: f64) -> Option<Contact> {
    if !(d_m.is_finite() && v_mps.is_finite() && a_mps2.is_finite()) {
        return None;
    }
    if d_m <= 0.0 {
        return (v_mps > 0.0).then_some(Contact {
            ttc_s: 0.0,
            closing_speed_mps: v_mps,
        });
    }
    let disc = v_mps * v_mps + 2.0 * a_mps2 * d_m;
    if !(disc >= 0.0) {
        return None;
    }
    let v_contact = libm::sqrt(disc);
    // Receding (v ≤ 0) with positive acceleration still reaches us on the "+" root only if
    // v + √disc > 0; the v < 0 branch is the object turning around and coming back, which a
    // tracker would report as a new approach: treat as no contact now.
    if v_mps <= 0.0 {
        return None;
    }
    let denom = v_mps + v_contact;
    if !(denom > 0.0) {
        return None;
    }
    let t = 2.0 * d_m / denom;
    (t.is_finite() && t >= 0.0).then_some(Contact {
        ttc_s: t,
        closing_speed_mps: v_contact,
    })
}

/// The characteristic diagram as the core needs it: the borrowed, validated view plus the
/// header facts the shell read from the file.
#[derive(Debug, Clone, Copy)]
pub struct Lut<'a> {
    /// Allocation-free interpolation.
    pub view: DiagramView<'a>,
    /// Id sent in the heartbeat (`EcuStatus.LutId`).
    pub id: u16,
    /// Ego vehicle mass the table was optimised for, kg.
    pub ego_mass_kg: f32,
    /// Ego stiffness class the table was optimised for.
    pub ego_class: u8,
    /// The planning margin the table's cells are verified for (its header's
    /// `robust.lighter_opponent_kg`): a plan up to this much heavier than the true opponent
    /// does not bottom the occupant out where the reference does not. `None`: the table states
    /// none (no claim, accepted); NaN: it states one the shell could not read (rejected).
    pub lighter_opponent_kg: Option<f32>,
}

/// Why a LUT was rejected at start-up (the ECU then runs DEGRADED on the reference restraint).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LutMismatch {
    /// Optimised for another car than the configured one.
    Ego {
        /// The table's ego mass, kg.
        table_mass_kg: f32,
        /// The table's ego class.
        table_class: u8,
        /// The configured ego mass, kg.
        config_mass_kg: f64,
        /// The configured ego class.
        config_class: u8,
    },
    /// Verified for plans less heavy than the truth than the configured margins make them.
    Margin {
        /// The span the table states, kg (NaN: unreadable).
        lighter_opponent_kg: f32,
        /// The span the configuration needs, kg: 2 × `mass_misreport_kg`, or
        /// `mass_misreport_kg` + `v2x_mass_margin_kg` if more.
        needed_kg: f64,
    },
}

impl core::fmt::Display for LutMismatch {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Ego {
                table_mass_kg,
                table_class,
                config_mass_kg,
                config_class,
            } => write!(
                f,
                "LUT is for ego {table_mass_kg} kg class {table_class}, ECU configured for \
                 {config_mass_kg} kg class {config_class}: LUT rejected, DEGRADED (reference \
                 restraint)"
            ),
            Self::Margin {
                lighter_opponent_kg,
                needed_kg,
            } => write!(
                f,
                "LUT is verified for plans up to {lighter_opponent_kg} kg heavier than the \
                 opponent (robust.lighter_opponent_kg), the ECU's planning margins need \
                 {needed_kg} kg (2 × mass_misreport_kg, or mass_misreport_kg + \
                 v2x_mass_margin_kg): LUT rejected, DEGRADED (reference restraint)"
            ),
        }
    }
}

/// `lut` if it was optimised for the configured ego vehicle (class equal, mass within 1 %):
/// its cells are optimal for that car only; and if the planning margin its cells are verified
/// for covers the configured margins — with one mass source off by up to `mass_misreport_kg`
/// either way the plan is up to twice that heavier than the truth, with a V2X station up to
/// `mass_misreport_kg` + `v2x_mass_margin_kg`. A mismatch drops it and says why.
pub fn check_lut<'a>(
    cfg: &CycleConfig,
    lut: Option<Lut<'a>>,
) -> (Option<Lut<'a>>, Option<LutMismatch>) {
    let Some(l) = lut else {
        return (None, None);
    };
    let rel = (f64::from(l.ego_mass_kg) - cfg.ego_mass_kg).abs() / cfg.ego_mass_kg;
    if l.ego_class != cfg.ego_class || rel > 0.01 {
        let m = LutMismatch::Ego {
            table_mass_kg: l.ego_mass_kg,
            table_class: l.ego_class,
            config_mass_kg: cfg.ego_mass_kg,
            config_class: cfg.ego_class,
        };
        return (None, Some(m));
    }
    if let Some(span_kg) = l.lighter_opponent_kg {
        let needed_kg =
            (2.0 * cfg.mass_misreport_kg).max(cfg.mass_misreport_kg + cfg.v2x_mass_margin_kg);
        // NaN-safe: an unreadable span (NaN) covers nothing. 0.5 kg: the span is stored as
        // text and read as f32.
        if !(needed_kg <= f64::from(span_kg) + 0.5) {
            let m = LutMismatch::Margin {
                lighter_opponent_kg: span_kg,
                needed_kg,
            };
            return (None, Some(m));
        }
    }
    (Some(l), None)
}

/// The estimated situation: the track's contact estimate at the cycle's time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Situation {
    /// The contact instant the decision plans with: estimate − k·σ
    /// (`track.contact_time_k`), CLOCK_MONOTONIC ns.
    pub contact_ns: u64,
    /// The estimated contact instant, CLOCK_MONOTONIC ns.
    pub contact_estimate_ns: u64,
    /// σ of the contact instant, s.
    pub contact_sigma_s: f64,
    /// Closing speed at contact, m/s.
    pub closing_speed_mps: f64,
    /// σ of the closing speed at contact, m/s.
    pub closing_speed_sigma_mps: f64,
    /// Conservative opponent mass m + k·σ (`conservative_mass_k`), kg: the prediction's and
    /// the LUT's.
    pub opponent_mass_kg: f64,
    /// Fused opponent mass estimate, kg.
    pub opponent_mass_estimate_kg: f64,
    /// σ of the fused opponent mass, kg.
    pub opponent_mass_sigma_kg: f64,
    /// The mass the V2X station reports for itself, kg, when its frame is fresh and it is the
    /// tracked object (`v2x_gate_*`): the second, independent mass source of the planning mass.
    pub v2x_mass_kg: Option<f64>,
    /// Ego equivalent barrier speed, km/h.
    pub ebs_kph: f64,
    /// Below the occupant's no-fire line (`CycleConfig::no_fire_line_kph`).
    pub low_speed: bool,
    /// The object stands (its closing speed is the ego's own within
    /// [`crate::inputs::STANDING_SPEED_MPS`]; `false` when the ego's speed is unknown): a
    /// wall, a pole, a tree or a parked vehicle, whose mass the object sensor cannot weigh (it
    /// reports a default).
    pub opponent_standing: bool,
}

/// The spring of the opponent class of `opp_kg` (by mass; beyond the heaviest class the
/// heaviest) among the six precomputed ones: its index.
fn spring_index(opp_kg: f64) -> usize {
    let class = physics::class_for_mass_kg(opp_kg)
        .map(MassClass::number)
        .unwrap_or(6);
    usize::from(class.saturating_sub(1))
}

/// State of the estimate: track, situation, prediction (springs, kept solution, diagnostics
/// pulse) and the LUT.
#[derive(Clone)]
pub struct Estimator<'a> {
    ego_mass_kg: f64,
    conservative_mass_k: f64,
    contact_time_k: f64,
    mass_misreport_kg: f64,
    v2x_mass_margin_kg: f64,
    v2x_gate_distance_m: f64,
    v2x_gate_speed_mps: f64,
    exit_horizon_ns: u64,
    springs: [Option<CombinedSpring>; 6],
    track: TrackFilter,
    solution: ExactCollision,
    /// The prediction the newest situation asks for, not yet solved: (spring index,
    /// conservative opponent kg, closing speed m/s).
    pending: Option<(usize, f64, f64)>,
    pulse: DiagnosticsPulse,
    lut: Option<Lut<'a>>,
    reference: RestraintPlan,
    /// Newest situation estimate.
    pub(crate) situation: Option<Situation>,
    /// Newest collision prediction.
    pub(crate) summary: Option<CollisionSummary>,
}

impl<'a> Estimator<'a> {
    /// Precomputes the six combined springs (ego class × opponent class); `lut` has passed
    /// [`check_lut`].
    pub fn new(
        cfg: &CycleConfig,
        lut: Option<Lut<'a>>,
        reference: RestraintPlan,
    ) -> Result<Self, ConfigError> {
        let class_error = ConfigError {
            key: "ego_class",
            value: f64::from(cfg.ego_class),
            lo: 1.0,
            hi: 6.0,
        };
        let ego_class = MassClass::new(cfg.ego_class).map_err(|_| class_error)?;
        let mut springs = [None; 6];
        for (i, s) in springs.iter_mut().enumerate() {
            let opp = MassClass::new(i as u8 + 1).map_err(|_| class_error)?;
            *s = CombinedSpring::series(ego_class.curve(), Some(opp.curve())).ok();
        }
        let horizon_ns = ms_to_ns(cfg.preset_horizon_ms);
        Ok(Self {
            ego_mass_kg: cfg.ego_mass_kg,
            conservative_mass_k: cfg.conservative_mass_k,
            contact_time_k: cfg.track.contact_time_k,
            mass_misreport_kg: cfg.mass_misreport_kg,
            v2x_mass_margin_kg: cfg.v2x_mass_margin_kg,
            v2x_gate_distance_m: cfg.v2x_gate_distance_m,
            v2x_gate_speed_mps: cfg.v2x_gate_speed_mps,
            exit_horizon_ns: horizon_ns.saturating_add(ms_to_ns(cfg.preset_exit_hysteresis_ms)),
            springs,
            track: TrackFilter::new(&cfg.track, cfg.object_timeout_ms),
            solution: ExactCollision::new(),
            pending: None,
            pulse: DiagnosticsPulse::new(),
            lut,
            reference,
            situation: None,
            summary: None,
        })
    }

    /// The airbag thresholds of the LUT in use (the defaults without one).
    pub fn thresholds(lut: Option<&Lut<'_>>) -> AirbagThresholds {
        lut.map_or(AirbagThresholds::DEFAULT, |l| l.view.thresholds())
    }

    /// The LUT in use (`None`: missing or rejected).
    pub fn lut(&self) -> Option<&Lut<'a>> {
        self.lut.as_ref()
    }

    /// The combined crush spring of the ego against an opponent of `opp_kg` (its class by
    /// mass; beyond the heaviest class the heaviest). `None` only if a class curve failed to
    /// combine at start-up.
    pub(crate) fn spring_for(&self, opp_kg: f64) -> Option<&CombinedSpring> {
        self.springs
            .get(spring_index(opp_kg))
            .and_then(Option::as_ref)
    }

    /// The configured ego mass, kg.
    pub(crate) fn ego_mass_kg(&self) -> f64 {
        self.ego_mass_kg
    }

    /// The track filter.
    pub fn track(&self) -> &TrackFilter {
        &self.track
    }

    /// The newest prediction's diagnostics pulse: ego acceleration, m/s², at
    /// k · [`pulse::PULSE_DT_S`] after contact, and how many points are valid yet.
    pub(crate) fn pulse(&self) -> (&[f32; crate::signals::PULSE_POINTS], usize) {
        (self.pulse.points(), self.pulse.filled())
    }

    /// The work no decision waits for, in a cycle that has time: the pending prediction if
    /// there is one, else the next chunk of its diagnostics pulse (nothing once complete).
    #[inline(always)]
    pub(crate) fn background(&mut self, counters: &mut CycleCounters) {
        match self.pending.take() {
            Some((spring, opp_kg, closing_mps)) => {
                self.predict(spring, opp_kg, closing_mps, counters);
            }
            None => self.pulse.fill(&self.solution),
        }
    }

    /// The situation from the track: a new object sample goes into the track filter first (a
    /// refused sample changes nothing). Looks the LUT up and asks for a prediction
    /// ([`Self::background`]) when contact is within the exit horizon. Returns the plan when
    /// one was looked up. Called only when a new sample (or a changed occupant) arrived;
    /// `no_fire_ebs_kph`: the occupant's no-fire line (`CycleConfig::no_fire_line_kph`).
    #[inline(always)]
    pub(crate) fn update(
        &mut self,
        now: u64,
        inputs: &InputMonitor,
        no_fire_ebs_kph: f64,
        counters: &mut CycleCounters,
    ) -> Option<RestraintPlan> {
        if inputs.new_object {
            let o = &inputs.object;
            if !o.is_valid() {
                self.track.end(); // the sensor reports no object: this track is over
            }
            if !inputs.object_present || inputs.object_invalid {
                self.situation = None;
                return None;
            }
            match self.track.update(o) {
                TrackEvent::Updated => {}
                TrackEvent::Started => {
                    counters.track_starts = counters.track_starts.saturating_add(1);
                }
                TrackEvent::Outlier => {
                    counters.track_outliers = counters.track_outliers.saturating_add(1);
                }
                TrackEvent::Refused(_) => {
                    // Nothing new: the situation and plan of the last sample stand.
                    counters.track_refused = counters.track_refused.saturating_add(1);
                    return None;
                }
            }
        } else if !inputs.object_present || inputs.object_invalid {
            self.situation = None;
            return None;
        }
        let Some(e) = self.track.estimate_at(now) else {
            self.situation = None; // no track, or it does not reach us
            return None;
        };
        let station = inputs
            .v2x_station(now)
            .filter(|st| self.is_tracked_object(&e, st));
        let sit = self.situation_of(&e, station, no_fire_ebs_kph, inputs.object_standing);
        self.situation = Some(sit);
        // Predict only what can become relevant before the next sample: contact within the
        // exit horizon (bounds the work to objects that matter).
        if sit.contact_estimate_ns.saturating_sub(now) > self.exit_horizon_ns || sit.low_speed {
            return None;
        }
        // Opponent class by the conservative mass; beyond the classes, the heaviest.
        let spring = spring_index(sit.opponent_mass_kg);
        self.pending = Some((spring, sit.opponent_mass_kg, sit.closing_speed_mps));
        Some(self.lookup(&sit, inputs, counters))
    }

    /// Whether the V2X station is the tracked object: its GNSS range, carried forward from its
    /// frame's reception to the estimate's time at its closing speed, and its closing speed
    /// agree with the track's within the gates. A wrong pairing matters only together with a
    /// second fault: the planning mass takes the heavier source.
    fn is_tracked_object(&self, e: &TrackEstimate, st: &V2xStation) -> bool {
        let age_s = e.at_ns.saturating_sub(st.rx_ns) as f64 * 1.0e-9;
        let range_now_m = st.range_m - st.closing_speed_mps * age_s;
        (range_now_m - e.distance_m).abs() <= self.v2x_gate_distance_m
            && (st.closing_speed_mps - e.closing_speed_mps).abs() <= self.v2x_gate_speed_mps
    }

    /// The situation of a track estimate (`station`: the V2X station that is the tracked
    /// object, if any; `no_fire_ebs_kph`: the occupant's no-fire line; `standing`: the object
    /// stands, [`Situation::opponent_standing`]).
    fn situation_of(
        &self,
        e: &TrackEstimate,
        station: Option<&V2xStation>,
        no_fire_ebs_kph: f64,
        standing: bool,
    ) -> Situation {
        let to_ns = |t_s: f64| (t_s * 1.0e9) as u64; // saturating, NaN → 0
        let contact_estimate_ns = e.at_ns.saturating_add(to_ns(e.contact.ttc_s));
        let early_ns = to_ns(self.contact_time_k * e.ttc_sigma_s);
        let opp_kg = e.mass_kg + self.conservative_mass_k * e.mass_sigma_kg;
        let v = e.contact.closing_speed_mps;
        let ebs_kph = physics::equivalent_barrier_speed_kph(v, self.ego_mass_kg, opp_kg);
        Situation {
            contact_ns: contact_estimate_ns.saturating_sub(early_ns),
            contact_estimate_ns,
            contact_sigma_s: e.ttc_sigma_s,
            closing_speed_mps: v,
            closing_speed_sigma_mps: e.closing_speed_sigma_mps,
            opponent_mass_kg: opp_kg,
            opponent_mass_estimate_kg: e.mass_kg,
            opponent_mass_sigma_kg: e.mass_sigma_kg,
            v2x_mass_kg: station.map(|st| st.mass_kg),
            ebs_kph,
            low_speed: !(ebs_kph >= no_fire_ebs_kph),
            opponent_standing: standing,
        }
    }

    /// Solves the collision of the opponent `spring` (index of the six combined springs).
    #[inline(always)]
    fn predict(&mut self, spring: usize, opp_kg: f64, closing_mps: f64, c: &mut CycleCounters) {
        c.predictions = c.predictions.saturating_add(1);
        let Some(spring) = self.springs.get(spring).and_then(Option::as_ref) else {
            self.summary = None;
            self.pulse.clear();
            c.prediction_errors = c.prediction_errors.saturating_add(1);
            return;
        };
        let input = CollisionInput::with_defaults(spring, self.ego_mass_kg, opp_kg, closing_mps);
        match self.solution.solve_in_place(&input) {
            Ok(s) => {
                self.summary = Some(*s);
                self.pulse.restart();
            }
            Err(_) => {
                self.summary = None;
                self.pulse.clear();
                c.prediction_errors = c.prediction_errors.saturating_add(1);
            }
        }
    }

    /// LUT plan for the situation; the reference plan when the LUT is missing, the occupant
    /// is outside what the table covers (unbelted, not an adult, no data), or any query
    /// axis is out of the table's range or NaN (the diagram's rule: a flagged lookup is
    /// degraded input).
    ///
    /// **Robust planning mass**: the table is queried at the situation's conservative mass
    /// raised to the track's fused mass estimate + `mass_misreport_kg`, capped at the table's heaviest
    /// opponent. The opponent's mass does not show in the ego pulse before the restraint is
    /// committed (`crash_match`), so the plan must already hold the heaviest opponent the
    /// sensing could be wrong about; where even the conservative mass is beyond the table, the
    /// lookup stays out of range (reference restraint). With a second, independent source — the
    /// V2X station that is the tracked object — the heavier of the two + `v2x_mass_margin_kg`
    /// instead: a single fault makes one source read light, and the other still holds the
    /// plan; one reading heavy only over-restrains.
    pub(crate) fn lookup(
        &self,
        sit: &Situation,
        inputs: &InputMonitor,
        counters: &mut CycleCounters,
    ) -> RestraintPlan {
        let Some(lut) = self.table_for(inputs) else {
            return self.reference;
        };
        let heaviest = heaviest_opponent_kg(lut);
        let robust = match sit.v2x_mass_kg {
            // f64::max: a NaN estimate yields the station's mass.
            Some(station_kg) => {
                counters.v2x_lookups = counters.v2x_lookups.saturating_add(1);
                sit.opponent_mass_estimate_kg.max(station_kg) + self.v2x_mass_margin_kg
            }
            None => sit.opponent_mass_estimate_kg + self.mass_misreport_kg,
        }
        .min(heaviest);
        // NaN-safe: a NaN robust mass keeps the conservative one.
        let mass = if robust > sit.opponent_mass_kg {
            robust
        } else {
            sit.opponent_mass_kg
        };
        self.query(lut, sit, mass, inputs, counters)
    }

    /// The table, where it covers the occupant (a belted adult); `None`: the reference
    /// restraint's situation (no table, or an occupant the table was not built for).
    fn table_for(&self, inputs: &InputMonitor) -> Option<&Lut<'a>> {
        let occ = inputs.occupant;
        self.lut.as_ref().filter(|_| occ.buckled && occ.adult)
    }

    /// Whether the table fires the airbag for the situation with the heaviest opponent one
    /// object fault can hide (`false` without a table or where it does not cover the
    /// occupant): a belt-only plan that this answers `true` for was made belt-only by the
    /// opponent's mass — what one object fault can get wrong — not by the occupant.
    ///
    /// That opponent is a truck or a wall reported as a car: beyond every mass the table
    /// covers, it gives the ego an equivalent barrier speed equal to the closing speed. The
    /// table stands in for it with its heaviest opponent at the closing speed that gives the
    /// same EBS, v·(m + m_ego)/m, capped at the table's fastest knot (a 48 km/h closing
    /// truck: the 3 000 kg opponent at 76.6 km/h).
    /// Not counted in the lookup counters: a question about the table, not a plan.
    pub(crate) fn heaviest_opponent_fires_airbag(
        &self,
        sit: &Situation,
        inputs: &InputMonitor,
    ) -> bool {
        let Some(lut) = self.table_for(inputs) else {
            return false;
        };
        let heaviest = heaviest_opponent_kg(lut);
        let fastest_mps = lut.view.axes()[0]
            .last()
            .map_or(f64::NAN, |v| f64::from(*v) / 3.6);
        let barrier_like = Situation {
            closing_speed_mps: (sit.closing_speed_mps * (heaviest + self.ego_mass_kg) / heaviest)
                .min(fastest_mps),
            ..*sit
        };
        let plan = self.query(
            lut,
            &barrier_like,
            heaviest,
            inputs,
            &mut CycleCounters::default(),
        );
        plan.source == crate::plan::PlanSource::Adaptive && plan.airbag_fires()
    }

    /// `lut`'s plan for the situation with the opponent mass `mass` (kg; the reference
    /// restraint where an axis is out of the table's range).
    fn query(
        &self,
        lut: &Lut<'a>,
        sit: &Situation,
        mass: f64,
        inputs: &InputMonitor,
        counters: &mut CycleCounters,
    ) -> RestraintPlan {
        let occ = inputs.occupant;
        let q = Query {
            closing_speed_kph: (sit.closing_speed_mps * 3.6) as f32,
            opponent_mass_kg: mass as f32,
            occupant_mass_kg: occ.mass_kg,
            seat_distance_mm: occ.chest_to_wheel_mm,
        };
        let l = lut.view.lookup(&q);
        counters.lut_lookups = counters.lut_lookups.saturating_add(1);
        if l.bottoming_out {
            counters.lut_bottoming_out = counters.lut_bottoming_out.saturating_add(1);
        }
        if l.out_of_range.any() {
            counters.lut_out_of_range = counters.lut_out_of_range.saturating_add(1);
            return self.reference;
        }
        RestraintPlan::from_lookup(&l, &lut.view.thresholds())
    }
}

/// The heaviest opponent the table covers, kg (its mass axis' last knot; NaN for an empty
/// axis).
fn heaviest_opponent_kg(lut: &Lut<'_>) -> f64 {
    lut.view.axes()[1]
        .last()
        .map_or(f64::NAN, |m| f64::from(*m))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ttc_constant_speed_is_distance_over_speed() {
        let c = time_to_contact(10.0, 20.0, 0.0).unwrap();
        assert!((c.ttc_s - 0.5).abs() < 1e-12);
        assert_eq!(c.closing_speed_mps, 20.0);
    }

    #[test]
    fn ttc_braking_matches_kinematics() {
        // d = 10 m, v = 20 m/s, closing speed falls at 8 m/s² (a = −8):
        // 10 = 20 t − 4 t² → t = (20 − √(400 − 160)) / 8 = 0.563508…; v_c = √(400 − 160).
        let c = time_to_contact(10.0, 20.0, -8.0).unwrap();
        let t = (20.0 - 240f64.sqrt()) / 8.0;
        assert!((c.ttc_s - t).abs() < 1e-12, "{c:?}");
        assert!((c.closing_speed_mps - 240f64.sqrt()).abs() < 1e-12);
        // Stops before contact: v² < 2|a|d.
        assert!(time_to_contact(10.0, 5.0, -8.0).is_none());
        assert!(time_to_contact(10.0, -1.0, 0.0).is_none());
        assert!(time_to_contact(f64::NAN, 1.0, 0.0).is_none());
    }
}
