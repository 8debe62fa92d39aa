//! The accelerometer variants: a dead or stuck sensor must show on the bus in time.

use super::*;

/// For a dead or stuck accelerometer variant: when the sensor failed (ms rel. contact) and
/// how its fault flag showed after that.
pub(super) fn accel_failure_seen(v: Variant, r: &Report) -> Option<(f64, FaultSeen)> {
    let (Variant::AccelDead { before_contact_s } | Variant::AccelStuck { before_contact_s }) = v
    else {
        return None;
    };
    let from_ms = -before_contact_s * 1e3;
    Some((from_ms, fault_seen(&r.ecu_faults, "accel_sensor", from_ms)))
}

/// Documented bound on "sensor failed → fault bit on the bus": the monitor's limit (no batch
/// for `accel_timeout_ms`, the same reading for `accel_stuck_ms`) plus one EcuStatus period.
pub(super) fn accel_fault_bound_ms(v: Variant) -> f64 {
    let cfg = restraint::CycleConfig::default();
    let limit = match v {
        Variant::AccelStuck { .. } => cfg.accel_stuck_ms,
        _ => cfg.accel_timeout_ms,
    };
    limit + bus::EcuStatus::MESSAGE_CYCLE_TIME_MS as f64
}

/// The checks of a scenario variant: a misreported crash is no worse than the reference
/// restraint (judged on the commanded levels at the planned times where the route's timing is
/// emulated, as the bench's library test does); a dead or stuck accelerometer is on the bus
/// before the contact.
pub(super) fn judge_variant(checks: &mut Checks, v: Variant, r: &Report) {
    match v {
        Variant::MassMisreport { .. } | Variant::SpeedBias { .. } => {
            let emulated = crate::Route::current().timing_emulated();
            let verdict = r.outcome.as_ref().map(|o| {
                let judged = match (&o.adaptive_planned, emulated) {
                    (Some(planned), true) => planned,
                    _ => &o.adaptive,
                };
                (
                    actuator_stubs::outcome::no_worse(judged, &o.reference),
                    format!(
                        "{:+.1} % a_max + a_mean vs the reference restraint{}{}",
                        o.change_pct,
                        if judged.bottomed_out {
                            ", bottomed out"
                        } else {
                            ""
                        },
                        if emulated {
                            " (commanded levels at planned times)"
                        } else {
                            ""
                        }
                    ),
                )
            });
            checks.check(
                "no worse than the reference restraint",
                verdict.as_ref().is_some_and(|(ok, _)| *ok),
                verdict.map_or("no outcome (no contact?)".into(), |(_, d)| d),
            );
        }
        Variant::AccelDead { .. } | Variant::AccelStuck { .. } => {
            let Some((from_ms, seen)) = accel_failure_seen(v, r) else {
                return;
            };
            // A precondition, like "ECU in Normal when the fault began": a fault bit still set
            // (an emulated start-up that starved the sensor) hides the detection.
            checks.check(
                ACCEL_HEALTHY_CHECK,
                !matches!(seen, FaultSeen::AlreadySet(_)),
                match seen {
                    FaultSeen::AlreadySet(t) => format!(
                        "FaultAccelSensor set since {t:+.0} ms, the sensor failed at {from_ms:+.0} ms"
                    ),
                    _ => "fault bit clear".into(),
                },
            );
            if let FaultSeen::AlreadySet(_) = seen {
                return;
            }
            checks.check(
                "accelerometer fault on the bus before the crash",
                matches!(seen, FaultSeen::Raised(t) if t < 0.0),
                match seen {
                    FaultSeen::Raised(t) => format!(
                        "FaultAccelSensor at {t:+.0} ms rel. contact, the sensor failed at \
                         {from_ms:+.0} ms"
                    ),
                    _ => format!("never reported after the sensor failed at {from_ms:+.0} ms"),
                },
            );
            if let FaultSeen::Raised(t) = seen {
                let bound_ms = accel_fault_bound_ms(v) + DETECTION_SLACK_MS;
                checks.check(
                    ACCEL_DETECTION_TIME_CHECK,
                    t - from_ms <= bound_ms,
                    format!(
                        "{:.0} ms (monitor limit + one EcuStatus period + {DETECTION_SLACK_MS:.0} ms: \
                         {bound_ms:.0} ms)",
                        t - from_ms
                    ),
                );
            }
        }
        Variant::AsIs | Variant::Dropout { .. } | Variant::Frozen { .. } => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_accelerometer_fault_counts_only_when_it_rises_after_the_sensor_failed() {
        let f = |names: &[&str]| names.iter().map(|n| (*n).to_owned()).collect::<Vec<_>>();
        // The accel-dead case of a clean-clone run: the start-up report (no samples yet) long
        // before the failure at −600 ms, then the detection 52 ms after it.
        let run = vec![
            (
                -3760.4,
                f(&["vehicle_input", "object_input", "accel_sensor"]),
            ),
            (-3685.1, f(&["vehicle_input", "object_input", "overrun"])),
            (-3669.5, f(&["overrun"])),
            (-548.4, f(&["accel_sensor", "overrun"])),
            (29.7, f(&["object_input", "accel_sensor", "overrun"])),
        ];
        assert_eq!(
            fault_seen(&run, "accel_sensor", -600.0),
            FaultSeen::Raised(-548.4)
        );
        // Without the detection the start-up report must not stand in for it.
        let undetected: Vec<_> = run.iter().take(3).cloned().collect();
        assert_eq!(
            fault_seen(&undetected, "accel_sensor", -600.0),
            FaultSeen::Never
        );
        // Still set from start-up when the sensor failed: nothing can be seen.
        let starved = vec![
            (-3760.4, f(&["accel_sensor"])),
            (29.7, f(&["accel_sensor"])),
        ];
        assert_eq!(
            fault_seen(&starved, "accel_sensor", -600.0),
            FaultSeen::AlreadySet(-3760.4)
        );
        assert!(
            accel_fault_bound_ms(Variant::AccelDead {
                before_contact_s: 0.6
            }) > 52.0
        );
    }
}
