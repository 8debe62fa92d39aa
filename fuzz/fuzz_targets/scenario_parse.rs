//! The scenario parser and validator of the bench (`world::Scenario::parse`) on
//! arbitrary text. Oracles beyond "no panic / no hang": errors render (Display), an error
//! carrying a line number points inside the text, and parsing is deterministic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match world::Scenario::parse("fuzz.toml", text) {
        // (Not compared with ==: a float field may legitimately hold NaN, NaN != NaN.)
        Ok(_) => assert!(world::Scenario::parse("fuzz.toml", text).is_ok()),
        Err(e) => {
            let _ = e.to_string();
            if let Some(line) = e.line {
                assert!(
                    line >= 1 && line <= text.lines().count() + 1,
                    "line {line} outside the text"
                );
            }
        }
    }
});
