//! Thresholds and timeouts of the restraint decision (`[cycle]` in `ecu.toml`).
//!
//! Every number the decision logic uses lives here, with its default and the reason for it.
//! Times are in ms in the file (engineers think in ms); the cycle converts them to ns once.
//! Files (LUT, reference restraint, SecOC keys) are the shell's business: the core gets their
//! contents, never a path.

use serde::{Deserialize, Serialize};

use crate::accel::AccelLimits;
use crate::agreement::{AgreementParams, SeverityAgreement};
use crate::confirm::ConfirmParams;
use crate::fallback::FireFloor;
use crate::safing::SafingParams;
use crate::settings::{check_range as range, ms_to_ns, ConfigError, G_MPS2};

/// Decision-logic configuration. Every key is optional (defaults below).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CycleConfig {
    /// Ego vehicle mass, kg (*default* 1785 kg: the paper's Ford Taurus). The LUT header must
    /// agree (±1 %), otherwise the LUT is rejected: its cells were optimised for another car.
    pub ego_mass_kg: f64,
    /// Ego stiffness class 1..=6 (*default* 4 for 1785 kg).
    pub ego_class: u8,

    /// k of the conservative opponent mass m + k·σ used for prediction and LUT lookup
    /// (*default* 1.0). Why: an opponent heavier than estimated raises the ego Δv and pulse,
    /// and with it the risk of bottoming out through a too-soft restraint; a lighter one only
    /// costs some comfort (paper: ±300 kg moves a_mean by ~2 g). k = 1 covers ~84 % of a
    /// Gaussian estimate one-sided.
    pub conservative_mass_k: f64,

    /// Enter PRE-CRASH when the predicted time to contact is below this, ms (*default* 300).
    /// Must exceed the earliest pretensioner time of the LUT (−100 ms) plus one object period
    /// (20 ms) and the prediction latency, so the preset is ready before it is needed.
    pub preset_horizon_ms: f64,
    /// Leave PRE-CRASH (collision avoided) when the time to contact grows above
    /// `preset_horizon_ms` + this, ms (*default* 200; hysteresis against TTC noise).
    pub preset_exit_hysteresis_ms: f64,
    /// Leave PRE-CRASH (collision avoided) when the predicted contact time plus this has
    /// passed without crash confirmation, ms (*default* 60: contact-time estimate error of a
    /// 10–20 ms object list plus the ~10 ms the accelerometer needs to confirm).
    pub avoided_margin_ms: f64,
    /// Objects below this track confidence are ignored (*default* 0.5).
    pub min_confidence: f64,

    /// Airbag no-fire below this ego equivalent barrier speed, km/h (*default* 20). The paper
    /// gives "below about 20 km/h per vehicle adaptive restraints make no sense (no-fire)". The
    /// per-vehicle speed of a car-to-car crash is the ego's change of speed to the common
    /// velocity, v_close · m_opp / (m_ego + m_opp): v/2 for equal cars, v for a rigid barrier.
    /// The conservative opponent mass is used (fails towards firing).
    pub no_fire_ebs_kph: f64,
    /// The airbag's no-fire line for an occupant not known to be belted, km/h (*default* 14,
    /// ≈ 9 mph): the belt buckle switch reads unbuckled, or its frame is missing or stale. An
    /// unbelted occupant is held by the airbag alone and strikes the wheel in a 20 km/h crash
    /// that the belt alone rides down, so production ECUs fire for them from a lower
    /// severity (dual thresholds; GM's single-stage deploy band 9–14 mph, the field's 50 %
    /// deployment at a Δv of 8–12 mph). The tracked path's low-speed rule and re-plan use it;
    /// the accelerometer-only path judges the airbag against `unbelted_dv_mps`, calibrated on
    /// it. The severity floors — what holds every misuse event — are the same for both. A buckle
    /// switch that reads unbuckled when the occupant is belted (one fault) can therefore fire
    /// the airbag in a 14–20 km/h crash, never on misuse.
    pub unbelted_no_fire_ebs_kph: f64,

    /// Crash confirmation: the accelerometer is "awake" from this deceleration, g
    /// (*default* 1.5); the first awake sample is the measured contact instant.
    pub confirm_wake_g: f64,
    /// Crash confirmation: deceleration threshold, g (*default* 4.0: above road and braking
    /// loads (≤ 1.2 g) and potholes' short spikes are filtered by the persistence below).
    pub confirm_decel_g: f64,
    /// Crash confirmation: consecutive samples over `confirm_decel_g` (*default* 3 = 3 ms at
    /// 1 kHz, 0.75 ms at 4 kHz: rejects single-sample spikes).
    pub confirm_samples: u32,
    /// Crash confirmation: Δv integrated since wake-up, m/s (*default* 0.5 m/s ≈ 1.8 km/h:
    /// reached 4–8 ms after contact from 20 to 54 km/h per vehicle, so confirmation comes
    /// before the reference fire time of 10 ms; a bump or pothole does not integrate to it).
    pub confirm_delta_v_mps: f64,
    /// Crash confirmation: the integrator is reset after this long below the wake threshold,
    /// ms (*default* 10).
    pub confirm_reset_gap_ms: f64,

    /// Prediction-matched confirmation (`crash_match`): the measured onset must be a ramp for
    /// at least this long before it can confirm, ms (*default* 1.0: 4 samples at 4 kHz above
    /// the wake threshold — enough for a least-squares slope with its residual, short enough to
    /// confirm 1.5–3 ms after contact at 40–120 km/h closing speed).
    pub match_min_ms: f64,
    /// Prediction-matched confirmation: the fitted onset must lie within ± this of the
    /// predicted contact, ms (*default* 30: the contact-time error of a 20 ms object list at
    /// 20 ms latency, a few ms, with margin for a misestimated closing speed).
    pub match_window_ms: f64,
    /// The measured onset slope "follows the prediction" within ± this fraction of the
    /// predicted slope (*default* 0.12: the series stiffness of the ego's front with one
    /// opponent class differs from that with another by at most 10 %, and the fit by ≈ 1 %;
    /// a closing-speed error beyond ≈ 12 % shows). Following, the preset plan holds; outside,
    /// up to the ratio limits below, the pulse "departs": the crash is still confirmed and
    /// re-planned at the re-estimated severity.
    pub match_tolerance: f64,
    /// Lowest measured / predicted onset-slope ratio that is still re-estimated as a collision
    /// with this object (*default* 0.5); below, the prediction is not used (accelerometer-only
    /// algorithm, reference restraint).
    pub match_ratio_min: f64,
    /// Highest ratio (*default* 2.5: a rigid barrier instead of a car doubles the slope;
    /// beyond, nothing in the model explains the pulse).
    pub match_ratio_max: f64,
    /// Robust planning: every table lookup (pre-crash preset and in-crash re-plan) is for an
    /// opponent at least this much heavier than reported, capped at the table's heaviest mass,
    /// kg (*default* 1200 — four times the sensing's 300 kg σ; 0 = the conservative
    /// mass m + k·σ only). Why: an opponent's mass does not show in the ego pulse
    /// until long after the restraint is committed (the pulses of 1300 and 2400 kg opponents at
    /// 96 km/h agree within 0.1 g for 30 ms), so the plan must already hold the heavier one.
    /// A table that states the span its cells are verified for (`robust.lighter_opponent_kg`)
    /// is rejected when 2 × this (or this + `v2x_mass_margin_kg`) exceeds it.
    pub mass_misreport_kg: f64,
    /// Robust planning with a second, independent mass source — the opponent's own mass from
    /// V2X (`V2xOpponentMass`), when it describes the tracked object: the lookup is for the
    /// heavier of the object list's estimate and the station's mass plus this margin, kg
    /// (*default* 300: the paper's payload uncertainty), instead of `mass_misreport_kg`. One
    /// source that reads too light (a single fault) is outvoted by the other; one that reads
    /// too heavy over-restrains (the safe direction). Set to `mass_misreport_kg` and V2X can
    /// only raise the plan, never lower it.
    pub v2x_mass_margin_kg: f64,
    /// A `V2xOpponentMass` frame older than this is not used, ms (*default* 300: three of its
    /// 100 ms periods).
    pub v2x_timeout_ms: f64,
    /// The station is the tracked object when its GNSS range, carried forward to the cycle at
    /// its closing speed, is within this of the track's distance, m (*default* 8: GNSS ≈ 2 m
    /// plus a 100 ms old position at 30 m/s) ...
    pub v2x_gate_distance_m: f64,
    /// ... and its closing speed within this of the track's, m/s (*default* 3).
    pub v2x_gate_speed_mps: f64,

    /// Backup confirmation with a faulty crash accelerometer: the vehicle-dynamics
    /// deceleration on CAN (`EgoVehicleState.EgoLongAccel`, 10 ms) at or above this, g, inside
    /// the predicted contact window confirms a predicted crash (*default* 4: braking ≤ 1.2 g).
    pub backup_confirm_g: f64,
    /// Accelerometer-only algorithm: velocity change since the onset [m/s] the crash must reach
    /// at 0, 4, 8, … 60 ms after the onset (linear between; *default* calibrated by
    /// `lut study fallback --derive`, restraint/README.md, "Crash phase"). Reaching it fires
    /// the reference airbag; not reaching it within 60 ms is a no-fire.
    pub fallback_dv_mps: [f64; crate::fallback::KNOTS],
    /// The same boundary for an occupant not known to be belted, m/s at 0, 4, … 60 ms
    /// (*default* calibrated by `lut study fallback --derive --unbelted` on the sweep's crashes
    /// below `unbelted_no_fire_ebs_kph`); at no knot above `fallback_dv_mps`.
    pub unbelted_dv_mps: [f64; crate::fallback::KNOTS],
    /// The airbag's severity floor, m/s (*default* 1.25 ≈ 4.5 km/h): a conventional must-fire
    /// needs at least this velocity change since the onset and the generic confirmation's
    /// persistence (`confirm_decel_g` for `confirm_samples`) at the deciding sample, and a
    /// prediction-matched airbag waits for it too (`Decision::hold_below_floor`). Why: the
    /// boundary's first knots are low so that a severe crash is recognised in its first ms, and
    /// a pothole or kerb strike at the predicted contact of a near miss can follow the predicted
    /// ramp; none carries this much — the matrix's largest misuse Δv is a pothole under both
    /// front wheels at 1.5 × its envelope, 1.2 m/s (at 1.0 such potholes still fired the airbag:
    /// near miss 32, spike in a pothole 17, braking and pothole 10 of 1 000, seed 1). *What it
    /// costs* (the safety order: no inadvertent fire before fire time): the accelerometer-only
    /// airbag fires +1.2 ms (p50) / +1.7 ms (worst) after "127 mm − 30 ms" instead of −0.2 /
    /// +0.5 ms; the FMVSS 208 56 km/h belted case, whose barrier refutes the prediction made for
    /// a 3 000 kg object, fires +11.5 ms instead of +10.5 and its occupant bottoms out (+18.5 %
    /// against the reference restraint at its own +10 ms). The table plans every adaptive airbag
    /// no earlier than its cell's pulse carries this floor (`lut`'s plan = fire).
    pub fallback_min_dv_mps: f64,
    /// The pyrotechnic pretensioner on the conventional path (no adaptive plan): its own
    /// velocity-time boundary, m/s at 0, 4, … 60 ms after the onset (*default* 0.6 × the
    /// airbag's: the pretensioner is meant for crashes below the airbag's no-fire line too).
    /// An event that does not reach it fires no pretensioner (a bump that the generic
    /// thresholds confirm is not a crash that needs one).
    pub pretensioner_dv_mps: [f64; crate::fallback::KNOTS],
    /// The pretensioner's severity floor on the conventional path, m/s (*default* 1.5), with
    /// the same persistence rule as `fallback_min_dv_mps`. Why above the airbag's 1.25: the
    /// pretensioner's boundary is 0.6 × the airbag's, so a rough road's first lobe (before the
    /// roughness measure has seen the road) could carry the floor alone — at 3.9–4.5 g rms
    /// 2 in 96 000 rough-road variants fired it at 1.25 (seeds 1 and 3), 0 in 144 000 at 1.5
    /// (seeds 1, 3, 5). The airbag's must-fire fires the pretensioner too, at the same
    /// instant (`Decision::gate_pretensioner`), so crashes above the airbag's line lose
    /// nothing; below it the pretensioner fires ≈ 2 ms later (library: +0.5 to +0.7 points on
    /// the five low-speed cases, all still no worse than the reference). A prediction-matched
    /// pretensioner waits for the lower of the two floors (`Decision::hold_below_floor`).
    pub pretensioner_min_dv_mps: f64,
    /// Prediction-matched confirmation: besides the onset ramp fitting the prediction, the
    /// velocity change since the onset must reach this, m/s, with the deceleration staying
    /// above the wake threshold until then (*default* 0.3). Why: a kerb strike or pothole at
    /// the predicted contact of a collision that does not happen (a near miss, a ghost
    /// object) can ramp up like the predicted crash for 2 ms (7.4 g in 4 ms ≈ 0.15 m/s);
    /// a crash of the table's range reaches 0.3 m/s 4–6 ms after contact, within the
    /// table's fire-delay tolerance of a +3 ms airbag.
    pub match_min_dv_mps: f64,
    /// Every path's deciding sample must find the event still *loading*: its smoothed
    /// deceleration (0.25 ms) at least this fraction of its peak since the onset
    /// (`restraint::confirm::Loading`; *default* 0.85; 0 switches the rule off). Why: a crash's
    /// deceleration rises as long as the structures are crushed (the force–deflection curves
    /// only rise), so the rule costs a real crash nothing; a pothole, kerb strike or door slam
    /// is a pulse that has peaked and is falling by the time it carries a floor's Δv. It lifts
    /// the no-fire limit of a half-sine misuse pulse from the floor f to ≈ 1.3 f.
    pub loading_fraction: f64,
    /// The accelerometers' anti-alias group delay, ms (*default* 0.70: the ADXL180's
    /// third-order Bessel low-pass at 400 Hz, as `world::lowpass` models it): a measured
    /// onset is this much later than the contact that caused it, so the crash phase dates
    /// the contact this much earlier and the plan's fire times keep their meaning.
    pub accel_delay_ms: f64,
    /// One object fault must not move a crash across the no-fire line: a crash
    /// the prediction matched fires before the measured pulse confirms it only when it would
    /// be above the no-fire line even with the lightest opponent on the road
    /// (`lightest_opponent_kg`, *default* 800 kg: a mass the object sensor misreports can be
    /// any) and a closing speed `speed_misreport_mps` lower (*default* 5 m/s, the bound the
    /// table is robust to); otherwise the airbag waits for the accelerometer-only boundary to
    /// say must-fire for the event (the adaptive plan kept, its fire no earlier than the
    /// boundary). Above ≈ 83 km/h closing nothing waits.
    pub lightest_opponent_kg: f64,
    /// See `lightest_opponent_kg`.
    pub speed_misreport_mps: f64,
    /// A tracked low-speed object (EBS below the no-fire line even with the opponent
    /// `mass_misreport_kg` heavier than reported) whose predicted contact is within
    /// `avoided_margin_ms` of the measured onset fires the airbag only when the event's
    /// measured Δv exceeds the most that crash can carry (the closing speed — the EBS of an
    /// opponent of any mass is at most that — × `low_speed_dv_factor`, *default* 1.3:
    /// restitution) plus this, m/s (*default* 1.2: the largest misuse Δv the matrix samples,
    /// a pothole × 1.5) — a kerb or pothole inside a low-speed crash never does; a crash far
    /// more severe than tracked still does, late.
    pub low_speed_misuse_dv_mps: f64,
    /// See `low_speed_misuse_dv_mps`.
    pub low_speed_dv_factor: f64,

    /// Braking compensation: while the vehicle frame's brake state says braking, its
    /// deceleration (`EgoLongAccel`, taken before the accelerometer event began and held
    /// through it) up to this is taken off the crash accelerometer's readings before the crash
    /// detectors see them, g (*default* 1.2: the most a tyre brakes; 0 = off). Sustained
    /// deceleration the car's own speed signal explains is not crash evidence: ABS braking at
    /// 0.6–1 g plus a pothole is a pothole. A forged or faulty vehicle frame can only make a
    /// crash look lighter by this much (later, never an inadvertent fire). Not in PRE-CRASH:
    /// a predicted crash's own (AEB) braking belongs to it — taking it off moved the airbag of
    /// a 31 + 31 km/h crash after ABS/EBA braking from +12.9 ms to +20.9 ms (plan +3 ms).
    pub braking_compensation_max_g: f64,

    /// Safing channel (`safing`): its events begin at this deceleration, g (*default* 1.5).
    pub safing_wake_g: f64,
    /// Safing channel: Δv since its onset that closes it, m/s (*default* 0.2: below every
    /// main path's floor, so a real crash is never waiting for it).
    pub safing_dv_mps: f64,
    /// Safing channel: stays closed this long after its event ended, ms (*default* 20).
    pub safing_hold_ms: f64,
    /// A crash-phase fire that is due waits at most this long for the safing agreement,
    /// then it is dropped, ms (*default* 30).
    pub safing_wait_ms: f64,
    /// With the safing sensor faulty, a vehicle deceleration (`EgoLongAccel`) at least this
    /// stands in for it, g (*default* 2.0: above braking, ≤ 1.2 g).
    pub safing_substitute_g: f64,
    /// Severity agreement (`agreement`): the crash sensor's Δv over the confirmed event may
    /// exceed the safing sensor's over the same window by at most this plus
    /// `severity_tolerance_fraction` × its own, m/s (*default* 0.10: two healthy sensors on
    /// the same pulse differ by ≤ 0.03 m/s in the matrix's must-fire crashes); beyond it the
    /// crash sensor is implausible for the event and nothing of it fires.
    pub severity_tolerance_dv_mps: f64,
    /// See `severity_tolerance_dv_mps` (*default* 0.10: two sensors' sensitivity tolerances,
    /// ±5 % each).
    pub severity_tolerance_fraction: f64,
    /// Road roughness (`roughness`): this many times the road's recent forward velocity
    /// excursion beyond 0.05 m/s (the crash sensor's velocity high-passed at 50 ms, its
    /// positive peak held) is added to every crash-phase fire's severity floor and to the
    /// generic confirmation's `confirm_delta_v_mps` (no CrashDetected on the bus for a rough
    /// road's lobes) (*default* 2.0;
    /// 0 = off). Why: a rough road swings the car's velocity as far back as forward, a crash
    /// only slows it; at the matrix's 3–4.5 g rms a backward swing now and then carried the
    /// 1.25 m/s floor and fired the pyrotechnic pretensioner (25 of 1 000, seed 1; 1 of 24 000
    /// left at 2.0, seeds 1, 7, 2 — 5 at 1.5; must-fire crashes on a smooth road unchanged;
    /// the last ones, first lobes before any forward swing, went with a physical rough road
    /// (`world::events`: from rest, crest factor 3) and `pretensioner_min_dv_mps` 1.5).
    pub roughness_k: f64,
    /// How long the held forward excursion takes to decay to 1/e, ms (*default* 500: a rough
    /// road's lobes refresh it every few tens of ms; after a pothole's forward rebound, up to
    /// 1.2 m/s, the floors are lifted by up to 2.3 m/s, 0.85 m/s half a second later — a crash
    /// right after a pothole fires a few ms later, the safe direction).
    pub roughness_hold_ms: f64,
    /// Safing sensor measuring range, g (*default* 50): readings at it are saturated, beyond
    /// it impossible (`SAFING_INVALID`). Its timeout and stuck time are the crash
    /// accelerometer's (`accel_timeout_ms`, `accel_stuck_ms`).
    pub safing_full_scale_g: f64,

    /// The car has the two crush-zone satellites (`satellites`; *default* true). `false`:
    /// central-only decisions, nothing expected on their ports.
    pub satellites: bool,
    /// Satellites' measuring range, g (*default* 240: an MMA5124-class ±240 g part): the
    /// ±480 data codes of a PSI5 frame span ±this.
    pub satellite_full_scale_g: f64,
    /// A satellite without a frame for this long grants nothing, ms (*default* 50, the crash
    /// accelerometer's timeout and for its reason).
    pub satellite_timeout_ms: f64,
    /// The crush Δv window: a satellite's velocity change over this less the tunnel's, ms
    /// (*default* 4: at 56 km/h a rigid barrier's crush Δv passes 2 m/s 3–4 ms after contact,
    /// a body motion's stays ≤ 0.1 m/s because both move alike).
    pub satellite_window_ms: f64,
    /// Frontal severity (the smaller crush Δv of the two) from which the satellites begin to
    /// lower the tunnel's thresholds, m/s (*default* 1.0: the library's no-fire crashes, 14–16
    /// km/h barriers, peak at 0.45–0.52, misuse at ≤ 0.41 — a factor 2 below).
    pub satellite_relief_from_mps: f64,
    /// Frontal severity of the whole relief, m/s (*default* 2.0: a 31 + 31 km/h car crash's
    /// peak; every must-fire crash of the library passes it within 4–6 ms of contact).
    pub satellite_relief_full_mps: f64,
    /// The whole relief brings the airbag's and the pyrotechnic pretensioner's severity
    /// floors down to this, m/s (*default* 0.5: above a door slam's or hammer blow's Δv, which
    /// cannot crush the front end anyway).
    pub satellite_floor_mps: f64,
    /// The whole relief scales the accelerometer-only boundary by this (*default* 1.0: the
    /// boundary is not lowered). Why: the satellites measure how fast the front end crushes,
    /// which is the closing speed's share, not the ego's velocity change; a light opponent at a
    /// high closing speed crushes the front like a must-fire crash and stays below the no-fire
    /// line (14–16 km/h EBS). The boundary is what still tells them apart: at 0.5 the matrix's
    /// `misreported-low-speed` family fired 35 airbags of 445 (seed 7), at 0.75 21; the must-fire
    /// families' fire times are the same at 1.0 — the floor is what held them.
    pub satellite_boundary_scale: f64,
    /// While usable satellites have not seen the front end crush as much as
    /// `satellite_relief_from_mps`, the accelerometer-only airbag boundary is lifted by this,
    /// m/s; from then on, while the relief holds, not at all (`satellites`, "Low crush";
    /// *default* 1.2: a kerb strike or pothole inside a 12–16 km/h crash, the matrix's
    /// envelope × 1.5). 0 = off.
    pub satellite_low_crush_lift_mps: f64,
    /// For an occupant not known to be belted the low-crush lift ends once usable satellites
    /// see the front end crush this much, m/s (*default* 0.5: above a 14 km/h barrier's 0.45 —
    /// the unbelted no-fire line — and every misuse event's ≤ 0.41; a 20 km/h barrier's ≈ 0.6).
    /// At `satellite_relief_from_mps` the lift would hold an unbelted occupant's 20–22 km/h
    /// crash to the boundary plus 1.2 m/s, tens of ms late. The unbelted relief counts from
    /// this line to `satellite_relief_full_mps` × this / `satellite_relief_from_mps` (the
    /// belted span scaled to the occupant's line).
    pub satellite_unbelted_crush_mps: f64,
    /// The front end folds (`satellites`, "The front end folds"): when the larger crush Δv of
    /// the two satellites reaches this, m/s (*default* 2.0: a crush rate of ≈ 30 km/h at the
    /// rail tip; a 24 km/h offset barrier's struck rail reaches 1.3), and the tracked
    /// prediction is a must-fire crash with the opponent's mass lowered by
    /// `mass_misreport_kg`, the accelerometer-only boundary is scaled by the next key for as
    /// long as a relief holds.
    pub satellite_fold_crush_mps: f64,
    /// What a fold scales the accelerometer-only boundary by (*default* 0.4; 1 = off).
    pub satellite_fold_boundary_scale: f64,

    /// Crash accelerometer: no batch for this long → `ACCEL_STALE`, ms (*default* 50: batches
    /// come every ms, so 50 missed ones are a dead sensor; with one 20 ms `EcuStatus` period the
    /// fault is on the bus within 70 ms. Tighter limits trip on the emulated bench's scheduling
    /// stalls (QEMU TCG: tens of ms under load), which would then look like dead sensors.)
    pub accel_timeout_ms: f64,
    /// Crash accelerometer: bit-identical readings for this long → stuck (`ACCEL_INVALID`),
    /// ms (*default* 20; see `accel` module docs).
    pub accel_stuck_ms: f64,
    /// Crash accelerometer measuring range, g (*default* 200): readings at it are saturated,
    /// beyond it impossible (`ACCEL_INVALID`).
    pub accel_full_scale_g: f64,

    /// Object data older than this (by receipt) is stale → DEGRADED, ms (*default* 100 = five
    /// missed samples of a 20 ms object list).
    pub object_timeout_ms: f64,
    /// Ego vehicle state (10 ms cycle) older than this → DEGRADED, ms (*default* 100).
    pub vehicle_timeout_ms: f64,
    /// Occupant classification (100 ms cycle) older than this → DEGRADED, ms (*default* 500).
    pub occupant_timeout_ms: f64,
    /// E2E failure burst: this many rejected input frames ... (*default* 3, max 16)
    pub e2e_burst_count: u32,
    /// ... within this window, ms (*default* 100) → DEGRADED ...
    pub e2e_burst_window_ms: f64,
    /// ... held until this long after the last rejection, ms (*default* 500).
    pub e2e_hold_ms: f64,
    /// Alive-counter gap tolerated without rejection (AUTOSAR MaxDeltaCounter − 1;
    /// *default* 1: one lost frame on a loaded bus is not a fault).
    pub e2e_max_lost: u8,

    /// The track filter of the object samples (`[cycle.track]`; see
    /// [`crate::estimate::track`]). The collision prediction has no setting: it is solved in
    /// closed form (no step size).
    pub track: TrackConfig,
}

impl Default for CycleConfig {
    fn default() -> Self {
        Self {
            ego_mass_kg: 1785.0,
            ego_class: 4,
            conservative_mass_k: 1.0,
            preset_horizon_ms: 300.0,
            preset_exit_hysteresis_ms: 200.0,
            avoided_margin_ms: 60.0,
            min_confidence: 0.5,
            no_fire_ebs_kph: 20.0,
            unbelted_no_fire_ebs_kph: 14.0,
            confirm_wake_g: 1.5,
            confirm_decel_g: 4.0,
            confirm_samples: 3,
            confirm_delta_v_mps: 0.5,
            confirm_reset_gap_ms: 10.0,
            match_min_ms: 1.0,
            match_window_ms: 30.0,
            match_tolerance: 0.12,
            match_ratio_min: 0.5,
            match_ratio_max: 2.5,
            mass_misreport_kg: 1200.0,
            v2x_mass_margin_kg: 300.0,
            v2x_timeout_ms: 300.0,
            v2x_gate_distance_m: 8.0,
            v2x_gate_speed_mps: 3.0,
            backup_confirm_g: 4.0,
            fallback_dv_mps: crate::fallback::DEFAULT_DV_MPS,
            unbelted_dv_mps: crate::fallback::DEFAULT_UNBELTED_DV_MPS,
            fallback_min_dv_mps: 1.25,
            pretensioner_dv_mps: crate::fallback::DEFAULT_PRETENSIONER_DV_MPS,
            pretensioner_min_dv_mps: 1.5,
            match_min_dv_mps: 0.3,
            loading_fraction: 0.85,
            accel_delay_ms: 0.70,
            lightest_opponent_kg: 800.0,
            speed_misreport_mps: 5.0,
            low_speed_misuse_dv_mps: 1.2,
            low_speed_dv_factor: 1.3,
            braking_compensation_max_g: 1.2,
            safing_wake_g: 1.5,
            safing_dv_mps: 0.2,
            safing_hold_ms: 20.0,
            safing_wait_ms: 30.0,
            safing_substitute_g: 2.0,
            severity_tolerance_dv_mps: 0.10,
            severity_tolerance_fraction: 0.10,
            roughness_k: 2.0,
            roughness_hold_ms: 500.0,
            safing_full_scale_g: 50.0,
            satellites: true,
            satellite_full_scale_g: 240.0,
            satellite_timeout_ms: 50.0,
            satellite_window_ms: 4.0,
            satellite_relief_from_mps: 1.0,
            satellite_relief_full_mps: 2.0,
            satellite_floor_mps: 0.5,
            satellite_boundary_scale: 1.0,
            satellite_low_crush_lift_mps: 1.2,
            satellite_unbelted_crush_mps: 0.5,
            satellite_fold_crush_mps: 2.0,
            satellite_fold_boundary_scale: 0.4,
            accel_timeout_ms: 50.0,
            accel_stuck_ms: 20.0,
            accel_full_scale_g: 200.0,
            object_timeout_ms: 100.0,
            vehicle_timeout_ms: 100.0,
            occupant_timeout_ms: 500.0,
            e2e_burst_count: 3,
            e2e_burst_window_ms: 100.0,
            e2e_hold_ms: 500.0,
            e2e_max_lost: 1,
            track: TrackConfig::default(),
        }
    }
}

/// Most E2E rejections remembered for burst detection (size of a preallocated ring).
pub const MAX_E2E_BURST: usize = 16;

impl CycleConfig {
    /// Range checks; the error names the key.
    pub fn validate(&self) -> Result<(), ConfigError> {
        range("ego_mass_kg", self.ego_mass_kg, 500.0, 5000.0)?;
        range("ego_class", f64::from(self.ego_class), 1.0, 6.0)?;
        range("conservative_mass_k", self.conservative_mass_k, 0.0, 5.0)?;
        range("preset_horizon_ms", self.preset_horizon_ms, 50.0, 5000.0)?;
        range(
            "preset_exit_hysteresis_ms",
            self.preset_exit_hysteresis_ms,
            0.0,
            5000.0,
        )?;
        range("avoided_margin_ms", self.avoided_margin_ms, 0.0, 1000.0)?;
        range("min_confidence", self.min_confidence, 0.0, 1.0)?;
        range("no_fire_ebs_kph", self.no_fire_ebs_kph, 0.0, 100.0)?;
        range(
            "unbelted_no_fire_ebs_kph",
            self.unbelted_no_fire_ebs_kph,
            0.0,
            self.no_fire_ebs_kph,
        )?;
        range("confirm_wake_g", self.confirm_wake_g, 0.1, 50.0)?;
        range(
            "confirm_decel_g",
            self.confirm_decel_g,
            self.confirm_wake_g,
            100.0,
        )?;
        range(
            "confirm_samples",
            f64::from(self.confirm_samples),
            1.0,
            100.0,
        )?;
        range("confirm_delta_v_mps", self.confirm_delta_v_mps, 0.0, 20.0)?;
        range(
            "confirm_reset_gap_ms",
            self.confirm_reset_gap_ms,
            0.1,
            1000.0,
        )?;
        range("match_min_ms", self.match_min_ms, 0.1, 20.0)?;
        range("match_window_ms", self.match_window_ms, 1.0, 500.0)?;
        range("match_tolerance", self.match_tolerance, 0.0, 1.0)?;
        range(
            "match_ratio_min",
            self.match_ratio_min,
            0.1,
            1.0 - self.match_tolerance,
        )?;
        range(
            "match_ratio_max",
            self.match_ratio_max,
            1.0 + self.match_tolerance,
            10.0,
        )?;
        range("mass_misreport_kg", self.mass_misreport_kg, 0.0, 10_000.0)?;
        range("v2x_mass_margin_kg", self.v2x_mass_margin_kg, 0.0, 10_000.0)?;
        range("v2x_timeout_ms", self.v2x_timeout_ms, 1.0, 5_000.0)?;
        range("v2x_gate_distance_m", self.v2x_gate_distance_m, 0.0, 100.0)?;
        range("v2x_gate_speed_mps", self.v2x_gate_speed_mps, 0.0, 30.0)?;
        range("backup_confirm_g", self.backup_confirm_g, 1.5, 15.0)?;
        crate::fallback::validate_thresholds("fallback_dv_mps", &self.fallback_dv_mps)?;
        crate::fallback::validate_thresholds("unbelted_dv_mps", &self.unbelted_dv_mps)?;
        for (&u, &b) in self.unbelted_dv_mps.iter().zip(&self.fallback_dv_mps) {
            range("unbelted_dv_mps", u, 0.0, b)?;
        }
        range("fallback_min_dv_mps", self.fallback_min_dv_mps, 0.0, 20.0)?;
        crate::fallback::validate_thresholds("pretensioner_dv_mps", &self.pretensioner_dv_mps)?;
        range(
            "pretensioner_min_dv_mps",
            self.pretensioner_min_dv_mps,
            0.0,
            20.0,
        )?;
        range("match_min_dv_mps", self.match_min_dv_mps, 0.0, 5.0)?;
        range("loading_fraction", self.loading_fraction, 0.0, 1.0)?;
        range("accel_delay_ms", self.accel_delay_ms, 0.0, 5.0)?;
        range(
            "lightest_opponent_kg",
            self.lightest_opponent_kg,
            100.0,
            5000.0,
        )?;
        range("speed_misreport_mps", self.speed_misreport_mps, 0.0, 30.0)?;
        range(
            "low_speed_misuse_dv_mps",
            self.low_speed_misuse_dv_mps,
            0.0,
            10.0,
        )?;
        range("low_speed_dv_factor", self.low_speed_dv_factor, 1.0, 3.0)?;
        range(
            "braking_compensation_max_g",
            self.braking_compensation_max_g,
            0.0,
            2.0,
        )?;
        range(
            "satellite_full_scale_g",
            self.satellite_full_scale_g,
            50.0,
            1_000.0,
        )?;
        range(
            "satellite_timeout_ms",
            self.satellite_timeout_ms,
            1.0,
            1_000.0,
        )?;
        range("satellite_window_ms", self.satellite_window_ms, 1.0, 10.0)?;
        range(
            "satellite_relief_from_mps",
            self.satellite_relief_from_mps,
            0.2,
            10.0,
        )?;
        range(
            "satellite_relief_full_mps",
            self.satellite_relief_full_mps,
            self.satellite_relief_from_mps,
            20.0,
        )?;
        range("satellite_floor_mps", self.satellite_floor_mps, 0.2, 5.0)?;
        range(
            "satellite_boundary_scale",
            self.satellite_boundary_scale,
            0.2,
            1.0,
        )?;
        range(
            "satellite_fold_crush_mps",
            self.satellite_fold_crush_mps,
            self.satellite_relief_from_mps,
            20.0,
        )?;
        range(
            "satellite_fold_boundary_scale",
            self.satellite_fold_boundary_scale,
            0.2,
            1.0,
        )?;
        range(
            "satellite_low_crush_lift_mps",
            self.satellite_low_crush_lift_mps,
            0.0,
            5.0,
        )?;
        range(
            "satellite_unbelted_crush_mps",
            self.satellite_unbelted_crush_mps,
            0.1,
            self.satellite_relief_from_mps,
        )?;
        range("safing_wake_g", self.safing_wake_g, 0.1, 50.0)?;
        range("safing_dv_mps", self.safing_dv_mps, 0.01, 5.0)?;
        range("safing_hold_ms", self.safing_hold_ms, 0.0, 1_000.0)?;
        range("safing_wait_ms", self.safing_wait_ms, 0.0, 1_000.0)?;
        range("safing_substitute_g", self.safing_substitute_g, 1.5, 15.0)?;
        range(
            "severity_tolerance_dv_mps",
            self.severity_tolerance_dv_mps,
            0.0,
            5.0,
        )?;
        range(
            "severity_tolerance_fraction",
            self.severity_tolerance_fraction,
            0.0,
            1.0,
        )?;
        range("roughness_k", self.roughness_k, 0.0, 5.0)?;
        range("roughness_hold_ms", self.roughness_hold_ms, 100.0, 10_000.0)?;
        range(
            "safing_full_scale_g",
            self.safing_full_scale_g,
            10.0,
            1_000.0,
        )?;
        range("accel_timeout_ms", self.accel_timeout_ms, 2.0, 1_000.0)?;
        range("accel_stuck_ms", self.accel_stuck_ms, 1.0, 10_000.0)?;
        range("accel_full_scale_g", self.accel_full_scale_g, 10.0, 1_000.0)?;
        range("object_timeout_ms", self.object_timeout_ms, 1.0, 10_000.0)?;
        range("vehicle_timeout_ms", self.vehicle_timeout_ms, 1.0, 10_000.0)?;
        range(
            "occupant_timeout_ms",
            self.occupant_timeout_ms,
            1.0,
            10_000.0,
        )?;
        range(
            "e2e_burst_count",
            f64::from(self.e2e_burst_count),
            1.0,
            MAX_E2E_BURST as f64,
        )?;
        range(
            "e2e_burst_window_ms",
            self.e2e_burst_window_ms,
            1.0,
            10_000.0,
        )?;
        range("e2e_hold_ms", self.e2e_hold_ms, 0.0, 60_000.0)?;
        range("e2e_max_lost", f64::from(self.e2e_max_lost), 0.0, 14.0)?;
        self.track.validate()
    }

    /// The airbag's no-fire line for the occupant, km/h: `no_fire_ebs_kph` for a belted one,
    /// `unbelted_no_fire_ebs_kph` for any other (unbuckled, or the buckle not known).
    pub fn no_fire_line_kph(&self, belted: bool) -> f64 {
        if belted {
            self.no_fire_ebs_kph
        } else {
            self.unbelted_no_fire_ebs_kph
        }
    }

    /// The closing speed [m/s] from which a matched crash fires on its plan without waiting
    /// for the accelerometer-only boundary: above the no-fire line even with the lightest
    /// opponent (`lightest_opponent_kg`) and a closing speed `speed_misreport_mps` lower than
    /// measured — the EBS v·m/(m_ego + m) solved for v
    /// (`physics::equivalent_barrier_speed_kph`), plus the misreport. −∞ when the line is at 0
    /// (every crash is above it).
    pub fn unguarded_closing_mps(&self) -> f64 {
        if self.no_fire_ebs_kph <= 0.0 {
            return f64::NEG_INFINITY;
        }
        let per_mps_kph =
            physics::equivalent_barrier_speed_kph(1.0, self.ego_mass_kg, self.lightest_opponent_kg);
        self.speed_misreport_mps + self.no_fire_ebs_kph / per_mps_kph
    }

    /// The generic crash confirmation's thresholds (`confirm_*`) in the detector's units.
    pub fn confirm_params(&self) -> ConfirmParams {
        ConfirmParams {
            wake_mps2: self.confirm_wake_g * G_MPS2,
            decel_mps2: self.confirm_decel_g * G_MPS2,
            samples: self.confirm_samples,
            delta_v_mps: self.confirm_delta_v_mps,
            reset_gap_ns: ms_to_ns(self.confirm_reset_gap_ms),
        }
    }

    /// The prediction-matched confirmation's settings (`match_*`) in its units.
    pub fn match_params(&self) -> crate::crash_match::MatchParams {
        crate::crash_match::MatchParams {
            onset: self.confirm_params(),
            min_span_ns: ms_to_ns(self.match_min_ms),
            window_ns: ms_to_ns(self.match_window_ms),
            tolerance: self.match_tolerance,
            ratio_min: self.match_ratio_min,
            ratio_max: self.match_ratio_max,
            min_dv_mps: self.match_min_dv_mps,
            loading_fraction: self.loading_fraction,
        }
    }

    /// The road-roughness measure (`roughness_k`, `roughness_hold_ms`).
    pub fn roughness(&self) -> crate::roughness::Roughness {
        crate::roughness::Roughness::new(self.roughness_k, self.roughness_hold_ms * 1e-3)
    }

    /// The airbag's floor on the conventional path (`fallback_min_dv_mps` + persistence).
    pub fn fallback_floor(&self) -> FireFloor {
        FireFloor {
            min_dv_mps: self.fallback_min_dv_mps,
            decel_mps2: self.confirm_decel_g * G_MPS2,
            samples: self.confirm_samples,
            loading_fraction: self.loading_fraction,
        }
    }

    /// The satellite fusion's settings (`satellite_*`) in its units.
    pub fn satellite_params(&self) -> crate::satellites::SatelliteParams {
        crate::satellites::SatelliteParams {
            enabled: self.satellites,
            lsb_mps2: self.satellite_full_scale_g * G_MPS2
                / f64::from(crate::signals::psi5::DATA_LIMIT),
            timeout_ns: ms_to_ns(self.satellite_timeout_ms),
            window_ns: ms_to_ns(self.satellite_window_ms),
            relief_from_mps: self.satellite_relief_from_mps,
            relief_full_mps: self.satellite_relief_full_mps,
            floor_mps: self.satellite_floor_mps,
            boundary_scale: self.satellite_boundary_scale,
            low_crush_lift_mps: self.satellite_low_crush_lift_mps,
            unbelted_crush_mps: self.satellite_unbelted_crush_mps,
            fold_crush_mps: self.satellite_fold_crush_mps,
            fold_boundary_scale: self.satellite_fold_boundary_scale,
        }
    }

    /// The safing function's settings (`safing_*`) in its units.
    pub fn safing_params(&self) -> SafingParams {
        SafingParams {
            onset: ConfirmParams {
                wake_mps2: self.safing_wake_g * G_MPS2,
                ..self.confirm_params()
            },
            dv_mps: self.safing_dv_mps,
            hold_ns: ms_to_ns(self.safing_hold_ms),
            substitute_mps2: self.safing_substitute_g * G_MPS2,
        }
    }

    /// The severity agreement of the two accelerometers (`severity_tolerance_*`; events as
    /// the safing function's).
    pub fn severity_agreement(&self) -> SeverityAgreement {
        let p = self.safing_params();
        SeverityAgreement::new(
            AgreementParams {
                tolerance_dv_mps: self.severity_tolerance_dv_mps,
                tolerance_fraction: self.severity_tolerance_fraction,
            },
            p.onset.wake_mps2,
            p.onset.reset_gap_ns,
        )
    }

    /// The safing sensor's monitor limits (the crash accelerometer's timeout and stuck time,
    /// its own range).
    pub fn safing_limits(&self) -> AccelLimits {
        AccelLimits {
            full_scale_mps2: self.safing_full_scale_g * G_MPS2,
            ..self.accel_limits()
        }
    }

    /// The accelerometer monitor's limits (`accel_*`) in its units.
    pub fn accel_limits(&self) -> AccelLimits {
        AccelLimits {
            timeout_ns: ms_to_ns(self.accel_timeout_ms),
            stuck_ns: ms_to_ns(self.accel_stuck_ms),
            full_scale_mps2: self.accel_full_scale_g * G_MPS2,
        }
    }
}

/// Settings of the track filter (`[cycle.track]` in `ecu.toml`). Every key is optional.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackConfig {
    /// Measurement noise of the distance, m, 1σ (*default* 0.1: twice the bench sensor's
    /// 5 cm, so a somewhat worse sensor is not gated out).
    pub distance_sigma_m: f64,
    /// Measurement noise of the closing speed, m/s, 1σ (*default* 0.2: twice the bench
    /// sensor's 0.1 m/s).
    pub closing_speed_sigma_mps: f64,
    /// Measurement noise of the tracker's relative acceleration, m/s², 1σ (*default* 1.0: a
    /// tracker differentiates it from the speed, so it is the noisiest of the three).
    pub accel_sigma_mps2: f64,
    /// Spectral density of the relative jerk, m²/s⁵ (*default* 200: the closing acceleration
    /// may change by √(q τ) ≈ 2 m/s² within one 20 ms object period — braking onsets reach
    /// 16 m/s² within 150 ms).
    pub jerk_density_m2ps5: f64,
    /// Gate on the squared Mahalanobis distance of a sample (*default* 16.27: the χ² 99.9 %
    /// quantile with 3 degrees of freedom — one good sample in a thousand is rejected).
    pub gate_chi2: f64,
    /// Outliers in a row after which the track restarts from the newest sample
    /// (*default* 3: 60 ms of a 20 ms object list).
    pub max_outliers: u32,
    /// Weight α of a sample in the measurement-noise scale λ (*default* 0.2: about the
    /// last five samples; 0 switches the adaptation off; see the module docs).
    pub noise_adaptation: f64,
    /// Share ρ of a mass sample's reported variance that is common to all samples
    /// (systematic), 0..=1 (*default* 0.5; see the module docs).
    pub mass_sigma_correlation: f64,
    /// The decision plans with the contact instant estimate − k·σ (*default* 1.0): a
    /// pretensioner planned before contact fires early rather than late, and PRE-CRASH is
    /// entered early rather than late.
    pub contact_time_k: f64,
}

impl Default for TrackConfig {
    fn default() -> Self {
        Self {
            distance_sigma_m: 0.1,
            closing_speed_sigma_mps: 0.2,
            accel_sigma_mps2: 1.0,
            jerk_density_m2ps5: 200.0,
            gate_chi2: 16.27,
            max_outliers: 3,
            noise_adaptation: 0.2,
            mass_sigma_correlation: 0.5,
            contact_time_k: 1.0,
        }
    }
}

impl TrackConfig {
    /// Range checks; the error names the key.
    pub fn validate(&self) -> Result<(), ConfigError> {
        range("track.distance_sigma_m", self.distance_sigma_m, 1e-3, 10.0)?;
        range(
            "track.closing_speed_sigma_mps",
            self.closing_speed_sigma_mps,
            1e-3,
            10.0,
        )?;
        range("track.accel_sigma_mps2", self.accel_sigma_mps2, 1e-3, 100.0)?;
        range(
            "track.jerk_density_m2ps5",
            self.jerk_density_m2ps5,
            0.0,
            1e6,
        )?;
        range("track.gate_chi2", self.gate_chi2, 1.0, 1e6)?;
        range(
            "track.max_outliers",
            f64::from(self.max_outliers),
            1.0,
            100.0,
        )?;
        range("track.noise_adaptation", self.noise_adaptation, 0.0, 1.0)?;
        range(
            "track.mass_sigma_correlation",
            self.mass_sigma_correlation,
            0.0,
            1.0,
        )?;
        range("track.contact_time_k", self.contact_time_k, 0.0, 5.0)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_name_the_key() {
        CycleConfig::default().validate().unwrap();
        let c = CycleConfig {
            conservative_mass_k: f64::NAN,
            ..CycleConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().key, "conservative_mass_k");
        let c = CycleConfig {
            e2e_burst_count: 17,
            ..CycleConfig::default()
        };
        let e = c.validate().unwrap_err();
        assert_eq!((e.key, e.value, e.hi), ("e2e_burst_count", 17.0, 16.0));
    }
}
