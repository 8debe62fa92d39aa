//! The diagnostics record's numeric fields, listed once for both formats: the MCAP's
//! `/ecu/diagnostics` messages (serialized straight from this list, no intermediate JSON tree:
//! the recording's cost is mostly the diagnostics) and the MF4's channels. A unit test holds
//! the list to the record's own serialization, so a field added to
//! [`signals::EcuDiagnostics`] and not here fails the build's tests instead of going missing.

use serde::ser::{Serialize, SerializeMap, Serializer};
use signals::{Degraded, EcuDiagnostics, EcuMode};

/// A field's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Num {
    /// An unsigned integer field.
    U(u64),
    /// An `f32` field (NaN: not known).
    F(f32),
}

/// One numeric field of the record.
pub(crate) struct DiagField {
    pub name: &'static str,
    pub unit: &'static str,
    /// Bytes of the field's type (1, 4 or 8).
    pub bytes: usize,
    pub float: bool,
    pub value: fn(&EcuDiagnostics) -> Num,
}

impl Num {
    /// Little-endian bytes; the field's own width is the first `bytes` of them.
    pub fn le_bytes(self, bytes: usize) -> [u8; 8] {
        let mut b = [0; 8];
        match self {
            Num::U(v) => b = v.to_le_bytes(),
            Num::F(v) => b[..4].copy_from_slice(&v.to_le_bytes()),
        }
        debug_assert!(bytes <= 8);
        b
    }
}

macro_rules! fields {
    ($( $name:ident : $ty:ident, $unit:literal; )*) => {
        [$( DiagField {
            name: stringify!($name),
            unit: $unit,
            bytes: std::mem::size_of::<$ty>(),
            float: fields!(@float $ty),
            value: |d| fields!(@num $ty, d.$name),
        } ),*]
    };
    (@float f32) => { true };
    (@float $t:ident) => { false };
    (@num f32, $v:expr) => { Num::F($v) };
    (@num $t:ident, $v:expr) => { Num::U(u64::from($v)) };
}

/// Every numeric field of [`EcuDiagnostics`] but its time stamp (the message's time) — the
/// predicted pulse, an array, travels on `/ecu/predicted_pulse`.
pub(crate) const DIAG_FIELDS: [DiagField; 28] = fields! {
    cycle_count: u64, "";
    overrun_count: u64, "";
    last_exec_ns: u64, "ns";
    wake_latency_ns: u64, "ns";
    last_object_sequence: u64, "";
    last_accel_sequence: u64, "";
    object_samples_rx: u64, "";
    accel_batches_rx: u64, "";
    predicted_delta_v_mps: f32, "m/s";
    predicted_a_max_mps2: f32, "m/s²";
    predicted_a_mean_mps2: f32, "m/s²";
    predicted_contact_time_s: f32, "s";
    time_to_contact_s: f32, "s";
    time_to_contact_sigma_s: f32, "s";
    closing_speed_mps: f32, "m/s";
    closing_speed_sigma_mps: f32, "m/s";
    opponent_mass_kg: f32, "kg";
    opponent_mass_sigma_kg: f32, "kg";
    pulse_dt_s: f32, "s";
    pulse_points: u32, "";
    belt_force_limit_n: f32, "N";
    pretensioner_time_s: f32, "s";
    airbag_time_s: f32, "s";
    airbag_stage: u8, "";
    mode: u8, "";
    pretensioner_fired: u8, "";
    airbag_fired: u8, "";
    degraded_reasons: u32, "";
};

/// A `/ecu/diagnostics` message: the record field by field (NaN as null, as serde_json writes
/// it) but for the predicted pulse's points, with the mode's and the degraded reasons' names
/// beside their numbers.
pub struct DiagnosticsMessage<'a>(pub &'a EcuDiagnostics);

impl Serialize for DiagnosticsMessage<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let d = self.0;
        let mut m = s.serialize_map(Some(DIAG_FIELDS.len() + 3))?;
        m.serialize_entry("timestamp_ns", &d.timestamp_ns)?;
        for f in &DIAG_FIELDS {
            match (f.value)(d) {
                Num::U(v) => m.serialize_entry(f.name, &v)?,
                Num::F(v) if v.is_finite() => m.serialize_entry(f.name, &v)?,
                Num::F(_) => m.serialize_entry(f.name, &())?,
            }
        }
        m.serialize_entry("mode_name", mode_name(d.mode))?;
        m.serialize_entry("degraded", &DegradedNames(d.degraded_reasons))?;
        m.end()
    }
}

/// A mode byte's name (`unknown` for a byte no mode has): the diagnostics' `mode_name` and the
/// mode-change log's.
pub(crate) fn mode_name(mode: u8) -> &'static str {
    EcuMode::from_u8(mode).map_or("unknown", EcuMode::name)
}

/// The names of the degraded-reason bits set in `bits`, lower case (unknown bits dropped): the
/// diagnostics' `degraded` and the mode-change log's.
pub(crate) fn degraded_names(bits: u32) -> impl Iterator<Item = String> {
    Degraded::from_bits_truncate(bits)
        .iter_names()
        .map(|(n, _)| n.to_ascii_lowercase())
}

/// The names of the degraded-reason bits, lower case.
struct DegradedNames(u32);

impl Serialize for DegradedNames {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(degraded_names(self.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The list is the record: every field serde serializes is in it (or is the time stamp or
    /// the pulse array), and each value read through the list is the field's.
    #[test]
    fn the_list_holds_every_field_of_the_record_and_reads_it() {
        let mut d = EcuDiagnostics::ZERO;
        d.cycle_count = 7;
        d.closing_speed_mps = 12.5;
        d.degraded_reasons = 0b101;
        let serde = serde_json::to_value(d).unwrap();
        let keys: Vec<&str> = serde
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        let mut listed: Vec<&str> = DIAG_FIELDS.iter().map(|f| f.name).collect();
        listed.extend(["timestamp_ns", "pulse_accel_mps2"]);
        let (mut a, mut b) = (keys.clone(), listed.clone());
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "EcuDiagnostics' fields vs DIAG_FIELDS");
        let msg = serde_json::to_value(DiagnosticsMessage(&d)).unwrap();
        for f in &DIAG_FIELDS {
            let (got, want) = (&msg[f.name], &serde[f.name]);
            assert_eq!(got, want, "{}", f.name);
        }
        assert_eq!(msg["degraded"].as_array().unwrap().len(), 2);
        assert_eq!(msg["mode_name"], "startup");
    }
}
