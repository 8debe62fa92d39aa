//! `E2eChecker::check` (stateful: CRC, alive counter per message, ranges) fed arbitrary
//! sequences of frames with arbitrary ids, lengths and bytes.
//!
//! Input: byte 0 = tolerated lost frames (`with_max_lost`, mod 16), then records
//! `[id selector][len][len bytes]`: selector < 0xF0 picks a DBC id (ids of E2E frames are the
//! interesting ones), otherwise the id is the next two bytes (any 11/29-bit value).
//!
//! Oracles: every call is counted exactly once (accepted or by reason); an accepted frame also
//! passes the stateless `bus::decode`; with no tolerance, an accepted E2E frame never repeats
//! the alive counter of the previous CRC-valid frame of its message.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&first, mut rest)) = data.split_first() else {
        return;
    };
    let max_lost = first & 0x0F;
    let mut rx = bus::E2eChecker::with_max_lost(max_lost);
    let mut calls = 0u64;
    // Last alive counter that updated the checker state, per DBC id.
    let mut last_counter: [Option<u8>; 0x800] = [None; 0x800];
    while rest.len() >= 2 {
        let sel = rest[0];
        let (id, after) = if sel < 0xF0 {
            (
                bus::MESSAGES[usize::from(sel) % bus::MESSAGES.len()].id,
                &rest[1..],
            )
        } else if rest.len() >= 3 {
            let raw = u32::from(u16::from_le_bytes([rest[1], rest[2]]));
            let id = if sel & 1 == 1 {
                raw | bus::CAN_EFF_FLAG
            } else {
                raw
            };
            (id, &rest[3..])
        } else {
            return;
        };
        let Some((&len, after)) = after.split_first() else {
            return;
        };
        let len = usize::from(len % 12).min(after.len());
        let (payload, tail) = after.split_at(len);
        rest = tail;

        let r = rx.check(id, payload);
        calls += 1;
        let info = bus::message_info(id);
        let crc_ok = info.is_some_and(|i| {
            payload.len() == i.size
                && bus::RawFrame::new(id, payload)
                    .e2e_crc_ok()
                    .unwrap_or(true)
        });
        match &r {
            Ok(_) => {
                assert!(
                    bus::decode(id, payload).is_ok(),
                    "checker accepted, decode did not"
                );
                if let Some(i) = info.filter(|i| i.e2e_data_id.is_some()) {
                    let counter = payload[1] & 0x0F;
                    let slot = &mut last_counter[(i.id as usize) & 0x7FF];
                    assert_ne!(*slot, Some(counter), "repeated alive counter accepted");
                    *slot = Some(counter);
                }
            }
            Err(e) => {
                // State updates on counter skips and range errors after a valid counter too.
                if crc_ok {
                    if let (
                        Some(i),
                        bus::RejectReason::CounterSkipped | bus::RejectReason::OutOfRange,
                    ) = (info.filter(|i| i.e2e_data_id.is_some()), e.reason())
                    {
                        last_counter[(i.id as usize) & 0x7FF] = Some(payload[1] & 0x0F);
                    }
                }
            }
        }
    }
    let s = rx.stats();
    let rejected: u64 = s.rejected.iter().sum();
    assert_eq!(s.accepted + rejected, calls);
});
