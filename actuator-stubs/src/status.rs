//! The `EcuStatus` vocabulary, read from the DBC's generated tables: which signals are fault
//! flags, what they are called in reports, and the names of the `EcuMode` values.

use heck::ToSnakeCase;

/// The EcuStatus fault flags, in DBC order: every `EcuStatus` signal named `Fault…`, as
/// (index in `EcuStatus::SIGNALS`, report name = the rest of the name in snake case).
pub fn ecu_fault_signals() -> impl Iterator<Item = (usize, String)> {
    ecu_fault_indices().map(|i| {
        let name = bus::EcuStatus::SIGNALS.get(i).map_or("", |s| s.name);
        (
            i,
            name.strip_prefix("Fault").unwrap_or(name).to_snake_case(),
        )
    })
}

/// The index in `EcuStatus::SIGNALS` of every fault flag, in DBC order ([`ecu_fault_signals`]
/// without the names: what decoding a status frame needs, every frame).
pub fn ecu_fault_indices() -> impl Iterator<Item = usize> {
    bus::EcuStatus::SIGNALS
        .iter()
        .enumerate()
        .filter(|(_, s)| s.name.starts_with("Fault"))
        .map(|(i, _)| i)
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
