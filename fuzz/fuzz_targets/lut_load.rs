//! The characteristic-diagram (LUT) loaders: `Diagram::from_bytes` (binary) and
//! `Diagram::from_json_str` (JSON, chosen when the input starts with `{`).
//!
//! Oracles for an accepted table: it re-encodes to a binary that loads to the same table
//! (same CRC-32C), and a lookup with query values taken from the input (NaN, inf, anything)
//! returns finite outputs — the ECU relies on that.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let first = data.iter().copied().find(|b| !b.is_ascii_whitespace());
    let loaded = if first == Some(b'{') {
        match std::str::from_utf8(data) {
            Ok(text) => diagram::Diagram::from_json_str("fuzz.json", text),
            Err(_) => return,
        }
    } else {
        diagram::Diagram::from_bytes("fuzz.lut", data)
    };
    let Ok(d) = loaded else {
        return;
    };
    let bytes = d.to_bytes();
    let again = diagram::Diagram::from_bytes("again.lut", &bytes).expect("own encoding loads");
    assert_eq!(again.checksum(), d.checksum());
    // Query from the last 16 input bytes (any f32 bit pattern).
    let mut q = [0f32; 4];
    for (i, c) in data.rchunks_exact(4).take(4).enumerate() {
        q[i] = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
    }
    let l = d.lookup(&diagram::Query {
        closing_speed_kph: q[0],
        opponent_mass_kg: q[1],
        occupant_mass_kg: q[2],
        seat_distance_mm: q[3],
    });
    let v = l.values;
    for x in [
        v.belt_limiter_kn,
        v.airbag_level_kn,
        v.pretensioner_time_ms,
        v.airbag_time_ms,
        v.a_max_g,
        v.a_mean_g,
        v.excursion_mm,
        v.bottoming_out,
        v.a_ideal_g,
    ] {
        assert!(x.is_finite(), "non-finite lookup output {x} for {q:?}");
    }
    assert!(l.airbag_command_kn().is_finite());
});
