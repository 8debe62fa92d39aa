//! Generates every bit layout of the bench bus from `restraint.dbc`, the one source of truth.
//!
//! Two generated files land in `OUT_DIR`:
//! - `restraint.rs`: the codecs, written by `dbc-codegen` (message structs with typed getters,
//!   range-checked setters, value-table enums, `Messages::from_can_message`, ids, sizes and
//!   `GenMsgCycleTime` constants);
//! - `restraint_meta.rs`: what dbc-codegen does not emit but the E2E and validation layer needs,
//!   generated with `can-dbc` from the same file: a message table (id, size, cycle time, E2E data
//!   id), one `E2eMessage` impl per protected message (position of its CRC byte and alive counter
//!   taken from the DBC), and receive-side range checks on raw values.
//!
//! Nothing in `src/` restates a bit position, an id, a cycle time, a data id or a value name:
//! each message also gets its `RAW_ID` and, per value-table signal, `<SIGNAL>_VALUES`.

use std::collections::BTreeMap;
use std::env;
use std::fmt::Write as _;
use std::fs;
use std::path::PathBuf;

use can_dbc::{AttributeValue, ByteOrder, Dbc, MessageId, NumericValue, ValueType};
use dbc_codegen::{Config, FeatureConfig};
use heck::{ToPascalCase, ToSnakeCase};

const DBC_PATH: &str = "restraint.dbc";
/// Name of the E2E CRC signal in every protected message.
const CRC_SIGNAL: &str = "Crc";
/// Name of the E2E alive-counter signal in every protected message.
const COUNTER_SIGNAL: &str = "AliveCounter";

fn main() {
    println!("cargo:rerun-if-changed={DBC_PATH}");
    println!("cargo:rerun-if-changed=build.rs");
    let dbc_text = fs::read_to_string(DBC_PATH).expect("read restraint.dbc");
    let out_dir = PathBuf::from(env::var("OUT_DIR").expect("OUT_DIR"));

    Config::builder()
        .dbc_name("restraint.dbc")
        .dbc_content(&dbc_text)
        .impl_debug(FeatureConfig::Always)
        .impl_error(FeatureConfig::Gated("std"))
        .impl_embedded_can_frame(FeatureConfig::Always)
        .check_ranges(FeatureConfig::Always)
        .allow_dead_code(true)
        .build()
        .write_to_file(out_dir.join("restraint.rs"))
        .expect("dbc-codegen failed on restraint.dbc");

    let dbc = Dbc::try_from(dbc_text.as_str()).expect("can-dbc failed to parse restraint.dbc");
    let meta = generate_meta(&dbc);
    fs::write(out_dir.join("restraint_meta.rs"), meta).expect("write restraint_meta.rs");
}

fn num(v: &NumericValue) -> f64 {
    match *v {
        NumericValue::Uint(u) => u as f64,
        NumericValue::Int(i) => i as f64,
        NumericValue::Double(d) => d,
    }
}

fn int_attr(dbc: &Dbc, id: MessageId, name: &str) -> Option<i64> {
    match dbc.message_attribute(id, name)? {
        AttributeValue::Uint(v) => i64::try_from(*v).ok(),
        AttributeValue::Int(v) => Some(*v),
        AttributeValue::Double(_) | AttributeValue::String(_) => None,
    }
}

/// Parameter-name suffix for a DBC unit, so generated signatures carry units (`_kn`, `_ms`, …).
fn unit_suffix(unit: &str) -> &'static str {
    match unit {
        "kN" => "_kn",
        "ms" => "_ms",
        "us" => "_us",
        "m/s" => "_mps",
        "m/s2" => "_mps2",
        "kg" => "_kg",
        "mm" => "_mm",
        "m" => "_m",
        "%" => "_pct",
        "" | "cycles" => "",
        other => panic!("unit {other:?}: add a suffix in build.rs"),
    }
}

/// Rust type of a raw value, as dbc-codegen's `*_raw_val()` accessors return it.
fn raw_type(size: u64, signed: bool) -> String {
    let bits = match size {
        0..=8 => 8,
        9..=16 => 16,
        17..=32 => 32,
        _ => 64,
    };
    format!("{}{bits}", if signed { 'i' } else { 'u' })
}

fn generate_meta(dbc: &Dbc) -> String {
    let mut o = String::new();
    let mut sig_tables = String::new();
    let mut dyn_decode_arms = String::new();
    let mut dyn_encode_arms = String::new();
    let mut table = String::new();
    let mut e2e_arms = String::new();
    let mut range_arms = String::new();
    let mut name_arms = String::new();
    let mut e2e_slot = 0usize;
    let mut ids = BTreeMap::new();

    for msg in &dbc.messages {
        let MessageId::Standard(id) = msg.id else {
            panic!("{}: only 11-bit ids are used on this bus", msg.name);
        };
        assert!(
            ids.insert(id, msg.name.clone()).is_none(),
            "duplicate id {id:#x}"
        );
        assert!(msg.size <= 8, "{}: classic CAN frames only", msg.name);
        let ty = msg.name.to_pascal_case();
        let cycle = int_attr(dbc, msg.id, "GenMsgCycleTime").filter(|c| *c > 0);
        let data_id = int_attr(dbc, msg.id, "E2EDataId").filter(|d| *d > 0);
        let transmitter = msg.transmitter.clone().unwrap_or_default();

        // E2E layout, taken from the signals themselves.
        let e2e = data_id.map(|data_id| {
            assert!(
                (0..=0xFFFF).contains(&data_id),
                "{}: E2EDataId is 16 bit",
                msg.name
            );
            let crc = msg
                .signals
                .iter()
                .find(|s| s.name == CRC_SIGNAL)
                .unwrap_or_else(|| panic!("{}: has E2EDataId but no {CRC_SIGNAL}", msg.name));
            let ctr = msg
                .signals
                .iter()
                .find(|s| s.name == COUNTER_SIGNAL)
                .unwrap_or_else(|| panic!("{}: has E2EDataId but no {COUNTER_SIGNAL}", msg.name));
            assert!(
                crc.size == 8
                    && crc.start_bit % 8 == 0
                    && crc.byte_order == ByteOrder::LittleEndian,
                "{}: the CRC must be one whole byte",
                msg.name
            );
            assert!(
                ctr.size == 4 && ctr.byte_order == ByteOrder::LittleEndian,
                "{}: the alive counter is 4 bit, Intel",
                msg.name
            );
            let slot = e2e_slot;
            e2e_slot += 1;
            (
                data_id,
                crc.start_bit / 8,
                slot,
                crc.start_bit,
                ctr.start_bit,
            )
        });

        let cycle_s = cycle.map_or("None".to_string(), |c| format!("Some({c})"));
        let e2e_s = data_id.map_or("None".to_string(), |d| format!("Some({d:#06x})"));
        writeln!(
            table,
            "    MessageInfo {{ name: {:?}, id: {id:#05x}, size: {}, cycle_time_ms: {cycle_s}, \
             e2e_data_id: {e2e_s}, transmitter: {transmitter:?} }},",
            msg.name, msg.size
        )
        .unwrap();
        writeln!(name_arms, "        Messages::{ty}(_) => {:?},", msg.name).unwrap();

        if let Some((data_id, crc_byte, slot, crc_start, ctr_start)) = e2e {
            writeln!(
                o,
                "impl E2eMessage for {ty} {{
    const NAME: &'static str = {name:?};
    const DATA_ID: u16 = {data_id:#06x};
    const CRC_BYTE: usize = {crc_byte};
    const SLOT: usize = {slot};
    #[inline]
    fn payload(&self) -> &[u8] {{ self.raw() }}
    #[inline]
    fn e2e_counter(&self) -> u8 {{ intel_raw(le_word(self.raw()), {ctr_start}, 4, false) as u8 }}
    #[inline]
    fn e2e_crc(&self) -> u8 {{ intel_raw(le_word(self.raw()), {crc_start}, 8, false) as u8 }}
    #[inline]
    fn set_e2e_counter(&mut self, counter: u8) {{ self.set_{ctr}_raw_val(counter & 0x0F) }}
    #[inline]
    fn set_e2e_crc(&mut self, crc: u8) {{ self.set_{crc}_raw_val(crc) }}
}}
",
                name = msg.name,
                ctr = COUNTER_SIGNAL.to_snake_case(),
                crc = CRC_SIGNAL.to_snake_case(),
            )
            .unwrap();
            writeln!(
                e2e_arms,
                "        Messages::{ty}(m) => Some(E2eView::of(m)),"
            )
            .unwrap();
        } else {
            writeln!(e2e_arms, "        Messages::{ty}(_) => None,").unwrap();
        }

        // Typed constructor with rounding, NaN rejection and range checks, plus the dynamic
        // (index-based) encode/decode used by tests, fuzzers and loggers.
        // Every signal of this bus is Intel (little-endian); a Motorola signal would make the
        // generator fall back to dbc-codegen's setters for its message.
        let intel = msg
            .signals
            .iter()
            .all(|s| s.byte_order == ByteOrder::LittleEndian && s.size < 64);
        let mut params = Vec::new();
        let mut body = String::new();
        let mut sig_rows = String::new();
        let mut dyn_dec = String::new();
        let mut dyn_enc = String::new();
        for (idx, s) in msg.signals.iter().enumerate() {
            let field = s.name.to_snake_case();
            let signed = s.value_type == ValueType::Signed;
            let rt = raw_type(s.size, signed);
            let (min, max) = (num(&s.min), num(&s.max));
            let raw_min = ((min - s.offset) / s.factor - 1e-6).ceil() as i128;
            let raw_max = ((max - s.offset) / s.factor + 1e-6).floor() as i128;
            let scaled = s.factor != 1.0 || s.offset != 0.0;
            let has_vt = dbc.value_descriptions_for_signal(msg.id, &s.name).is_some();
            let values = if has_vt {
                format!("Self::{}_VALUES", s.name.to_snake_case().to_uppercase())
            } else {
                "&[]".to_owned()
            };
            let comment = dbc.signal_comment(msg.id, &s.name).unwrap_or("");
            writeln!(
                sig_rows,
                "    SignalInfo {{ name: {:?}, start_bit: {}, size: {}, signed: {signed}, factor: {:?}, \
                 offset: {:?}, min: {min:?}, max: {max:?}, raw_min: {raw_min}, raw_max: {raw_max}, unit: {:?}, \
                 values: {values}, comment: {comment:?} }},",
                s.name, s.start_bit, s.size, s.factor, s.offset, s.unit
            )
            .unwrap();
            if scaled {
                writeln!(dyn_dec, "            out[{idx}] = f64::from(m.{field}());").unwrap();
            } else {
                writeln!(
                    dyn_dec,
                    "            out[{idx}] = m.{field}_raw_val() as f64;"
                )
                .unwrap();
            }
            let is_e2e_field = e2e.is_some() && (s.name == CRC_SIGNAL || s.name == COUNTER_SIGNAL);
            let msg_name = &msg.name;
            let sig_name = &s.name;
            let err = format!("EncodeError {{ message: {msg_name:?}, signal: {sig_name:?}");
            if is_e2e_field {
                // Set by E2eProtector; the dynamic encoder still accepts them (tests, fuzzing).
                writeln!(
                    dyn_enc,
                    "            m.set_{field}_raw_val(raw_from_f64(v[{idx}], {raw_min}, {raw_max}, 1.0, 0.0).ok_or({err}, kind: EncodeErrorKind::OutOfRange }})? as {rt});"
                )
                .unwrap();
                continue;
            }
            writeln!(
                dyn_enc,
                "            m.set_{field}_raw_val(raw_from_f64(v[{idx}], {raw_min}, {raw_max}, {:?}, {:?}).ok_or({err}, kind: EncodeErrorKind::OutOfRange }})? as {rt});",
                s.factor, s.offset
            )
            .unwrap();
            let pname = format!("{field}{}", unit_suffix(&s.unit));
            if has_vt {
                let ety = format!("{}{}", msg.name.to_pascal_case(), s.name.to_pascal_case());
                let conv = if s.size == 1 {
                    format!("i128::from(bool::from({pname}))")
                } else {
                    format!("i128::from(u8::from({pname}))")
                };
                params.push(format!("{pname}: {ety}"));
                writeln!(body, "        let raw = {conv};").unwrap();
            } else if s.size == 1 {
                params.push(format!("{pname}: bool"));
                writeln!(body, "        let raw = i128::from({pname});").unwrap();
            } else if scaled {
                params.push(format!("{pname}: f32"));
                writeln!(
                    body,
                    "        let raw = raw_from_f64(f64::from({pname}), {raw_min}, {raw_max}, {:?}, {:?})\n            .ok_or(if {pname}.is_finite() {{ {err}, kind: EncodeErrorKind::OutOfRange }} }} else {{ {err}, kind: EncodeErrorKind::NotFinite }} }})?;",
                    s.factor, s.offset
                )
                .unwrap();
            } else {
                params.push(format!("{pname}: {rt}"));
                writeln!(body, "        let raw = i128::from({pname});").unwrap();
            }
            let store = if intel {
                format!(
                    "w = with_intel_raw(w, {}, {}, raw as i64);",
                    s.start_bit, s.size
                )
            } else {
                format!("m.set_{field}_raw_val(raw as {rt});")
            };
            writeln!(
                body,
                "        if raw < {raw_min} || raw > {raw_max} {{ return Err({err}, kind: EncodeErrorKind::OutOfRange }}); }}\n        {store}"
            )
            .unwrap();
        }
        let mut value_tables = String::new();
        for sig in &msg.signals {
            if let Some(vals) = dbc.value_descriptions_for_signal(msg.id, &sig.name) {
                let rows: Vec<String> = vals
                    .iter()
                    .map(|v| format!("({}, {:?})", v.id, v.description))
                    .collect();
                writeln!(
                    value_tables,
                    "    /// `{}` value table (`VAL_`): raw value → DBC name (generated).
    pub const {}_VALUES: &'static [(i64, &'static str)] = &[{}];",
                    sig.name,
                    sig.name.to_snake_case().to_uppercase(),
                    rows.join(", ")
                )
                .unwrap();
            }
        }
        let nsig = msg.signals.len();
        let new_err = format!(
            "EncodeError {{ message: {:?}, signal: \"\", kind: EncodeErrorKind::OutOfRange }}",
            msg.name
        );
        let (enc_head, enc_tail) = if intel {
            (
                "        let mut w = 0u64;\n".to_owned(),
                format!(
                    "        Self::try_from(&w.to_le_bytes()[..{}]).map_err(|_| {new_err})",
                    msg.size
                ),
            )
        } else {
            (
                format!(
                    "        let mut m = Self::try_from(&[0u8; {}][..]).map_err(|_| {new_err})?;\n",
                    msg.size
                ),
                "        Ok(m)".to_owned(),
            )
        };
        let e2e_note = if e2e.is_some() {
            "\n    /// `Crc` and `AliveCounter` are left 0: [`E2eProtector::protect`](crate::E2eProtector::protect) sets them."
        } else {
            ""
        };
        writeln!(
            o,
            "impl {ty} {{
    /// Linux `can_id` of this message (11-bit id, no flags; generated from the DBC).
    pub const RAW_ID: u32 = {id:#05x};
    /// Builds the frame from physical values (generated from the DBC): scaled values are
    /// rounded to the nearest step (not truncated), NaN/inf and values outside the DBC range are
    /// rejected with the signal's name.{e2e_note}
    #[allow(clippy::too_many_arguments, clippy::cast_possible_truncation, clippy::manual_range_contains, unused_comparisons)]
    pub fn encode({}) -> Result<Self, EncodeError> {{
{enc_head}{body}{enc_tail}
    }}
    /// The signals of this message, in DBC order (generated).
    pub const SIGNALS: &'static [SignalInfo] = &[
{sig_rows}    ];
{value_tables}}}
",
            params.join(", "),
        )
        .unwrap();
        writeln!(sig_tables, "        {:#05x} => Some({ty}::SIGNALS),", id).unwrap();
        writeln!(
            dyn_decode_arms,
            "        Messages::{ty}(m) => {{\n            if out.len() < {nsig} {{ return None; }}\n{dyn_dec}            Some({nsig})\n        }}"
        )
        .unwrap();
        writeln!(
            dyn_encode_arms,
            "        {id:#05x} => {{\n            if v.len() != {nsig} {{ return Err(EncodeError {{ message: {:?}, signal: \"\", kind: EncodeErrorKind::WrongSignalCount }}); }}\n            let mut m = {ty}::try_from(&[0u8; {}][..]).map_err(|_| EncodeError {{ message: {:?}, signal: \"\", kind: EncodeErrorKind::OutOfRange }})?;\n{dyn_enc}            Ok(RawFrame::from_message(&m))\n        }}",
            msg.name, msg.size, msg.name
        )
        .unwrap();

        // Receive-side range checks on the raw integer, so that no float rounding can reject a
        // value the sender was allowed to encode (e.g. 240 * 0.05 = 12.000001 kN in f32).
        let mut checks = String::new();
        for s in &msg.signals {
            let field = s.name.to_snake_case();
            let (min, max) = (num(&s.min), num(&s.max));
            let raw_min = ((min - s.offset) / s.factor - 1e-6).ceil() as i128;
            let raw_max = ((max - s.offset) / s.factor + 1e-6).floor() as i128;
            let (full_min, full_max) = match s.value_type {
                ValueType::Unsigned => (0i128, (1i128 << s.size) - 1),
                ValueType::Signed => (-(1i128 << (s.size - 1)), (1i128 << (s.size - 1)) - 1),
            };
            if raw_min <= full_min && raw_max >= full_max {
                continue; // every raw value is valid
            }
            let read = if intel {
                format!(
                    "i128::from(intel_raw(w, {}, {}, {}))",
                    s.start_bit,
                    s.size,
                    s.value_type == ValueType::Signed
                )
            } else {
                format!("m.{field}_raw_val() as i128")
            };
            writeln!(
                checks,
                "            let raw = {read};\n            if raw < {raw_min} || raw > {raw_max} {{ return Some({:?}); }}",
                s.name
            )
            .unwrap();
        }
        if checks.is_empty() {
            writeln!(range_arms, "        Messages::{ty}(_) => None,").unwrap();
        } else {
            let word = if intel {
                "            let w = le_word(m.raw());\n"
            } else {
                ""
            };
            writeln!(
                range_arms,
                "        Messages::{ty}(m) => {{\n{word}{checks}            None\n        }}"
            )
            .unwrap();
        }
    }

    let mut head = String::new();
    writeln!(
        head,
        "/// Every frame of `restraint.dbc`, in file order (generated)."
    )
    .unwrap();
    writeln!(head, "pub const MESSAGES: &[MessageInfo] = &[\n{table}];").unwrap();
    writeln!(
        head,
        "/// Number of E2E-protected messages (size of the per-message counter state)."
    )
    .unwrap();
    writeln!(head, "pub const E2E_MESSAGE_COUNT: usize = {e2e_slot};").unwrap();
    writeln!(
        head,
        "/// Names of the E2E CRC and alive-counter signals in every protected message.
pub const E2E_SIGNALS: (&str, &str) = ({CRC_SIGNAL:?}, {COUNTER_SIGNAL:?});"
    )
    .unwrap();
    writeln!(
        head,
        "/// E2E fields of a decoded message, `None` for unprotected frames (generated).
pub(crate) fn e2e_view(m: &Messages) -> Option<E2eView<'_>> {{
    match m {{
{e2e_arms}    }}
}}
/// Name of the first signal whose raw value lies outside its DBC `[min|max]` (generated).
#[allow(clippy::manual_range_contains, unused_comparisons)]
pub(crate) fn out_of_range_signal(m: &Messages) -> Option<&'static str> {{
    match m {{
{range_arms}    }}
}}
/// Signal table of a message id (generated).
pub fn signals_of(id: u32) -> Option<&'static [SignalInfo]> {{
    match id {{
{sig_tables}        _ => None,
    }}
}}
/// Physical values of every signal of `m`, in DBC order, into `out`; returns how many
/// (`None` if `out` is too short). Value-table signals give their raw number.
#[allow(clippy::cast_precision_loss)]
pub fn signal_values(m: &Messages, out: &mut [f64]) -> Option<usize> {{
    match m {{
{dyn_decode_arms}    }}
}}
/// Frame of message `id` from physical values in DBC order, E2E fields included as given
/// (rounded to the nearest step; generated). For tests, fuzzers and bench tools.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
pub fn encode_values(id: u32, v: &[f64]) -> Result<RawFrame, EncodeError> {{
    match id {{
{dyn_encode_arms}        _ => Err(EncodeError {{ message: \"\", signal: \"\", kind: EncodeErrorKind::UnknownId }}),
    }}
}}
/// DBC name of a decoded message (generated).
pub fn message_name(m: &Messages) -> &'static str {{
    match m {{
{name_arms}    }}
}}
"
    )
    .unwrap();
    head + &o
}
