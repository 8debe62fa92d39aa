//! The `EcuStatus` vocabulary, read from the DBC's generated tables: which signals are fault
//! flags, what they are called in reports, and the names of the `EcuMode` values.

use heck::ToSnakeCase;

/// The EcuStatus fault flags, in DBC order: every `EcuStatus` signal named `Fault…`, as
/// (index in `EcuStatus::SIGNALS`, report name = the rest of the name in snake case).
pub fn ecu_fault_signals() -> impl Iterator<Item = (usize, String)> {
    fault_signals().map(|(i, name)| (i, name.to_snake_case()))
}

/// The index in `EcuStatus::SIGNALS` of every fault flag, in DBC order ([`ecu_fault_signals`]
/// without the names: what decoding a status frame needs, every frame).
pub fn ecu_fault_indices() -> impl Iterator<Item = usize> {
    fault_signals().map(|(i, _)| i)
}

/// Every `EcuStatus` signal named `Fault…`: (index in `EcuStatus::SIGNALS`, the rest of its
/// name as the DBC spells it).
fn fault_signals() -> impl Iterator<Item = (usize, &'static str)> {
    bus::EcuStatus::SIGNALS
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.name.strip_prefix("Fault").map(|n| (i, n)))
}

/// The names of the fault flags set in `bits` (bit k = the k-th of [`ecu_fault_signals`]).
pub fn ecu_fault_names(bits: u16) -> Vec<String> {
    ecu_fault_signals()
        .enumerate()
        .filter(|(k, _)| bits & (1 << k) != 0)
        .map(|(_, (_, n))| n)
        .collect()
}

/// DBC EcuMode names (the DBC's value table; "Unknown" outside it).
pub fn ecu_mode_name(mode: u8) -> &'static str {
    bus::value_name(bus::EcuStatus::ECU_MODE_VALUES, i64::from(mode)).unwrap_or("Unknown")
}
