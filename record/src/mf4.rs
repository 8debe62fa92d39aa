//! `run.mf4`: the run's CAN bus in the ASAM MDF 4.1 bus-logging layout (CANape, Vector tools,
//! asammdf) plus the ECU's diagnostics as plain channels.
//!
//! **Why by hand.** No crate that builds here writes the bus-logging layout: `mdf4-rs` 0.4–0.6
//! need rustc 1.97 (the project's toolchain is 1.95); 0.3.3 writes `CAN_DataFrame` as one plain
//! byte array without the bus-event flags or a CAN source, so asammdf's
//! `extract_bus_logging` decodes no signal from it. What a bus-logging reader needs is small and
//! fixed, so this module writes exactly that and nothing else (no compression, no
//! fragmentation, one channel group per data group): ID, HD, FH, DG, CG, CN, CC (value → text),
//! SI, TX, MD, AT and DT blocks.
//!
//! | group | source | channels |
//! |---|---|---|
//! | `CAN` (bus event, plain) | SI: bus, CAN, simulated (vcan) | `t`, `CAN_DataFrame` composed of `.BusChannel`, `.ID`, `.IDE`, `.DLC`, `.DataLength`, `.DataBytes` |
//! | `CAN_ErrorFrame` (bus event, plain; only when candump logged error frames) | the same SI | `t`, `CAN_ErrorFrame` composed of `.BusChannel`, `.ErrorType` (ASAM's values, with names), `.ErrorClass` (Linux `CAN_ERR_*` bits), `.DataBytes` (the eight detail bytes) |
//! | `EcuDiagnostics` | SI: ECU | `t` and one channel per numeric field of the diagnostics record (`mode` with its names) |
//!
//! `bus/restraint.dbc` is embedded as an attachment of `CAN_DataFrame`, so a tool that decodes
//! with attached databases needs nothing else.
//!
//! **Time.** The header's start time is the first event's CLOCK_REALTIME (UTC, whole µs); every
//! group's master channel `t` is seconds from it (f64): CAN frames at candump's kernel stamps,
//! diagnostics at their CLOCK_MONOTONIC timestamp plus the run's measured realtime − monotonic
//! offset — the same instants as the MCAP's log times, on the clock MDF tools expect. Without
//! that offset (no frame seen by both candump and the stubs) the diagnostics are left out and
//! the header comment says so.

use crate::diag_fields::DIAG_FIELDS;
use crate::run_folder::RunFiles;
use anyhow::{Context, Result};
use signals::{EcuDiagnostics, EcuMode};
use std::path::Path;

/// File name of a run's MDF recording in its folder.
pub const RUN_MF4: &str = "run.mf4";

/// The run summary's line for `path`.
pub fn summary_line(path: &Path, s: &Mf4Summary) -> String {
    format!(
        "recording (MDF 4.1): {} ({} CAN frames, {}{} diagnostics records, {:.0} kB; open in asammdf or CANape, docs/using.md \"Recordings\"){}",
        path.display(),
        s.can_frames,
        if s.error_frames > 0 {
            format!("{} error frames, ", s.error_frames)
        } else {
            String::new()
        },
        s.diagnostics,
        s.bytes as f64 / 1e3,
        s.diagnostics_left_out
            .as_deref()
            .map_or(String::new(), |w| format!("; diagnostics left out: {w}"))
    )
}

/// What was written.
#[derive(Clone, Debug)]
pub struct Mf4Summary {
    /// Frames in the CAN group (= candump's data frames).
    pub can_frames: usize,
    /// Records in the CAN_ErrorFrame group (= candump's error frames; no group when 0).
    pub error_frames: usize,
    /// Records in the diagnostics group (0 when left out).
    pub diagnostics: usize,
    /// Why the diagnostics are left out, if they are.
    pub diagnostics_left_out: Option<String>,
    /// The header's start time, CLOCK_REALTIME ns.
    pub start_realtime_ns: u64,
    /// File size, bytes.
    pub bytes: u64,
}

// Block and field codes of ASAM MDF 4.1 (the standard's names in comments).
const CN_TYPE_VALUE: u8 = 0; // fixed length data channel
const CN_TYPE_MASTER: u8 = 2;
const SYNC_NONE: u8 = 0;
const SYNC_TIME: u8 = 1;
const DT_UINT_LE: u8 = 0;
const DT_FLOAT_LE: u8 = 4;
const DT_BYTE_ARRAY: u8 = 10;
const CN_FLAG_BUS_EVENT: u32 = 1 << 10;
const CG_FLAG_BUS_EVENT: u16 = 1 << 1;
const CG_FLAG_PLAIN_BUS_EVENT: u16 = 1 << 2;
const SI_TYPE_ECU: u8 = 1;
const SI_TYPE_BUS: u8 = 2;
const SI_BUS_NONE: u8 = 0;
const SI_BUS_CAN: u8 = 2;
const SI_FLAG_SIMULATED: u8 = 1;
const CC_VALUE_TO_TEXT: u8 = 7;
const AT_FLAG_EMBEDDED: u16 = 1;
const NIL: u64 = 0;

/// The file in memory: blocks appended at 8-byte aligned addresses, each written after the
/// blocks it links to (children first), so every link is known when its block is written.
struct MdfFile {
    buf: Vec<u8>,
}

impl MdfFile {
    fn new() -> Self {
        // ID block: file id, format version, program, reserved, version number, reserved,
        // (un)finalized flags — a finalized file.
        let mut buf = Vec::with_capacity(1 << 16);
        buf.extend_from_slice(b"MDF     4.10    record  ");
        buf.extend_from_slice(&[0; 4]);
        buf.extend_from_slice(&410u16.to_le_bytes());
        buf.extend_from_slice(&[0; 30]);
        buf.extend_from_slice(&[0; 4]);
        debug_assert_eq!(buf.len(), 64);
        // The HD block has to be at 64; reserve it and write it last.
        buf.resize(64 + HD_LEN, 0);
        Self { buf }
    }

    /// Appends a block; its address.
    fn block(&mut self, id: &[u8; 4], links: &[u64], data: &[u8]) -> u64 {
        let at = self.buf.len() as u64;
        self.buf.extend_from_slice(&block_bytes(id, links, data));
        self.pad();
        at
    }

    fn pad(&mut self) {
        while !self.buf.len().is_multiple_of(8) {
            self.buf.push(0);
        }
    }

    /// A text block (TX), zero-terminated, padded; `NIL` for no text.
    fn text(&mut self, s: &str) -> u64 {
        if s.is_empty() {
            return NIL;
        }
        self.block(b"##TX", &[], &zero_terminated(s))
    }

    /// A metadata block (MD) holding XML.
    fn xml(&mut self, xml: &str) -> u64 {
        self.block(b"##MD", &[], &zero_terminated(xml))
    }

    /// A source (SI): name, type, bus type, simulated or not.
    fn source(&mut self, name: &str, path: &str, kind: u8, bus: u8, flags: u8) -> u64 {
        let (n, p) = (self.text(name), self.text(path));
        self.block(b"##SI", &[n, p, NIL], &[kind, bus, flags, 0, 0, 0, 0, 0])
    }

    /// A data block of `records`: header with its exact length, then padding outside it.
    fn data(&mut self, records: &[u8]) -> u64 {
        let at = self.buf.len() as u64;
        self.buf.extend_from_slice(b"##DT");
        self.buf.extend_from_slice(&[0; 4]);
        self.buf
            .extend_from_slice(&(24 + records.len() as u64).to_le_bytes());
        self.buf.extend_from_slice(&0u64.to_le_bytes());
        self.buf.extend_from_slice(records);
        self.pad();
        at
    }

    /// A value → text conversion (CC type 7): `pairs` of value and name; other values show
    /// as the number.
    fn value_to_text(&mut self, pairs: &[(u8, &str)]) -> u64 {
        let mut links = vec![NIL; 4]; // name, unit, comment, inverse
        links.extend(pairs.iter().map(|(_, t)| self.text(t)));
        links.push(NIL); // default: none
        let mut d = vec![CC_VALUE_TO_TEXT, 0];
        d.extend_from_slice(&0u16.to_le_bytes()); // flags
        d.extend_from_slice(&(pairs.len() as u16 + 1).to_le_bytes()); // ref count
        d.extend_from_slice(&(pairs.len() as u16).to_le_bytes()); // value count
        d.extend_from_slice(&0f64.to_le_bytes());
        d.extend_from_slice(&0f64.to_le_bytes());
        for (v, _) in pairs {
            d.extend_from_slice(&f64::from(*v).to_le_bytes());
        }
        self.block(b"##CC", &links, &d)
    }

    /// A data group of one channel group: `channels` (first = master `t`) over `records` of
    /// `record_bytes` each.
    #[allow(clippy::too_many_arguments)]
    fn group(
        &mut self,
        next_dg: u64,
        name: &str,
        source: u64,
        flags: u16,
        first_channel: u64,
        records: &[u8],
        record_bytes: usize,
        comment: &str,
    ) -> u64 {
        let dt = self.data(records);
        let name = self.text(name);
        let comment = self.text(comment);
        let mut d = Vec::with_capacity(32);
        d.extend_from_slice(&0u64.to_le_bytes()); // record id (one group: none)
        d.extend_from_slice(&((records.len() / record_bytes.max(1)) as u64).to_le_bytes());
        d.extend_from_slice(&flags.to_le_bytes());
        d.extend_from_slice(&u16::from(b'.').to_le_bytes()); // path separator
        d.extend_from_slice(&[0; 4]);
        d.extend_from_slice(&(record_bytes as u32).to_le_bytes());
        d.extend_from_slice(&0u32.to_le_bytes()); // invalidation bytes
        let cg = self.block(
            b"##CG",
            &[NIL, first_channel, name, source, NIL, comment],
            &d,
        );
        self.block(b"##DG", &[next_dg, cg, dt, NIL], &[0; 8])
    }
}

const HD_LEN: usize = 24 + 6 * 8 + 32;

fn zero_terminated(s: &str) -> Vec<u8> {
    let mut v = s.as_bytes().to_vec();
    v.push(0);
    while !v.len().is_multiple_of(8) {
        v.push(0);
    }
    v
}

fn block_bytes(id: &[u8; 4], links: &[u64], data: &[u8]) -> Vec<u8> {
    let mut b = Vec::with_capacity(24 + links.len() * 8 + data.len());
    b.extend_from_slice(id);
    b.extend_from_slice(&[0; 4]);
    b.extend_from_slice(&((24 + links.len() * 8 + data.len()) as u64).to_le_bytes());
    b.extend_from_slice(&(links.len() as u64).to_le_bytes());
    for l in links {
        b.extend_from_slice(&l.to_le_bytes());
    }
    b.extend_from_slice(data);
    b
}

/// One channel (CN) to be written.
struct Channel<'a> {
    name: &'a str,
    unit: &'a str,
    comment: &'a str,
    kind: u8,
    sync: u8,
    data_type: u8,
    byte_offset: u32,
    bit_offset: u8,
    bit_count: u32,
    flags: u32,
    conversion: u64,
    composition: u64,
    attachment: Option<u64>,
}

impl<'a> Channel<'a> {
    fn value(name: &'a str, data_type: u8, byte_offset: u32, bit_count: u32) -> Self {
        Self {
            name,
            unit: "",
            comment: "",
            kind: CN_TYPE_VALUE,
            sync: SYNC_NONE,
            data_type,
            byte_offset,
            bit_offset: 0,
            bit_count,
            flags: 0,
            conversion: NIL,
            composition: NIL,
            attachment: None,
        }
    }

    /// The master channel: seconds from the header's start time, f64 at byte 0.
    fn time() -> Self {
        Self {
            unit: "s",
            comment: "seconds from the header's start time (CLOCK_REALTIME, UTC)",
            kind: CN_TYPE_MASTER,
            sync: SYNC_TIME,
            ..Self::value("t", DT_FLOAT_LE, 0, 64)
        }
    }
}

impl MdfFile {
    /// Writes `channels` as one chain (`next` after the last); the first one's address.
    fn channels(&mut self, channels: &[Channel], next: u64) -> u64 {
        let mut next = next;
        for c in channels.iter().rev() {
            let name = self.text(c.name);
            let unit = self.text(c.unit);
            let comment = self.text(c.comment);
            let mut links = vec![
                next,
                c.composition,
                name,
                NIL,
                c.conversion,
                NIL,
                unit,
                comment,
            ];
            links.extend(c.attachment);
            let mut d = Vec::with_capacity(72);
            d.extend_from_slice(&[c.kind, c.sync, c.data_type, c.bit_offset]);
            d.extend_from_slice(&c.byte_offset.to_le_bytes());
            d.extend_from_slice(&c.bit_count.to_le_bytes());
            d.extend_from_slice(&c.flags.to_le_bytes());
            d.extend_from_slice(&0u32.to_le_bytes()); // invalidation bit position
            d.extend_from_slice(&[0, 0]); // precision, reserved
            d.extend_from_slice(&u16::from(c.attachment.is_some()).to_le_bytes());
            d.extend_from_slice(&[0; 48]); // value range and limits (not valid)
            next = self.block(b"##CN", &links, &d);
        }
        next
    }
}

/// Bytes of one CAN record: t, then `CAN_DataFrame` (bus channel, id | IDE << 31, DLC, data
/// length, 8 data bytes).
const CAN_RECORD_BYTES: usize = 8 + 1 + 4 + 1 + 1 + 8;

/// Bytes of one error record: t, then `CAN_ErrorFrame` (bus channel, ASAM error type, Linux
/// error classes, 8 detail bytes).
const ERROR_RECORD_BYTES: usize = 8 + 1 + 1 + 4 + 8;

/// Writes `out` (normally `DIR/run.mf4`) from the run folder `dir` (`candump.log` required,
/// the stubs' diagnostics log used when present).
///
/// # Errors
/// A file of the folder that cannot be read or parsed, or the output cannot be written.
pub fn write_run_mf4(dir: &Path, out: &Path) -> Result<Mf4Summary> {
    let run = RunFiles::read(dir)?;
    let frames = &run.log.frames;
    let diags: &[EcuDiagnostics] = &run.diagnostics.0;
    let diag_realtime = |d: &EcuDiagnostics| -> Option<i128> {
        run.offset
            .map(|o| i128::from(d.timestamp_ns) + i128::from(o))
    };
    let diagnostics_left_out = match (diags.is_empty(), run.offset) {
        (true, _) => None,
        (false, Some(_)) => None,
        (false, None) => Some(
            "no frame was seen by both candump and the stubs: the diagnostics' CLOCK_MONOTONIC \
             cannot be placed on the file's clock"
                .to_owned(),
        ),
    };
    let errors = &run.log.errors;
    let start_ns: u64 = frames
        .first()
        .map(|f| i128::from(f.t_us) * 1_000)
        .into_iter()
        .chain(errors.first().map(|e| i128::from(e.t_us) * 1_000))
        .chain(diags.first().and_then(diag_realtime))
        .min()
        // Whole µs: candump's resolution, and what a reader's date-time type holds exactly.
        .map(|t| t - t.rem_euclid(1_000))
        .and_then(|t| u64::try_from(t).ok())
        .unwrap_or(0);
    let seconds = |t_ns: i128| ((t_ns - i128::from(start_ns)) as f64) * 1e-9;

    let mut f = MdfFile::new();

    // Interfaces as bus channels 1, 2, … in order of appearance.
    let mut interfaces: Vec<String> = Vec::new();
    let mut channel_of = |device: &str| -> usize {
        match interfaces.iter().position(|i| i == device) {
            Some(i) => i + 1,
            None => {
                interfaces.push(device.to_owned());
                interfaces.len()
            }
        }
    };
    let mut can = Vec::with_capacity(frames.len() * CAN_RECORD_BYTES);
    for fr in frames {
        let channel = channel_of(&fr.device);
        can.extend_from_slice(&seconds(i128::from(fr.t_us) * 1_000).to_le_bytes());
        can.push(u8::try_from(channel).unwrap_or(u8::MAX));
        // Linux can_id: bit 31 = extended, as the standard's ID with IDE in bit 31.
        can.extend_from_slice(&fr.frame.id.to_le_bytes());
        let len = fr.frame.payload().len() as u8;
        can.extend_from_slice(&[len, len]);
        can.extend_from_slice(&fr.frame.data);
    }
    let mut err = Vec::with_capacity(errors.len() * ERROR_RECORD_BYTES);
    for e in errors {
        let channel = channel_of(&e.device);
        err.extend_from_slice(&seconds(i128::from(e.t_us) * 1_000).to_le_bytes());
        err.push(u8::try_from(channel).unwrap_or(u8::MAX));
        err.push(e.error_type);
        err.extend_from_slice(&e.class.to_le_bytes());
        err.extend_from_slice(&e.data);
    }

    // Diagnostics records: t, then the fields packed in order.
    let diag_bytes: usize = 8 + DIAG_FIELDS.iter().map(|c| c.bytes).sum::<usize>();
    let mut diag = Vec::new();
    if diagnostics_left_out.is_none() {
        diag.reserve(diags.len() * diag_bytes);
        for d in diags {
            let t = diag_realtime(d).map_or(f64::NAN, seconds);
            diag.extend_from_slice(&t.to_le_bytes());
            for c in &DIAG_FIELDS {
                diag.extend_from_slice(&(c.value)(d).le_bytes(c.bytes)[..c.bytes]);
            }
        }
    }

    let mode_names: Vec<(u8, &str)> = (0..=u8::MAX)
        .filter_map(|v| EcuMode::from_u8(v).map(|m| (v, m.name())))
        .collect();
    let mode_cc = f.value_to_text(&mode_names);
    let mut offset = 8u32;
    let diag_channels: Vec<Channel> = DIAG_FIELDS
        .iter()
        .map(|c| {
            let data_type = if c.float { DT_FLOAT_LE } else { DT_UINT_LE };
            let mut ch = Channel::value(c.name, data_type, offset, c.bytes as u32 * 8);
            ch.unit = c.unit;
            if c.name == "mode" {
                ch.conversion = mode_cc;
                ch.comment = "the ECU's mode (signals::EcuMode)";
            }
            offset += c.bytes as u32;
            ch
        })
        .collect();
    let mut chain = vec![Channel::time()];
    chain.extend(diag_channels);
    let first = f.channels(&chain, NIL);
    let ecu = f.source(
        bus::ECU_NODE,
        "iceoryx2 diagnostics, as the actuator stubs received them",
        SI_TYPE_ECU,
        SI_BUS_NONE,
        0,
    );
    let diag_dg = if diagnostics_left_out.is_none() && !diags.is_empty() {
        f.group(
            NIL,
            "EcuDiagnostics",
            ecu,
            0,
            first,
            &diag,
            diag_bytes,
            "one record per ECU cycle the stubs received (a cycle whose record the ECU never \
             published is a gap in cycle_count)",
        )
    } else {
        NIL
    };

    // The DBC travels with the file: a tool that decodes with attached databases needs no
    // other file.
    let dbc = include_bytes!("../../bus/restraint.dbc");
    let at_name = f.text("restraint.dbc");
    let at_mime = f.text("application/x-dbc");
    let mut at = Vec::with_capacity(40 + dbc.len());
    at.extend_from_slice(&AT_FLAG_EMBEDDED.to_le_bytes());
    at.extend_from_slice(&0u16.to_le_bytes()); // creator: the FH block 0
    at.extend_from_slice(&[0; 4]);
    at.extend_from_slice(&[0; 16]); // MD5 (flag not set: not given)
    at.extend_from_slice(&(dbc.len() as u64).to_le_bytes());
    at.extend_from_slice(&(dbc.len() as u64).to_le_bytes());
    at.extend_from_slice(dbc);
    let attachment = f.block(b"##AT", &[NIL, at_name, at_mime, NIL], &at);

    let byte = |name, off, bits| Channel::value(name, DT_UINT_LE, off, bits);
    let parts = [
        Channel {
            comment: "bus channel: 1 = the first interface in candump.log",
            ..byte("CAN_DataFrame.BusChannel", 8, 8)
        },
        byte("CAN_DataFrame.ID", 9, 29),
        Channel {
            bit_offset: 7,
            comment: "1 = 29-bit identifier",
            ..byte("CAN_DataFrame.IDE", 12, 1)
        },
        byte("CAN_DataFrame.DLC", 13, 4),
        Channel {
            unit: "B",
            ..byte("CAN_DataFrame.DataLength", 14, 8)
        },
        Channel::value("CAN_DataFrame.DataBytes", DT_BYTE_ARRAY, 15, 64),
    ];
    let composition = f.channels(&parts, NIL);
    let frame = Channel {
        flags: CN_FLAG_BUS_EVENT,
        composition,
        attachment: Some(attachment),
        comment: "CAN data frames as candump logged them (kernel receive time)",
        ..Channel::value(
            "CAN_DataFrame",
            DT_BYTE_ARRAY,
            8,
            (CAN_RECORD_BYTES as u32 - 8) * 8,
        )
    };
    let first = f.channels(&[Channel::time(), frame], NIL);
    let bus = f.source(
        &interfaces.join(","),
        "SocketCAN vcan (candump -L)",
        SI_TYPE_BUS,
        SI_BUS_CAN,
        SI_FLAG_SIMULATED,
    );
    let err_dg = if errors.is_empty() {
        diag_dg
    } else {
        let error_type_cc = f.value_to_text(&bus::candump::ASAM_ERROR_TYPES);
        let parts = [
            Channel {
                comment: "bus channel: 1 = the first interface in candump.log",
                ..byte("CAN_ErrorFrame.BusChannel", 8, 8)
            },
            Channel {
                conversion: error_type_cc,
                comment: "ASAM error type, read from the Linux report's protocol violation",
                ..byte("CAN_ErrorFrame.ErrorType", 9, 8)
            },
            Channel {
                comment: "Linux error classes (CAN_ERR_* bits of the error frame's id)",
                ..byte("CAN_ErrorFrame.ErrorClass", 10, 32)
            },
            Channel {
                comment: "the report's eight detail bytes (linux/can/error.h)",
                ..Channel::value("CAN_ErrorFrame.DataBytes", DT_BYTE_ARRAY, 14, 64)
            },
        ];
        let composition = f.channels(&parts, NIL);
        let frame = Channel {
            flags: CN_FLAG_BUS_EVENT,
            composition,
            comment: "CAN error frames as candump logged them (the controller's reports)",
            ..Channel::value(
                "CAN_ErrorFrame",
                DT_BYTE_ARRAY,
                8,
                (ERROR_RECORD_BYTES as u32 - 8) * 8,
            )
        };
        let first = f.channels(&[Channel::time(), frame], NIL);
        f.group(
            diag_dg,
            "CAN_ErrorFrame",
            bus,
            CG_FLAG_BUS_EVENT | CG_FLAG_PLAIN_BUS_EVENT,
            first,
            &err,
            ERROR_RECORD_BYTES,
            "",
        )
    };
    let can_dg = f.group(
        err_dg,
        "CAN",
        bus,
        CG_FLAG_BUS_EVENT | CG_FLAG_PLAIN_BUS_EVENT,
        first,
        &can,
        CAN_RECORD_BYTES,
        "",
    );

    let fh_comment = f.xml(&format!(
        "<FHcomment><TX>written from the run folder's candump.log and the actuator stubs' \
         diagnostics log</TX><tool_id>record</tool_id><tool_vendor>restraint bench</tool_vendor>\
         <tool_version>{}</tool_version></FHcomment>",
        env!("CARGO_PKG_VERSION")
    ));
    let mut fh = Vec::with_capacity(16);
    fh.extend_from_slice(&start_ns.to_le_bytes());
    fh.extend_from_slice(&[0; 8]); // UTC, no offsets; reserved
    let fh = f.block(b"##FH", &[NIL, fh_comment], &fh);
    let hd_comment = f.xml(&format!(
        "<HDcomment><TX>restraint bench run: CAN bus (vcan, candump's kernel stamps) and the \
         ECU's diagnostics on one clock. {}</TX></HDcomment>",
        diagnostics_left_out
            .as_deref()
            .map_or(String::new(), |r| format!("Diagnostics left out: {r}."))
    ));
    let mut hd = Vec::with_capacity(32);
    hd.extend_from_slice(&start_ns.to_le_bytes());
    hd.extend_from_slice(&[0; 24]); // UTC, no offsets, time class, flags; angle; distance
    let hd_bytes = block_bytes(
        b"##HD",
        &[can_dg, fh, NIL, attachment, NIL, hd_comment],
        &hd,
    );
    f.buf[64..64 + HD_LEN].copy_from_slice(&hd_bytes);

    std::fs::write(out, &f.buf).with_context(|| out.display().to_string())?;
    Ok(Mf4Summary {
        can_frames: frames.len(),
        error_frames: errors.len(),
        diagnostics: if diag_dg == NIL { 0 } else { diags.len() },
        diagnostics_left_out,
        start_realtime_ns: start_ns,
        bytes: f.buf.len() as u64,
    })
}
