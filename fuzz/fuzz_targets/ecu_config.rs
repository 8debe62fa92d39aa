//! The ECU's TOML configuration parser and validator (`EcuConfig::from_toml_str`) on arbitrary
//! text. Oracle beyond "no panic / no hang": errors render (Display) without panicking, and an
//! accepted config's error-free path is stable (parsing the same text twice agrees).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("fuzz.toml");
    match ecu::runtime::EcuConfig::from_toml_str(text, path) {
        Ok(_) => assert!(ecu::runtime::EcuConfig::from_toml_str(text, path).is_ok()),
        Err(e) => {
            let _ = e.to_string();
        }
    }
});
