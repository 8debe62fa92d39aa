//! The judge: occupant outcome of what was actually commanded, against the TRUE crash pulse,
//! beside the conventional reference restraint and the ideal constant-force bound.
//!
//! Commanded restraint (times relative to the TRUE contact, from receive timestamps):
//! * pretensioner: time of the fire command if the pretensioner was still fired at contact
//!   (a release before contact undoes a pre-crash fire) or fired after contact; never fired →
//!   no pretensioning (slack stays);
//! * load limiter: the level in force 10 ms after contact (the belt reaches its limit later
//!   than that; commands after it are too late to change the hardware); no belt command at all
//!   → the reference level (the passive retractor's built-in limiter);
//! * airbag: receive time and level of the first armed fire command; none → no airbag.
//!
//! Reference restraint: `data/reference-restraint.toml` levels and times, fired as a
//! conventional ECU would: below [`REFERENCE_NO_FIRE_EBS_KPH`] of true equivalent barrier speed
//! (ego Δv / (1 + e)) it does not fire the airbag (no-fire requirement; same limit as the
//! ECU's default `no_fire_ebs_kph`).

use crate::report::Judged;
use physics::{OccupantInput, OccupantOutcome, RestraintHardware, RestraintSettings};

/// Conventional no-fire limit on the ego's true equivalent barrier speed [km/h] (SPEC: below
/// about 20 km/h restraints must not fire).
pub const REFERENCE_NO_FIRE_EBS_KPH: f64 = 20.0;

/// Hand-over instant of the load-limiter level after contact [s].
pub const LIMITER_LATCH_AFTER_CONTACT_S: f64 = 0.010;

/// "Never fired" trigger time [s after contact]: beyond every simulation.
pub const NEVER_S: f64 = 100.0;

/// Tolerance of the "adaptive no worse than reference" verdict on a_max + a_mean: command
/// receive times carry scheduling jitter of a few ms (more under an emulator), which moves
/// the outcome by a few per cent even for identical settings.
pub const NO_WORSE_TOLERANCE: f64 = 0.05;

/// Simulates `set` against `pulse` for `occ`, with its time history.
pub fn judge(
    pulse: &physics::CompartmentPulse<'_>,
    occ: &OccupantInput,
    set: &RestraintSettings,
) -> Result<(Judged, OccupantOutcome), String> {
    let (mut t_ms, mut decel_g, mut exc) = (Vec::new(), Vec::new(), Vec::new());
    let hw = RestraintHardware::default();
    let out = physics::simulate_occupant_observed(pulse, occ, set, &hw, |t, x, a| {
        t_ms.push(t * 1e3);
        decel_g.push(physics::mps2_to_g(a));
        exc.push(x * 1e3);
    })
    .map_err(|e| format!("occupant simulation: {e:?}"))?;
    let fired = |t: f64, on: bool| (on && t < NEVER_S).then_some(t * 1e3);
    Ok((
        Judged {
            load_limiter_kn: set.load_limiter_n * 1e-3,
            airbag_level_kn: set.airbag_force_n * 1e-3,
            pretensioner_ms: fired(set.pretensioner_time_s, occ.belted),
            airbag_ms: fired(set.airbag_time_s, set.airbag_force_n > 0.0),
            a_max_g: physics::mps2_to_g(out.max_decel_mps2),
            a_mean_g: physics::mps2_to_g(out.mean_decel_mps2),
            excursion_mm: out.max_excursion_m * 1e3,
            available_mm: out.available_ride_down_m * 1e3,
            bottomed_out: out.bottomed_out,
            t_ms,
            decel_g,
            excursion_trace_mm: exc,
        },
        out,
    ))
}

/// Inputs of the commanded restraint, relative to the true contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Commanded {
    /// Pretensioner fire time [s after contact], `None` = not fired (or released before contact).
    pub pretensioner_s: Option<f64>,
    /// Load-limiter level [kN], `None` = no belt command received.
    pub load_limiter_kn: Option<f64>,
    /// Airbag fire time [s after contact] and level [kN].
    pub airbag: Option<(f64, f64)>,
}

impl Commanded {
    /// Settings for the physics; a missing limiter level falls back to `reference`'s.
    pub fn settings(&self, reference: &RestraintSettings) -> RestraintSettings {
        RestraintSettings {
            load_limiter_n: self
                .load_limiter_kn
                .map_or(reference.load_limiter_n, |k| k * 1e3),
            airbag_force_n: self.airbag.map_or(0.0, |a| a.1 * 1e3),
            pretensioner_time_s: self.pretensioner_s.unwrap_or(NEVER_S),
            airbag_time_s: self.airbag.map_or(NEVER_S, |a| a.0),
        }
    }
}

/// Derives [`Commanded`] from the module state machines, the true contact [ns].
pub fn commanded(m: &crate::commands::Modules, contact_ns: u64) -> Commanded {
    let rel = |t_ns: u64| (t_ns as f64 - contact_ns as f64) * 1e-9;
    // Pretensioner: the last fire that was not undone by a release before contact.
    let mut pret: Option<u64> = None;
    for a in &m.actions {
        match a.what.as_str() {
            "pretensioner_fire" if pret.is_none() => pret = Some(a.t_ns),
            "pretensioner_release" if a.t_ns <= contact_ns => pret = None,
            _ => {}
        }
    }
    // Saturating: without a contact the caller passes u64::MAX ("never").
    let latch_ns = contact_ns.saturating_add((LIMITER_LATCH_AFTER_CONTACT_S * 1e9) as u64);
    Commanded {
        pretensioner_s: pret.map(rel),
        load_limiter_kn: m.limiter_at(latch_ns),
        airbag: m.action("airbag_fire").map(|a| (rel(a.t_ns), a.level_kn)),
    }
}

/// Reference settings as fired by a conventional ECU for a crash of true ego Δv.
pub fn reference_as_fired(
    reference: &RestraintSettings,
    ego_delta_v_mps: f64,
) -> RestraintSettings {
    let ebs_kph = ego_delta_v_mps * 3.6 / (1.0 + physics::defaults::RESTITUTION);
    if ebs_kph < REFERENCE_NO_FIRE_EBS_KPH {
        RestraintSettings {
            airbag_force_n: 0.0,
            airbag_time_s: NEVER_S,
            ..*reference
        }
    } else {
        *reference
    }
}

/// What [`evaluate`] found: the true crash and the occupant outcome comparison.
#[derive(Clone, Debug)]
pub struct Evaluated {
    /// The true crash.
    pub true_crash: crate::report::TrueCrash,
    /// Adaptive (as commanded and as planned) vs reference vs ideal.
    pub outcome: crate::report::Outcome,
}

/// Judges what `modules` did against the scenario's TRUE crash (`truth`, contact at
/// `contact_ns` on the modules' clock): the restraint as commanded (receive times), the same
/// levels at the ECU's planned times, and the reference restraint as a conventional ECU fires
/// it. `Ok(None)` when the true physics has no collision.
///
/// # Errors
/// An occupant simulation failed (invalid settings).
pub fn evaluate(
    scenario: &world::Scenario,
    truth: &world::Truth,
    modules: &crate::commands::Modules,
    contact_ns: u64,
    reference: &physics::reference::ReferenceRestraint,
) -> Result<Option<Evaluated>, String> {
    let Some(crash) = truth.collision else {
        return Ok(None);
    };
    let true_crash = crate::report::TrueCrash {
        closing_speed_kph: truth.closing_speed_at_contact_mps() * 3.6,
        delta_v_kph: crash.vehicle.delta_v_mps * 3.6,
        a_max_g: physics::mps2_to_g(crash.vehicle.a_max_mps2),
        a_mean_g: physics::mps2_to_g(crash.vehicle.a_mean_mps2),
        crush_mm: crash.vehicle.crush_m * 1e3,
        required_ms: truth.required_fire_ms(),
    };
    let pulse = truth.pulse.ego_pulse();
    let occ = OccupantInput {
        mass_kg: scenario.occupant.mass_kg,
        chest_to_wheel_m: scenario.occupant.chest_to_wheel_mm * 1e-3,
        belted: scenario.occupant.belted,
    };
    let ref_set = reference.settings();
    let commanded = commanded(modules, contact_ns);
    let (adaptive, out_a) = judge(&pulse, &occ, &commanded.settings(&ref_set))?;
    let (refj, _) = judge(
        &pulse,
        &occ,
        &reference_as_fired(&ref_set, crash.vehicle.delta_v_mps),
    )?;
    let sum_a = adaptive.a_max_g + adaptive.a_mean_g;
    let sum_r = refj.a_max_g + refj.a_mean_g;
    // The same levels at the ECU's PLANNED times (relative to its predicted contact ≈ the true
    // one): separates the plan's quality from command timing.
    let planned = Commanded {
        pretensioner_s: commanded.pretensioner_s.and(
            modules
                .action("pretensioner_fire")
                .map(|a| a.planned_ms * 1e-3),
        ),
        load_limiter_kn: commanded.load_limiter_kn,
        airbag: modules
            .action("airbag_fire")
            .map(|a| (a.planned_ms * 1e-3, a.level_kn)),
    };
    let adaptive_planned = judge(&pulse, &occ, &planned.settings(&ref_set))
        .ok()
        .map(|j| j.0);
    Ok(Some(Evaluated {
        true_crash,
        outcome: crate::report::Outcome {
            adaptive_planned,
            adaptive_no_worse: no_worse(&adaptive, &refj),
            change_pct: if sum_r > 0.0 {
                (sum_a / sum_r - 1.0) * 100.0
            } else {
                0.0
            },
            ideal_g: physics::mps2_to_g(out_a.ideal_decel_mps2),
            adaptive,
            reference: refj,
        },
    }))
}

/// True when the adaptive outcome is no worse than the reference: no bottoming-out the
/// reference avoided, and a_max + a_mean within [`NO_WORSE_TOLERANCE`].
pub fn no_worse(adaptive: &Judged, reference: &Judged) -> bool {
    if adaptive.bottomed_out && !reference.bottomed_out {
        return false;
    }
    adaptive.a_max_g + adaptive.a_mean_g
        <= (reference.a_max_g + reference.a_mean_g) * (1.0 + NO_WORSE_TOLERANCE)
}

/// The repository file the ECU reads its reference restraint from by default.
pub const REFERENCE_FILE: &str = "data/reference-restraint.toml";

/// Where the judge's reference restraint came from ([`reference_restraint`]).
#[derive(Debug, Clone, PartialEq)]
pub enum ReferenceSource {
    /// This file.
    File(std::path::PathBuf),
    /// The copy built into the binary, and why no file was used.
    BuiltIn(String),
}

/// The reference restraint the judge compares against, and where it came from: `path` when
/// given (an error if it cannot be read); else the repository's [`REFERENCE_FILE`] as the ECU
/// finds it — the first folder holding it walking up from the current folder, then from the
/// executable's —, so that editing that file changes the ECU and the judge together; else,
/// missing or unreadable as for the ECU, the copy built into the binary (with the reason).
pub fn reference_restraint(
    path: Option<&std::path::Path>,
) -> Result<(physics::reference::ReferenceRestraint, ReferenceSource), String> {
    use physics::reference::ReferenceRestraint;
    if let Some(p) = path {
        return Ok((
            ReferenceRestraint::load(p)?,
            ReferenceSource::File(p.to_path_buf()),
        ));
    }
    let builtin =
        |why: String| ReferenceRestraint::builtin().map(|r| (r, ReferenceSource::BuiltIn(why)));
    match host::files::find_upwards(std::path::Path::new(REFERENCE_FILE)) {
        Some(p) => match ReferenceRestraint::load(&p) {
            Ok(r) => Ok((r, ReferenceSource::File(p))),
            Err(e) => builtin(e),
        },
        None => builtin(format!("no {REFERENCE_FILE} above the current folder")),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_judge_reads_the_repositorys_reference_file_as_the_ecu_does() {
        // The tests run in actuator-stubs/: the repository's file is one folder up.
        let (r, from) = super::reference_restraint(None).expect("loads");
        let super::ReferenceSource::File(from) = from else {
            panic!("not the repository's file: {from:?}")
        };
        assert!(from.ends_with(super::REFERENCE_FILE), "{}", from.display());
        let file = physics::reference::ReferenceRestraint::load(&from).expect("file");
        assert_eq!(r, file);
        // A file named on the command line is that file, and an unreadable one an error.
        let missing = std::path::Path::new("/nonexistent-reference.toml");
        assert!(super::reference_restraint(Some(missing)).is_err());
    }

    use super::*;
    use crate::commands::{Decoded, Modules};

    fn belt(p: &str, kn: f64) -> Decoded {
        Decoded::Belt {
            pretensioner: p.into(),
            source: "adaptive".into(),
            load_limiter_kn: kn,
            pretensioner_fire_time_ms: 0.0,
        }
    }

    /// Without any contact (stubs stopped before the bench truth arrived) the caller passes
    /// "never" = u64::MAX: no overflow, the last level counts.
    #[test]
    fn no_contact_is_never_and_does_not_overflow() {
        let mut m = Modules::default();
        m.apply(1_000, &belt("fire", 3.0));
        let k = commanded(&m, u64::MAX);
        assert_eq!(k.load_limiter_kn, Some(3.0));
        assert!(k.pretensioner_s.is_some_and(|s| s < 0.0));
    }

    #[test]
    fn release_before_contact_undoes_the_pre_crash_fire() {
        let c = 1_000_000_000u64;
        let mut m = Modules::default();
        m.apply(c - 50_000_000, &belt("fire", 3.0));
        m.apply(c - 20_000_000, &belt("release", 3.0));
        assert_eq!(commanded(&m, c).pretensioner_s, None);
        m.apply(c + 5_000_000, &belt("fire", 5.0));
        let k = commanded(&m, c);
        assert!((k.pretensioner_s.unwrap() - 0.005).abs() < 1e-9);
        assert_eq!(k.load_limiter_kn, Some(5.0));
        assert_eq!(k.airbag, None);
    }

    #[test]
    fn pre_crash_fire_counts_with_negative_time() {
        let c = 2_000_000_000u64;
        let mut m = Modules::default();
        m.apply(c - 40_000_000, &belt("fire", 4.0));
        m.apply(
            c + 12_000_000,
            &Decoded::Airbag {
                armed: true,
                fire: true,
                source: "adaptive".into(),
                stage: 1,
                force_level_kn: 7.0,
                fire_time_ms: 12.0,
            },
        );
        let k = commanded(&m, c);
        assert!((k.pretensioner_s.unwrap() + 0.040).abs() < 1e-9);
        let (t, l) = k.airbag.unwrap();
        assert!((t - 0.012).abs() < 1e-9 && l == 7.0);
    }

    #[test]
    fn reference_does_not_fire_below_the_no_fire_limit() {
        let r = RestraintSettings {
            load_limiter_n: 4e3,
            airbag_force_n: 6e3,
            pretensioner_time_s: 0.01,
            airbag_time_s: 0.01,
        };
        // EBS = Δv / 1.1: 21.9 km/h Δv → 19.9 km/h EBS (no fire), 22.1 → 20.1 (fire).
        assert_eq!(reference_as_fired(&r, 21.9 / 3.6).airbag_force_n, 0.0);
        assert_eq!(reference_as_fired(&r, 22.1 / 3.6).airbag_force_n, 6e3);
    }

    #[test]
    fn no_airbag_and_no_belt_strikes_through_in_a_real_crash() {
        // Closed-form sanity of the judge: a 40 g·(0.1 s) square pulse (Δv 39 m/s… capped):
        // use a 20 g, 80 ms square pulse (Δv 15.7 m/s); an unrestrained, unbelted occupant
        // travels far beyond 240 mm of ride-down and bottoms out.
        let step = 1e-4;
        let pulse: Vec<f64> = (0..800)
            .map(|_| -20.0 * physics::defaults::STANDARD_GRAVITY_MPS2)
            .collect();
        let p = physics::CompartmentPulse {
            step_s: step,
            accel_mps2: &pulse,
        };
        let occ = OccupantInput {
            mass_kg: 75.0,
            chest_to_wheel_m: 0.3,
            belted: false,
        };
        let none = Commanded {
            pretensioner_s: None,
            load_limiter_kn: None,
            airbag: None,
        };
        let r = RestraintSettings {
            load_limiter_n: 4e3,
            airbag_force_n: 6e3,
            pretensioner_time_s: 0.01,
            airbag_time_s: 0.01,
        };
        let (j, _) = judge(&p, &occ, &none.settings(&r)).unwrap();
        assert!(j.bottomed_out && j.airbag_ms.is_none());
        let (jr, _) = judge(&p, &occ, &r).unwrap();
        assert!(!no_worse(&j, &jr) || jr.bottomed_out);
        assert_eq!(j.t_ms.len(), j.decel_g.len());
        assert!(!j.t_ms.is_empty());
    }
}
