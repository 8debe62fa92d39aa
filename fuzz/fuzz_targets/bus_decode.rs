//! `bus::decode` (stateless: id, DLC, E2E CRC, signal ranges) on arbitrary ids and payloads.
//!
//! Input: bytes 0..2 = CAN id (little-endian u16; values >= 0x800 are mapped onto the DBC's ids
//! half of the time so the fuzzer reaches the signal decoders quickly), byte 2 = a flag byte
//! (bit 0: set the 29-bit flag), rest = payload of any length.
//!
//! Oracle beyond "no panic": an accepted frame has the DBC size and a correct E2E CRC, and its
//! physical values re-encode (`encode_values`) and decode back to the same values.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 3 {
        return;
    }
    let raw_id = u32::from(u16::from_le_bytes([data[0], data[1]]));
    let mut id = if raw_id >= 0x800 {
        bus::MESSAGES[(raw_id as usize) % bus::MESSAGES.len()].id
    } else {
        raw_id
    };
    if data[2] & 1 == 1 {
        id |= bus::CAN_EFF_FLAG;
    }
    let payload = &data[3..];
    let Ok(msg) = bus::decode(id, payload) else {
        return;
    };
    let info = bus::message_info(id).expect("accepted id is in the DBC");
    assert_eq!(payload.len(), info.size);
    if info.e2e_data_id.is_some() {
        // A decoded E2E frame carries a valid CRC (positions from the DBC).
        assert_eq!(bus::RawFrame::new(id, payload).e2e_crc_ok(), Some(true));
    }
    let mut vals = [0f64; 16];
    let n = bus::signal_values(&msg, &mut vals).expect("16 slots suffice");
    let sigs = bus::signals_of(id).expect("signal table");
    assert_eq!(n, sigs.len());
    let frame = bus::encode_values(id, &vals[..n]).expect("decoded values are encodable");
    let sid = embedded_can_id(id);
    let again = bus::Messages::from_can_message(sid, frame.payload()).expect("same layout");
    let mut vals2 = [0f64; 16];
    bus::signal_values(&again, &mut vals2).expect("16 slots suffice");
    for (s, (a, b)) in sigs.iter().zip(vals.iter().zip(vals2.iter())) {
        assert!((a - b).abs() <= s.factor * 1e-3, "{}: {a} vs {b}", s.name);
    }
});

fn embedded_can_id(id: u32) -> embedded_can::Id {
    let sid = embedded_can::StandardId::new(id as u16).expect("11-bit DBC id");
    embedded_can::Id::Standard(sid)
}
