//! The one judge of a scenario's `[expect]` block: the offline bench and the
//! real bench read a run into [`Observed`] their own way, and [`check`] compares it with every
//! key the file sets. `offline-bench` and `hil-bench` exit non-zero on any mismatch (unless
//! `--no-expect`), naming the scenario, the key, the expected and the measured value; the
//! suite's library tests use the same judge.

use crate::offline::OfflineRun;
use actuator_stubs::report::Report;
use world::Scenario;

/// What a run showed, as the `[expect]` keys read it.
#[derive(Debug, Clone, Copy)]
pub struct Observed<'a> {
    /// True contact [s after the scenario start] (`None`: no contact).
    pub contact_s: Option<f64>,
    /// The airbag module fired.
    pub airbag_fired: bool,
    /// The pretensioner fired before the true contact and was still fired at it.
    pub pretensioner_before_contact: bool,
    /// The pretensioner was released at some point.
    pub pretensioner_released: bool,
    /// EcuStatus mode changes: (ms after the contact, or after the start without one, name).
    pub modes: &'a [(f64, String)],
    /// EcuStatus fault-flag changes, on the time base of `modes`.
    pub faults: &'a [(f64, Vec<String>)],
    /// The ECU planned with the V2X station's mass (its `v2x_lookups` counter).
    pub v2x_planned: bool,
}

impl<'a> Observed<'a> {
    /// An offline run (`offline-bench`, the library tests).
    pub fn offline(r: &'a OfflineRun) -> Self {
        let before = r.action("pretensioner_fire").is_some_and(|a| a.0 < 0.0)
            && r.action("pretensioner_release")
                .is_none_or(|rel| rel.0 >= 0.0);
        Self {
            contact_s: r.contact_s,
            airbag_fired: r.action("airbag_fire").is_some(),
            pretensioner_before_contact: before,
            pretensioner_released: r.action("pretensioner_release").is_some(),
            modes: &r.modes,
            faults: &r.faults,
            v2x_planned: r.v2x_lookups > 0,
        }
    }

    /// A run of the real processes, from the actuator stubs' report and the ECU's
    /// (`ecu-report.json`; `None`: it wrote none, and nothing the ECU counted is observed).
    pub fn bench(r: &'a Report, ecu_report: Option<&serde_json::Value>) -> Self {
        let v2x_lookups = crate::ecu_counter(ecu_report, "v2x_lookups");
        Self {
            contact_s: (r.contact_ns != 0)
                .then(|| r.contact_ns.saturating_sub(r.start_ns) as f64 * 1e-9),
            airbag_fired: r.airbag_fired,
            pretensioner_before_contact: r.pretensioner_before_contact,
            pretensioner_released: r.pretensioner_released,
            modes: &r.ecu_modes,
            faults: &r.ecu_faults,
            v2x_planned: v2x_lookups.is_some_and(|n| n > 0),
        }
    }
}

/// One `[expect]` key the run did not meet.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mismatch {
    /// Scenario name.
    pub scenario: String,
    /// The key as written in the file (`airbag_fires`, …).
    pub key: &'static str,
    /// What the file expects.
    pub expected: bool,
    /// What the run showed.
    pub measured: bool,
}

impl std::fmt::Display for Mismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: [expect] {} = {}, measured {}",
            self.scenario, self.key, self.expected, self.measured
        )
    }
}

/// Every key of `s.expect` that `o` does not meet (empty: all met, or none set).
pub fn check(s: &Scenario, o: &Observed<'_>) -> Vec<Mismatch> {
    let e = &s.expect;
    let measured = [
        ("contact", e.contact, o.contact_s.is_some()),
        ("airbag_fires", e.airbag_fires, o.airbag_fired),
        (
            "pretensioner_before_contact",
            e.pretensioner_before_contact,
            o.pretensioner_before_contact,
        ),
        (
            "pretensioner_released",
            e.pretensioner_released,
            o.pretensioner_released,
        ),
        // After having been Normal: every run starts in ReferenceFallback (and sends the
        // reference settings) until its inputs are fresh, which would make any run pass.
        (
            "reference_fallback",
            e.reference_fallback,
            crate::fell_back_after_normal(o.modes).is_some(),
        ),
        // Raised after the sensor failed (not the start-up report) and before the contact.
        (
            "accel_fault_before_contact",
            e.accel_fault_before_contact,
            crate::accel_fault_before_contact(s, o.faults, o.contact_s),
        ),
        ("v2x_planned", e.v2x_planned, o.v2x_planned),
    ];
    measured
        .into_iter()
        .filter_map(|(key, want, got)| {
            want.filter(|w| *w != got).map(|expected| Mismatch {
                scenario: s.name.clone(),
                key,
                expected,
                measured: got,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(expect: &str) -> Scenario {
        let text = format!(
            "name = \"x\"\nduration_s = 1.0\n[ego]\nmass_kg = 1785\nclass = 4\nspeed_kph = 50\n\
             [opponent]\nkind = \"barrier\"\ninitial_distance_m = 900.0\n\
             [sensor]\nmass_estimate_kg = 3000\n\
             [occupant]\nmass_kg = 75\nchest_to_wheel_mm = 300\nbelted = true\n[expect]\n{expect}"
        );
        Scenario::parse("x.toml", &text).expect("scenario")
    }

    #[test]
    fn every_key_set_is_judged_and_only_those() {
        let modes = vec![
            (0.5, "ReferenceFallback".to_owned()),
            (20.0, "Normal".to_owned()),
        ];
        let o = Observed {
            contact_s: None,
            airbag_fired: true,
            pretensioner_before_contact: false,
            pretensioner_released: false,
            modes: &modes,
            faults: &[],
            v2x_planned: false,
        };
        assert!(check(&scenario(""), &o).is_empty());
        let bad = check(
            &scenario(
                "contact = false\nairbag_fires = false\nreference_fallback = true\nv2x_planned = true",
            ),
            &o,
        );
        let keys: Vec<_> = bad
            .iter()
            .map(|m| (m.key, m.expected, m.measured))
            .collect();
        assert_eq!(
            keys,
            [
                ("airbag_fires", false, true),
                ("reference_fallback", true, false),
                ("v2x_planned", true, false)
            ]
        );
        assert_eq!(
            bad[0].to_string(),
            "x: [expect] airbag_fires = false, measured true"
        );
    }
}
