//! JSON Schemas and JSON messages of the CAN topics, from the DBC's generated tables.

use bus::{MessageInfo, RawFrame, SignalInfo, CAN_EFF_FLAG};
use serde_json::{json, Map, Value};
use signals::{CrashAccelSample, EcuDiagnostics, EcuMode, ObjectState};

/// Schema name of `/can/raw`.
pub const RAW_FRAME_SCHEMA: &str = "restraint_bench.CanFrame";

/// JSON Schema of a raw frame on `/can/raw`.
pub fn raw_frame_schema() -> Value {
    json!({
        "title": RAW_FRAME_SCHEMA,
        "description": "One classic CAN data frame as candump logged it",
        "type": "object",
        "properties": {
            "interface": { "type": "string", "description": "CAN interface it was logged on" },
            "id": { "type": "integer", "description": "identifier (without the extended flag)" },
            "extended": { "type": "boolean", "description": "29-bit identifier" },
            "dlc": { "type": "integer", "minimum": 0, "maximum": 8 },
            "data": { "type": "array", "items": { "type": "integer", "minimum": 0, "maximum": 255 } },
            "message": { "type": ["string", "null"], "description": "DBC message name of the id" }
        },
        "required": ["interface", "id", "extended", "dlc", "data", "message"]
    })
}

/// A raw frame as a `/can/raw` message.
pub fn raw_frame(interface: &str, f: &RawFrame) -> Value {
    let extended = f.id & CAN_EFF_FLAG != 0;
    let id = f.id & !CAN_EFF_FLAG;
    let message = (!extended)
        .then(|| bus::message_info(id))
        .flatten()
        .map(|m| m.name);
    json!({
        "interface": interface,
        "id": id,
        "extended": extended,
        "dlc": f.payload().len(),
        "data": f.payload(),
        "message": message,
    })
}

/// Schema name of `/can/error`.
pub const ERROR_FRAME_SCHEMA: &str = "restraint_bench.CanErrorFrame";

/// JSON Schema of an error frame on `/can/error`.
pub fn error_frame_schema() -> Value {
    let names: Vec<Value> = bus::candump::ASAM_ERROR_TYPES
        .iter()
        .map(|(v, n)| json!({ "const": v, "title": n }))
        .collect();
    json!({
        "title": ERROR_FRAME_SCHEMA,
        "description": "One CAN error frame as candump logged it: a controller's report of a bus error",
        "type": "object",
        "properties": {
            "interface": { "type": "string", "description": "CAN interface it was logged on" },
            "class": { "type": "integer", "description": "Linux error classes (CAN_ERR_* bits of the id, linux/can/error.h)" },
            "data": { "type": "array", "items": { "type": "integer", "minimum": 0, "maximum": 255 }, "description": "the report's eight detail bytes" },
            "error_type": { "type": "integer", "oneOf": names, "description": "ASAM MDF bus logging's ErrorType" },
            "text": { "type": "string", "description": "every cause in words" }
        },
        "required": ["interface", "class", "data", "error_type", "text"]
    })
}

/// An error frame as a `/can/error` message.
pub fn error_frame(e: &bus::candump::LoggedErrorFrame) -> Value {
    json!({
        "interface": e.device,
        "class": e.class,
        "data": e.data,
        "error_type": e.error_type,
        "text": e.text,
    })
}

/// Schema name of `/can/<message>`.
pub fn message_schema_name(m: &MessageInfo) -> String {
    format!("restraint_bench.dbc.{}", m.name)
}

/// JSON Schema of a DBC message's topic: one number per signal (its physical value), described
/// by the DBC's comment, unit, range and bit layout, and a signal with a value table (`VAL_`)
/// by its names: each
/// value a `oneOf` entry titled with the DBC's name (as cantools' `decode_choices` gives it),
/// listed in the description too.
pub fn message_schema(m: &MessageInfo, signals: &[SignalInfo]) -> Value {
    let mut props = Map::new();
    for s in signals {
        let mut p = Map::new();
        let integral = decodes_to_integer(s);
        p.insert(
            "type".into(),
            json!(if integral { "integer" } else { "number" }),
        );
        p.insert(
            "description".into(),
            json!(
                format!(
                    "{}{}{}{}[{} … {}], bits {}+{}{}, phys = raw × {} + {}",
                    s.comment,
                    if s.comment.is_empty() { "" } else { " — " },
                    s.unit,
                    if s.unit.is_empty() { "" } else { ", " },
                    s.min,
                    s.max,
                    s.start_bit,
                    s.size,
                    if s.signed { " signed" } else { "" },
                    s.factor,
                    s.offset
                ) + &value_names(s)
            ),
        );
        if !s.values.is_empty() {
            p.insert(
                "oneOf".into(),
                Value::Array(
                    s.values
                        .iter()
                        .map(|&(raw, name)| json!({ "const": phys_of(s, raw), "title": name }))
                        .collect(),
                ),
            );
        }
        props.insert(s.name.into(), Value::Object(p));
    }
    json!({
        "title": message_schema_name(m),
        "description": format!(
            "DBC message {} (id {:#05x}, {} bytes, sent by {}), decoded from bus/restraint.dbc",
            m.name, m.id, m.size, m.transmitter
        ),
        "type": "object",
        "properties": props,
        "required": signals.iter().map(|s| s.name).collect::<Vec<_>>(),
    })
}

/// A value-table signal's names for its description: "; values: 0 = NoFire, 1 = Fire".
fn value_names(s: &SignalInfo) -> String {
    if s.values.is_empty() {
        return String::new();
    }
    let names: Vec<String> = s
        .values
        .iter()
        .map(|&(raw, name)| format!("{} = {name}", phys_of(s, raw)))
        .collect();
    format!("; values: {}", names.join(", "))
}

/// A raw value's physical value as the topic's messages and its value table carry it: an
/// integer where the signal decodes to integers, else `raw · factor + offset`
/// ([`SignalInfo::value`]'s).
fn phys_of(s: &SignalInfo, raw: i64) -> Value {
    if decodes_to_integer(s) {
        json!(raw * s.factor as i64 + s.offset as i64)
    } else {
        json!(raw as f64 * s.factor + s.offset)
    }
}

/// Integral step and offset: the signal decodes to integers, as cantools gives them (schema
/// and message agree on it).
fn decodes_to_integer(s: &SignalInfo) -> bool {
    s.factor.fract() == 0.0 && s.offset.fract() == 0.0
}

/// A frame's signals as its topic's message: every signal as the bits lie (forged and damaged
/// frames included: the recording shows what was on the bus, the verdicts are on
/// `/stubs/commands`).
pub fn message_values(signals: &[SignalInfo], payload: &[u8]) -> Value {
    let mut o = Map::new();
    for s in signals {
        o.insert(s.name.into(), phys_of(s, s.raw(payload)));
    }
    Value::Object(o)
}

/// Schema name of `/truth/world`.
pub const TRUTH_SCHEMA: &str = "restraint_bench.WorldState";

/// JSON Schema of `/truth/world`, derived from the state's own serialization.
pub fn truth_schema(s: &world::truth::WorldState) -> Value {
    let mut v = schema_of(&serde_json::to_value(s).unwrap_or(Value::Null));
    if let Some(o) = v.as_object_mut() {
        o.insert("title".into(), json!(TRUTH_SCHEMA));
        o.insert(
            "description".into(),
            json!("The scenario's closed-form true world every ms (world::Truth::state): what the sensors observe, units in the field names"),
        );
    }
    v
}

/// Schema name of `/ecu/diagnostics`.
pub const DIAGNOSTICS_SCHEMA: &str = "restraint_bench.EcuDiagnostics";

/// Schema name of `/ecu/predicted_pulse`.
pub const PULSE_SCHEMA: &str = "restraint_bench.PredictedPulse";

/// The record's predicted pulse: a message of its own, written when it changes (it changes
/// with each prediction, not each cycle, and is 64 of the record's ~100 numbers).
pub fn predicted_pulse(d: &EcuDiagnostics) -> PulseMessage {
    let n = (d.pulse_points as usize).min(d.pulse_accel_mps2.len());
    PulseMessage {
        pulse_dt_s: d.pulse_dt_s,
        pulse_points: d.pulse_points,
        pulse_accel_mps2: d.pulse_accel_mps2[..n].to_vec(),
        predicted_contact_time_s: d.predicted_contact_time_s,
        predicted_delta_v_mps: d.predicted_delta_v_mps,
        predicted_a_max_mps2: d.predicted_a_max_mps2,
        predicted_a_mean_mps2: d.predicted_a_mean_mps2,
    }
}

/// A `/ecu/predicted_pulse` message (compared with the last one written: only changes are).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PulseMessage {
    pulse_dt_s: f32,
    pulse_points: u32,
    pulse_accel_mps2: Vec<f32>,
    predicted_contact_time_s: f32,
    predicted_delta_v_mps: f32,
    predicted_a_max_mps2: f32,
    predicted_a_mean_mps2: f32,
}

/// JSON Schema of `/ecu/predicted_pulse`.
pub fn predicted_pulse_schema() -> Value {
    let mut z = EcuDiagnostics::ZERO;
    z.pulse_points = 1;
    let mut s = schema_of(&serde_json::to_value(predicted_pulse(&z)).unwrap_or(Value::Null));
    if let Some(o) = s.as_object_mut() {
        o.insert("title".into(), json!(PULSE_SCHEMA));
        o.insert(
            "description".into(),
            json!("The ECU's predicted crash pulse (ego acceleration, m/s², from the predicted contact on, every pulse_dt_s), written when it changes"),
        );
    }
    s
}

/// A diagnostics record as published on iceoryx2, field by field (`diag_fields`) but for the
/// predicted pulse's points (on `/ecu/predicted_pulse`), with the mode's and the degraded
/// reasons' names beside their numbers.
pub fn diagnostics(d: &EcuDiagnostics) -> crate::diag_fields::DiagnosticsMessage<'_> {
    crate::diag_fields::DiagnosticsMessage(d)
}

/// Schema name of `/ecu/log`: Foxglove's well-known log message, shown in its Log panel.
pub const LOG_SCHEMA: &str = "foxglove.Log";

/// Foxglove's `foxglove.Log` JSON Schema (foxglove/schemas, `jsonschema/Log.json`).
pub fn log_schema() -> Value {
    json!({
        "title": LOG_SCHEMA,
        "description": "A log message",
        "type": "object",
        "properties": {
            "timestamp": {
                "type": "object",
                "title": "time",
                "properties": {
                    "sec": { "type": "integer", "minimum": 0 },
                    "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 }
                },
                "description": "Timestamp of log message"
            },
            "level": {
                "title": "foxglove.LogLevel",
                "description": "Log level",
                "oneOf": [
                    { "title": "UNKNOWN", "const": 0 },
                    { "title": "DEBUG", "const": 1 },
                    { "title": "INFO", "const": 2 },
                    { "title": "WARNING", "const": 3 },
                    { "title": "ERROR", "const": 4 },
                    { "title": "FATAL", "const": 5 }
                ]
            },
            "message": { "type": "string", "description": "Log message" },
            "name": { "type": "string", "description": "Process or node name" },
            "file": { "type": "string", "description": "Filename" },
            "line": { "type": "integer", "minimum": 0, "description": "Line number in the file" }
        }
    })
}

/// The `/ecu/log` message of a diagnostics record whose mode or degraded reasons differ from
/// the previous record's (`prev`; `None` for the first): the new mode and reasons, at WARNING
/// while degraded, INFO otherwise.
pub fn mode_change_log(prev: Option<&EcuDiagnostics>, d: &EcuDiagnostics) -> Option<Value> {
    if prev.is_some_and(|p| p.mode == d.mode && p.degraded_reasons == d.degraded_reasons) {
        return None;
    }
    let mode = crate::diag_fields::mode_name(d.mode);
    let reasons: Vec<String> = crate::diag_fields::degraded_names(d.degraded_reasons).collect();
    let mut message = match prev.and_then(|p| EcuMode::from_u8(p.mode)) {
        Some(p) if p as u8 != d.mode => format!("mode {} -> {mode}", p.name()),
        Some(_) => format!("mode {mode}"),
        None => format!("mode {mode} (first record)"),
    };
    if !reasons.is_empty() {
        message.push_str(&format!("; degraded: {}", reasons.join(", ")));
    } else if prev.is_some_and(|p| p.degraded_reasons != 0) {
        message.push_str("; no degraded reason");
    }
    let level = if d.mode == EcuMode::Degraded as u8 || !reasons.is_empty() {
        3
    } else {
        2
    };
    Some(json!({
        "timestamp": {
            "sec": d.timestamp_ns / 1_000_000_000,
            "nsec": d.timestamp_ns % 1_000_000_000
        },
        "level": level,
        "message": message,
        "name": "ecu",
        "file": "",
        "line": 0
    }))
}

/// Schema name of `/sensors/object`.
pub const OBJECT_SCHEMA: &str = "restraint_bench.ObjectState";
/// Schema name of `/sensors/crash_accel` and `/sensors/safing_accel`.
pub const ACCEL_SCHEMA: &str = "restraint_bench.AccelBatch";

/// An object state as the feeds published it (serde of the record, without its padding).
pub fn object(o: &ObjectState) -> Value {
    let mut v = serde_json::to_value(o).unwrap_or(Value::Null);
    if let Some(m) = v.as_object_mut() {
        m.remove("_reserved");
    }
    v
}

/// An accelerometer batch as the feeds published it: its valid samples only, and the time of
/// the newest one (what a cycle that read this batch knew last).
#[derive(serde::Serialize)]
pub struct AccelBatchMessage<'a> {
    first_timestamp_ns: u64,
    newest_sample_ns: u64,
    sequence: u64,
    sample_period_ns: u32,
    count: u32,
    accel_mps2: &'a [f32],
}

/// The sample time of the newest of `n` samples `period_ns` apart from `first_ns`: what a
/// cycle that read the batch knew last.
fn newest_sample_ns(first_ns: u64, n: usize, period_ns: u32) -> u64 {
    first_ns + (n as u64).saturating_sub(1) * u64::from(period_ns)
}

/// The `/sensors/…_accel` message of a batch.
pub fn accel_batch(b: &CrashAccelSample) -> AccelBatchMessage<'_> {
    AccelBatchMessage {
        first_timestamp_ns: b.first_timestamp_ns,
        newest_sample_ns: newest_sample_ns(
            b.first_timestamp_ns,
            b.samples().len(),
            b.sample_period_ns,
        ),
        sequence: b.sequence,
        sample_period_ns: b.sample_period_ns,
        count: b.count,
        accel_mps2: b.samples(),
    }
}

/// Schema name of `/sensors/satellite_left` and `/sensors/satellite_right`.
pub const SATELLITE_SCHEMA: &str = "restraint_bench.SatelliteFrames";

/// A satellite batch as the feeds published it: the raw PSI5 frames (10-bit data + even
/// parity) and their data codes decoded (`null`: corrupt or a status word).
#[derive(serde::Serialize)]
pub struct SatelliteMessage<'a> {
    first_timestamp_ns: u64,
    newest_sample_ns: u64,
    sequence: u64,
    sample_period_ns: u32,
    count: u32,
    frames: &'a [u16],
    decel_codes: Vec<Option<i16>>,
}

/// The `/sensors/satellite_…` message of a batch.
pub fn satellite_batch(b: &signals::SatelliteFrames) -> SatelliteMessage<'_> {
    SatelliteMessage {
        first_timestamp_ns: b.first_timestamp_ns,
        newest_sample_ns: newest_sample_ns(
            b.first_timestamp_ns,
            b.frames().len(),
            b.sample_period_ns,
        ),
        sequence: b.sequence,
        sample_period_ns: b.sample_period_ns,
        count: b.count,
        frames: b.frames(),
        decel_codes: b
            .frames()
            .iter()
            .map(|f| match signals::psi5::decode(*f) {
                signals::psi5::Psi5Word::Data(c) => Some(c),
                _ => None,
            })
            .collect(),
    }
}

/// JSON Schema of the satellite topics.
pub fn satellite_schema() -> Value {
    let mut b = signals::SatelliteFrames::EMPTY;
    b.count = 1;
    titled(
        schema_of(&serde_json::to_value(satellite_batch(&b)).unwrap_or(Value::Null)),
        SATELLITE_SCHEMA,
        "One batch of a crush-zone satellite's PSI5 frames the sensor feeds published on iceoryx2 (log time: the publish; frame k sampled at first_timestamp_ns + k·sample_period_ns, CLOCK_MONOTONIC; frames: 10-bit data + even parity in bit 10; decel_codes: data codes, + = deceleration, null = corrupt or status)",
    )
}

/// JSON Schema of `/sensors/object`.
pub fn object_schema() -> Value {
    titled(
        schema_of(&object(&ObjectState::INVALID)),
        OBJECT_SCHEMA,
        "The opponent object state the sensor feeds published on iceoryx2 (log time: the publish; timestamp_ns: the measurement, CLOCK_MONOTONIC)",
    )
}

/// JSON Schema of the accelerometer topics.
pub fn accel_batch_schema() -> Value {
    let mut b = CrashAccelSample::EMPTY;
    b.count = 1;
    titled(
        schema_of(&serde_json::to_value(accel_batch(&b)).unwrap_or(Value::Null)),
        ACCEL_SCHEMA,
        "One accelerometer batch the sensor feeds published on iceoryx2 (log time: the publish; sample k at first_timestamp_ns + k·sample_period_ns, CLOCK_MONOTONIC; m/s², negative = deceleration)",
    )
}

/// JSON Schema of a topic whose messages are another process's JSON records (the actuator
/// stubs' commands, actions and verdict): the union of every message's fields, so a reader
/// (Foxglove's panels, any MCAP tool) is offered each of them — one message may lack a field
/// another has (an action without a force, a command without a SecOC verdict).
pub fn records_schema<'a>(
    messages: impl IntoIterator<Item = &'a Value>,
    title: &str,
    description: &str,
) -> Value {
    let mut union = Value::Null;
    for m in messages {
        merge_shape(&mut union, m);
    }
    if !union.is_object() {
        union = json!({});
    }
    titled(schema_of(&union), title, description)
}

/// Widens `into` by `v`'s shape: objects take every key of both, a missing or null value takes
/// the other's, an integer meeting a float becomes the float, arrays merge their first items.
fn merge_shape(into: &mut Value, v: &Value) {
    match (into, v) {
        (Value::Object(a), Value::Object(b)) => {
            for (k, x) in b {
                merge_shape(a.entry(k.clone()).or_insert(Value::Null), x);
            }
        }
        (Value::Array(a), Value::Array(b)) => match (a.first_mut(), b.first()) {
            (Some(x), Some(y)) => merge_shape(x, y),
            (None, Some(y)) => a.push(y.clone()),
            _ => {}
        },
        (slot @ Value::Null, x) => *slot = x.clone(),
        (slot @ Value::Number(_), Value::Number(n)) if n.is_f64() => *slot = v.clone(),
        _ => {}
    }
}

fn titled(mut s: Value, title: &str, description: &str) -> Value {
    if let Some(o) = s.as_object_mut() {
        o.insert("title".into(), json!(title));
        o.insert("description".into(), json!(description));
    }
    s
}

/// JSON Schema of `/ecu/diagnostics`, derived from the record's own serialization (so a field
/// added to the record appears here without an edit).
pub fn diagnostics_schema() -> Value {
    let mut s =
        schema_of(&serde_json::to_value(diagnostics(&EcuDiagnostics::ZERO)).unwrap_or(Value::Null));
    if let Some(o) = s.as_object_mut() {
        o.insert("title".into(), json!(DIAGNOSTICS_SCHEMA));
        o.insert(
            "description".into(),
            json!("The ECU's diagnostics record of one cycle, as published on iceoryx2 (signals::EcuDiagnostics); units in the field names"),
        );
    }
    s
}

/// The JSON Schema of a value's shape.
fn schema_of(v: &Value) -> Value {
    match v {
        Value::Null => json!({}),
        Value::Bool(_) => json!({ "type": "boolean" }),
        Value::Number(n) if n.is_f64() => json!({ "type": ["number", "null"] }),
        Value::Number(_) => json!({ "type": "integer" }),
        Value::String(_) => json!({ "type": "string" }),
        Value::Array(a) => {
            json!({ "type": "array", "items": a.first().map_or(json!({}), schema_of) })
        }
        Value::Object(o) => json!({
            "type": "object",
            "properties": o.iter().map(|(k, v)| (k.clone(), schema_of(v))).collect::<Map<_, _>>(),
        }),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_log_message_marks_each_change_of_mode_or_degraded_reasons() {
        use signals::{Degraded, EcuDiagnostics, EcuMode};
        let at = |t_ns: u64, mode: EcuMode, reasons: Degraded| EcuDiagnostics {
            timestamp_ns: t_ns,
            mode: mode as u8,
            degraded_reasons: reasons.bits(),
            ..EcuDiagnostics::ZERO
        };
        let a = at(1_500_000_000, EcuMode::Monitoring, Degraded::empty());
        let b = at(2_000_000_001, EcuMode::PreCrash, Degraded::empty());
        let c = at(2_001_000_000, EcuMode::PreCrash, Degraded::OBJECT_STALE);
        let first = super::mode_change_log(None, &a).unwrap();
        assert_eq!(first["message"], "mode monitoring (first record)");
        assert_eq!(first["level"], 2);
        assert_eq!(first["timestamp"], json!({ "sec": 1, "nsec": 500_000_000 }));
        assert!(
            super::mode_change_log(Some(&a), &a).is_none(),
            "no change, no message"
        );
        let m = super::mode_change_log(Some(&a), &b).unwrap();
        assert_eq!(m["message"], "mode monitoring -> pre-crash");
        assert_eq!(m["timestamp"], json!({ "sec": 2, "nsec": 1 }));
        let d = super::mode_change_log(Some(&b), &c).unwrap();
        assert_eq!(d["message"], "mode pre-crash; degraded: object_stale");
        assert_eq!(d["level"], 3, "a degraded reason is a warning");
        let back = super::mode_change_log(Some(&c), &b).unwrap();
        assert_eq!(back["message"], "mode pre-crash; no degraded reason");
        // Every message is what the schema names.
        let s = super::log_schema();
        for k in first.as_object().unwrap().keys() {
            assert!(s["properties"].get(k).is_some(), "{k}");
        }
    }

    #[test]
    fn a_records_schema_offers_every_field_any_message_has() {
        let msgs = [
            json!({ "t_ms": 1, "kind": "airbag_fire", "force_kn": null, "stage": { "n": 1 } }),
            json!({ "t_ms": 2.5, "kind": "release", "extra": [1, 2], "stage": { "m": true } }),
            json!({ "force_kn": 12.0 }),
        ];
        let s = super::records_schema(&msgs, "T", "D");
        let p = &s["properties"];
        assert_eq!(s["title"], "T");
        assert_eq!(
            p["t_ms"]["type"],
            json!(["number", "null"]),
            "int then float: a number"
        );
        assert_eq!(p["kind"]["type"], "string");
        assert_eq!(
            p["force_kn"]["type"],
            json!(["number", "null"]),
            "null, then a value"
        );
        assert_eq!(p["extra"]["items"]["type"], "integer");
        let stage = &p["stage"]["properties"];
        assert!(stage.get("n").is_some() && stage.get("m").is_some(), "{s}");
        // No message at all: still an object schema.
        assert_eq!(super::records_schema(&[], "T", "D")["title"], "T");
    }

    use super::*;

    #[test]
    fn every_dbc_message_has_a_schema_naming_each_signal() {
        for m in bus::MESSAGES {
            let sigs = bus::signals_of(m.id).unwrap();
            let s = message_schema(m, sigs);
            let props = s["properties"].as_object().unwrap();
            assert_eq!(props.len(), sigs.len(), "{}", m.name);
            for sig in sigs {
                assert!(props.contains_key(sig.name), "{}.{}", m.name, sig.name);
                // A value table: every DBC name, at its raw value.
                let one_of = props[sig.name]["oneOf"]
                    .as_array()
                    .map_or(&[][..], Vec::as_slice);
                assert_eq!(one_of.len(), sig.values.len(), "{}.{}", m.name, sig.name);
                for (&(raw, name), e) in sig.values.iter().zip(one_of) {
                    assert_eq!(e["title"], name, "{}.{}", m.name, sig.name);
                    assert_eq!(
                        e["const"].as_f64(),
                        Some(raw as f64),
                        "{}.{}",
                        m.name,
                        sig.name
                    );
                }
            }
        }
        // Read from the DBC's own text: `CM_ SG_ 48 Arm "Arming: …"` and
        // `VAL_ 48 Fire 0 "NoFire" 1 "Fire" ;`.
        let m = bus::message_info(bus::AirbagStageCmd::RAW_ID).unwrap();
        let s = message_schema(m, bus::signals_of(m.id).unwrap());
        let arm = s["properties"]["Arm"]["description"].as_str().unwrap();
        assert!(
            arm.starts_with("Arming: the module may only fire while armed. — "),
            "{arm}"
        );
        let fire = s["properties"]["Fire"]["oneOf"].as_array().unwrap();
        assert!(
            fire.contains(&serde_json::json!({ "const": 1, "title": "Fire" })),
            "{s}"
        );
        assert!(
            fire.contains(&serde_json::json!({ "const": 0, "title": "NoFire" })),
            "{s}"
        );
    }

    #[test]
    fn a_frame_decodes_to_the_values_it_was_encoded_from() {
        let m = bus::message_info(bus::EgoVehicleState::RAW_ID).unwrap();
        let sigs = bus::signals_of(m.id).unwrap();
        let vals: Vec<f64> = sigs
            .iter()
            .map(|s| {
                // a raw value inside the range, as a physical value
                let raw = (s.raw_min + s.raw_max) / 2;
                raw as f64 * s.factor + s.offset
            })
            .collect();
        let f = bus::encode_values(m.id, &vals).unwrap();
        let msg = message_values(sigs, f.payload());
        for (s, v) in sigs.iter().zip(&vals) {
            let got = msg[s.name].as_f64().unwrap();
            assert!(
                (got - v).abs() <= 1e-9 * v.abs().max(1.0),
                "{}: {got} vs {v}",
                s.name
            );
        }
        let raw = raw_frame("vcan0", &f);
        assert_eq!(raw["message"], "EgoVehicleState");
        assert_eq!(raw["dlc"], m.size);
    }

    #[test]
    fn the_diagnostics_schema_names_every_field_of_the_record() {
        let s = diagnostics_schema();
        let props = s["properties"].as_object().unwrap();
        for f in [
            "timestamp_ns",
            "mode",
            "mode_name",
            "degraded",
            "pulse_points",
            "opponent_mass_sigma_kg",
        ] {
            assert!(props.contains_key(f), "{f}");
        }
        assert!(
            !props.contains_key("pulse_accel_mps2"),
            "the pulse has its own topic"
        );
        assert_eq!(
            predicted_pulse_schema()["properties"]["pulse_accel_mps2"]["type"],
            "array"
        );
    }
}
