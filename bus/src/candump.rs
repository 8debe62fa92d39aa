//! `candump -L` logs (feature `socket`), read with socketcan's own parser
//! ([`socketcan::dump::Reader`]) — the bench's one candump reader, for the judges, the fault
//! campaign and the tests — and frames written as `cansend` takes them.

use std::io;
use std::path::Path;

use socketcan::{CanAnyFrame, EmbeddedFrame, Frame};

use crate::{RawFrame, CAN_EFF_FLAG};

/// One data frame of a log.
#[derive(Debug, Clone)]
pub struct LoggedFrame {
    /// candump's time stamp, µs (CLOCK_REALTIME of the logging host).
    pub t_us: u64,
    /// Interface it was logged on.
    pub device: String,
    /// The frame.
    pub frame: RawFrame,
}

/// One error frame of a log: what a CAN controller reported (candump logs it when its error
/// filter is set, `IFACE,0:0,#FFFFFFFF`).
#[derive(Debug, Clone)]
pub struct LoggedErrorFrame {
    /// candump's time stamp, µs (CLOCK_REALTIME of the logging host).
    pub t_us: u64,
    /// Interface it was logged on.
    pub device: String,
    /// The error classes (`CAN_ERR_*` bits of the id, without `CAN_ERR_FLAG`).
    pub class: u32,
    /// The eight detail bytes (controller state, protocol violation and location, counters).
    pub data: [u8; 8],
    /// The ASAM error type ([`ASAM_ERROR_TYPES`]) the report amounts to.
    pub error_type: u8,
    /// The report in words, every cause (socketcan's decoding of the classes and bytes).
    pub text: String,
}

/// ASAM MDF bus logging's `CAN_ErrorFrame.ErrorType` values and names.
pub const ASAM_ERROR_TYPES: [(u8, &str); 6] = [
    (0, "Unknown"),
    (1, "Bit Error"),
    (2, "Form Error"),
    (3, "Bit Stuffing Error"),
    (4, "CRC Error"),
    (5, "Acknowledgment Error"),
];

/// The ASAM error type ([`ASAM_ERROR_TYPES`]) of a controller's report, from socketcan's
/// decoding of it: a protocol violation in the CRC sequence or delimiter is a CRC error, else
/// its violation type (bit, form, stuffing); a missing acknowledgement an acknowledgment error;
/// anything else (controller state, bus-off, counters only) unknown.
fn asam_error_type(e: &socketcan::CanError) -> u8 {
    use socketcan::errors::{ErrorCause, Location, ViolationTypes};
    if let Some((types, location)) = e.protocol() {
        if matches!(location, Location::CrcSequence | Location::CrcDelimiter) {
            return 4;
        }
        if types.intersects(ViolationTypes::BIT | ViolationTypes::BIT0 | ViolationTypes::BIT1) {
            return 1;
        }
        if types.contains(ViolationTypes::FORM) {
            return 2;
        }
        if types.contains(ViolationTypes::STUFF) {
            return 3;
        }
    }
    if e.causes().any(|c| matches!(c, ErrorCause::NoAck)) {
        return 5;
    }
    0
}

/// A log: its data frames and error frames in order, and how many lines were neither (remote
/// frames, CAN FD frames, lines candump did not write).
#[derive(Debug, Clone, Default)]
pub struct CandumpLog {
    /// The data frames.
    pub frames: Vec<LoggedFrame>,
    /// The error frames.
    pub errors: Vec<LoggedErrorFrame>,
    /// Lines skipped.
    pub skipped: usize,
}

impl CandumpLog {
    /// Parses `candump -L` text; nothing in it is an error (a line that is neither a classic
    /// data frame nor an error frame is counted in `skipped`).
    pub fn parse(text: &str) -> Self {
        let mut log = Self::default();
        for rec in socketcan::dump::Reader::from_reader(text.as_bytes()) {
            match rec {
                Ok(r) => match r.frame {
                    CanAnyFrame::Normal(d) => {
                        let id = if d.is_extended() {
                            d.raw_id() | CAN_EFF_FLAG
                        } else {
                            d.raw_id()
                        };
                        log.frames.push(LoggedFrame {
                            t_us: r.t_us,
                            device: r.device,
                            frame: RawFrame::new(id, d.data()),
                        });
                    }
                    CanAnyFrame::Error(e) => {
                        let mut data = [0u8; 8];
                        let n = e.data().len().min(data.len());
                        data[..n].copy_from_slice(&e.data()[..n]);
                        let class = e.error_bits();
                        let report = e.into_error();
                        log.errors.push(LoggedErrorFrame {
                            t_us: r.t_us,
                            device: r.device,
                            class,
                            data,
                            error_type: asam_error_type(&report),
                            text: report.to_string(),
                        });
                    }
                    _ => log.skipped += 1,
                },
                Err(_) => log.skipped += 1,
            }
        }
        log
    }

    /// Reads and parses a log file.
    pub fn read(path: &Path) -> io::Result<Self> {
        Ok(Self::parse(&std::fs::read_to_string(path)?))
    }
}

/// One line of a `candump -L` log (without its newline): `(seconds.µs) DEVICE ID#HEX`, what
/// [`CandumpLog::parse`] reads back; for logs written by simulations and tests.
pub fn log_line(t_us: u64, device: &str, f: &RawFrame) -> String {
    format!(
        "({}.{:06}) {device} {}",
        t_us / 1_000_000,
        t_us % 1_000_000,
        cansend_arg(f)
    )
}

/// A payload's bytes as lower-case hex pairs, as a record beside a candump log names a frame
/// (the stubs' `commands.jsonl`): the run's recording pairs such records with candump's
/// frames by id and payload, so writer and reader share this one function.
pub fn data_hex(payload: &[u8]) -> String {
    payload.iter().map(|b| format!("{b:02x}")).collect()
}

/// `ID#HEX` as `cansend` takes it (3 hex digits for a standard id, 8 for an extended one).
pub fn cansend_arg(f: &RawFrame) -> String {
    let hex: String = f.payload().iter().map(|b| format!("{b:02X}")).collect();
    if f.id & CAN_EFF_FLAG != 0 {
        format!("{:08X}#{hex}", f.id & !CAN_EFF_FLAG)
    } else {
        format!("{:03X}#{hex}", f.id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_written_line_reads_back_as_the_same_frame_and_stamp() {
        for f in [
            RawFrame::new(0x30, &[0x12, 0xab, 0, 7]),
            RawFrame::new(0x1234_5678 | CAN_EFF_FLAG, &[]),
        ] {
            let line = log_line(1_733_000_123_000_456, "vcan0", &f);
            let log = CandumpLog::parse(&line);
            assert_eq!(log.skipped, 0, "{line}");
            assert_eq!(log.frames[0].t_us, 1_733_000_123_000_456, "{line}");
            assert_eq!(log.frames[0].device, "vcan0");
            assert_eq!(log.frames[0].frame, f, "{line}");
        }
    }

    #[test]
    fn a_log_reads_back_what_cansend_would_send() {
        let text = "(1796387461.290112) vcan0 040#9F40B36400000000\n\
                    (1796387461.290130) vcan0 12345678#0102\n\
                    garbage line\n\
                    (1796387461.290139) vcan0 030#R\n\
                    (1796387461.290150) vcan0 0A0#\n";
        let log = CandumpLog::parse(text);
        assert_eq!(log.frames.len(), 3, "{log:?}");
        assert_eq!(log.skipped, 2);
        let f = &log.frames[0];
        assert_eq!(
            (f.t_us, f.device.as_str()),
            (1_796_387_461_290_112, "vcan0")
        );
        assert_eq!(f.frame.id, crate::BeltLimiterCmd::RAW_ID);
        assert_eq!(cansend_arg(&f.frame), "040#9F40B36400000000");
        assert_eq!(cansend_arg(&log.frames[1].frame), "12345678#0102");
        assert_eq!(log.frames[2].frame.payload(), &[] as &[u8]);
    }

    #[test]
    fn an_error_frame_is_kept_with_its_classes_and_causes() {
        // linux/can/error.h: CAN_ERR_FLAG | PROT 0x08 | BUSERROR 0x80 | CNT 0x200; data[2] =
        // CAN_ERR_PROT_BIT 0x01, data[3] = CAN_ERR_PROT_LOC_CRC_SEQ 0x08, data[7] = rx count.
        let text = "(1796387461.290112) vcan0 20000288#0000010800000007\n\
                    (1796387461.290130) vcan0 12345678#0102\n";
        let log = CandumpLog::parse(text);
        assert_eq!((log.frames.len(), log.errors.len(), log.skipped), (1, 1, 0));
        let e = &log.errors[0];
        assert_eq!(
            (e.t_us, e.device.as_str()),
            (1_796_387_461_290_112, "vcan0")
        );
        assert_eq!(e.class, 0x288);
        assert_eq!(e.data, [0, 0, 1, 8, 0, 0, 0, 7]);
        for part in ["CRC sequence", "bus error", "rx=7"] {
            assert!(e.text.contains(part), "{}", e.text);
        }
        assert_eq!(e.error_type, 4, "CRC Error");
        // an extended data frame's eight digits stay a data frame
        assert_eq!(cansend_arg(&log.frames[0].frame), "12345678#0102");
    }
}
