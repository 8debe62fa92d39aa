//! `run.mcap` from a run folder (module docs of the crate: topics and clock).

use crate::run_folder::{missed_cycles, RunFiles};
use crate::schema;
use anyhow::{bail, Context, Result};
use mcap::records::MessageHeader;
use mcap::write::{Metadata, Writer};
use serde_json::Value;
use signals::FeedItem;
use std::collections::{BTreeMap, HashMap};
use std::io::BufWriter;
use std::path::Path;

/// What the folder cannot say about the run: where it ran.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct RunMeta {
    /// The vcan route (`host-vcan`, `qemu-kvm`, `qemu-tcg`, …).
    pub route: String,
    /// Whether the route's timing is emulated (a virtual CPU's), not the host's (`None`: not
    /// known, e.g. a folder recorded after the fact).
    pub timing_emulated: Option<bool>,
    /// The scenario file the run played: its closed-form truth goes on `/truth/world`.
    pub scenario: Option<std::path::PathBuf>,
    /// A simulated run (the offline bench): every time in the folder is on its simulated
    /// clock, and its scenario starts at this time, ns. `None`: a bench run (the clocks are
    /// the kernel's; the start is the stubs' report's).
    #[serde(default)]
    pub simulated_start_ns: Option<u64>,
}

/// What was written.
#[derive(Clone, Debug)]
pub struct WriteSummary {
    /// Messages per topic.
    pub messages: BTreeMap<String, u64>,
    /// CLOCK_REALTIME − CLOCK_MONOTONIC used for candump's stamps, ns (`None`: no frame seen by
    /// both candump and the stubs; log times are then candump's realtime stamps).
    pub realtime_minus_monotonic_ns: Option<i64>,
    /// File size, bytes.
    pub bytes: u64,
}

/// One JSON topic of the file.
struct Topic {
    channel: u16,
    sequence: u32,
}

/// The file being written: topics by name, schemas added on first use.
struct Recording<W: std::io::Write + std::io::Seek> {
    w: Writer<W>,
    /// What turns a bench time (CLOCK_MONOTONIC) into the file's log time, ns: the run's
    /// realtime − monotonic offset (log times in UTC), or 0 (a simulated run, or no offset).
    to_log_ns: i64,
    topics: HashMap<String, Topic>,
    counts: BTreeMap<String, u64>,
    buf: Vec<u8>,
}

impl<W: std::io::Write + std::io::Seek> Recording<W> {
    fn topic(&mut self, name: &str, schema_name: &str, schema: &Value) -> Result<u16> {
        if let Some(t) = self.topics.get(name) {
            return Ok(t.channel);
        }
        let schema_id = self.w.add_schema(
            schema_name,
            "jsonschema",
            serde_json::to_string(schema)?.as_bytes(),
        )?;
        let channel = self
            .w
            .add_channel(schema_id, name, "json", &BTreeMap::new())?;
        self.topics.insert(
            name.to_owned(),
            Topic {
                channel,
                sequence: 0,
            },
        );
        Ok(channel)
    }

    fn write(
        &mut self,
        topic: &str,
        schema_name: &str,
        schema: &Value,
        log_time: u64,
        publish_time: u64,
        msg: &impl serde::Serialize,
    ) -> Result<()> {
        let channel_id = self.topic(topic, schema_name, schema)?;
        let t = self.topics.get_mut(topic).expect("added above");
        t.sequence = t.sequence.wrapping_add(1);
        // Serialized straight into one reused buffer: no JSON tree, no string per message.
        self.buf.clear();
        serde_json::to_writer(&mut self.buf, msg)?;
        self.w.write_to_known_channel(
            &MessageHeader {
                channel_id,
                sequence: t.sequence,
                log_time: log_time.saturating_add_signed(self.to_log_ns),
                publish_time,
            },
            &self.buf,
        )?;
        *self.counts.entry(topic.to_owned()).or_default() += 1;
        Ok(())
    }
}

/// Writes `out` (normally `DIR/run.mcap`) from the run folder `dir`. `candump.log` is required;
/// `commands.jsonl` and `report.json` are recorded when present.
///
/// # Errors
/// A file that cannot be read or parsed, or the MCAP cannot be written.
pub fn write_run(dir: &Path, out: &Path, meta: &RunMeta) -> Result<WriteSummary> {
    let RunFiles {
        candump_path,
        log,
        commands,
        commands_unreadable,
        report,
        diagnostics,
        feeds,
        offset,
    } = RunFiles::read(dir)?;
    // A simulated run has one clock: candump's stamps and the records' are the same.
    let offset = if meta.simulated_start_ns.is_some() {
        Some(0)
    } else {
        offset
    };
    // The truth of a scenario that cannot be loaded (a damaged file of the campaign) is left
    // out and said so in the metadata; everything else is still recorded.
    let truth = meta.scenario.as_ref().map(|path| {
        world::Scenario::load(path)
            .map_err(|e| e.to_string())
            .and_then(|s| world::Truth::new(&s).map(|t| (s, t)))
    });
    let file = std::fs::File::create(out).with_context(|| out.display().to_string())?;
    // Log times in UTC where the run measured its realtime − monotonic offset (the MF4 of the
    // same run is stamped in UTC too): every bench time below is CLOCK_MONOTONIC and moves by
    // that offset; a simulated run (its offset 0, above) keeps its one clock.
    let to_log_ns = offset.unwrap_or(0);
    let mut rec = Recording {
        w: Writer::new(BufWriter::new(file))?,
        to_log_ns,
        topics: HashMap::new(),
        counts: BTreeMap::new(),
        buf: Vec::with_capacity(4096),
    };
    let mut bench = BTreeMap::from([
        ("route".to_owned(), meta.route.clone()),
        (
            "timing".to_owned(),
            match (meta.simulated_start_ns, meta.timing_emulated) {
                (Some(_), _) => "simulated (the offline bench: the core on a simulated clock)",
                (None, Some(true)) => "emulated (a virtual CPU's; measure real timing on the host)",
                (None, Some(false)) => "real",
                (None, None) => "unknown",
            }
            .to_owned(),
        ),
        (
            "log_time_clock".to_owned(),
            if meta.simulated_start_ns.is_some() {
                "the offline bench's simulated clock (restraint::SimLoop), ns: no processes, \
                 frames at their cycle or tick without bus latency"
                    .to_owned()
            } else if offset.is_some() {
                "CLOCK_REALTIME (UTC), ns: the bench's CLOCK_MONOTONIC + realtime_minus_monotonic_ns"
                    .to_owned()
            } else {
                "CLOCK_REALTIME (candump's stamps; no frame seen by both candump and the stubs)"
                    .to_owned()
            },
        ),
        (
            "can_publish_time".to_owned(),
            "candump's kernel arrival stamp, CLOCK_REALTIME ns".to_owned(),
        ),
        (
            "realtime_minus_monotonic_ns".to_owned(),
            offset.map_or_else(String::new, |o| o.to_string()),
        ),
        ("dbc".to_owned(), "bus/restraint.dbc".to_owned()),
        ("can_frames".to_owned(), log.frames.len().to_string()),
        (
            "commands_lines_unreadable".to_owned(),
            commands_unreadable.to_string(),
        ),
        (
            "diagnostics_records".to_owned(),
            diagnostics.0.len().to_string(),
        ),
        (
            "diagnostics_missed".to_owned(),
            missed_cycles(&diagnostics.0).to_string(),
        ),
        (
            "diagnostics_log_trailing_bytes".to_owned(),
            diagnostics.1.to_string(),
        ),
        ("candump_lines_skipped".to_owned(), log.skipped.to_string()),
        ("feeds_records".to_owned(), feeds.0.len().to_string()),
        ("feeds_log_trailing_bytes".to_owned(), feeds.1.to_string()),
    ]);
    if let Some((r, _)) = &report {
        bench.insert("scenario".to_owned(), r.scenario.clone());
        bench.insert("start_ns".to_owned(), r.start_ns.to_string());
        bench.insert("contact_ns".to_owned(), r.contact_ns.to_string());
    } else if let Some(start) = meta.simulated_start_ns {
        // A run without the stubs' report (the offline bench): the scenario's name and its
        // true contact from the truth, on the simulated clock.
        bench.insert("start_ns".to_owned(), start.to_string());
        if let Some(Ok((s, t))) = &truth {
            bench.insert("scenario".to_owned(), s.name.clone());
            let contact = t
                .contact_s
                .map_or(0, |c| start.saturating_add((c * 1e9).round() as u64));
            bench.insert("contact_ns".to_owned(), contact.to_string());
        }
    }
    rec.w.write_metadata(&Metadata {
        name: "bench".to_owned(),
        metadata: bench,
    })?;
    if let Ok(toml) = std::fs::read_to_string(dir.join(crate::ECU_CONFIG)) {
        rec.w.write_metadata(&Metadata {
            name: "ecu_config".to_owned(),
            metadata: BTreeMap::from([("toml".to_owned(), toml)]),
        })?;
    }

    let to_mono = |realtime_ns: u64| -> u64 {
        offset.map_or(realtime_ns, |o| {
            u64::try_from(realtime_ns as i64 - o).unwrap_or_default()
        })
    };
    let raw_schema = schema::raw_frame_schema();
    /// A DBC message's topic: its table row and signals, topic and schema, made once.
    struct MessageTopic {
        info: &'static bus::MessageInfo,
        signals: &'static [bus::SignalInfo],
        topic: String,
        schema_name: String,
        schema: Value,
    }
    let msg_topics: HashMap<u32, MessageTopic> = bus::MESSAGES
        .iter()
        .map(|m| {
            let signals = bus::signals_of(m.id).unwrap_or(&[]);
            let t = MessageTopic {
                info: m,
                signals,
                topic: format!("/can/{}", m.name),
                schema_name: schema::message_schema_name(m),
                schema: schema::message_schema(m, signals),
            };
            (m.id, t)
        })
        .collect();
    for f in &log.frames {
        let publish = f.t_us * 1_000;
        let log_time = to_mono(publish);
        rec.write(
            "/can/raw",
            schema::RAW_FRAME_SCHEMA,
            &raw_schema,
            log_time,
            publish,
            &schema::raw_frame(&f.device, &f.frame),
        )?;
        if let Some(m) = msg_topics.get(&f.frame.id) {
            if f.frame.payload().len() == m.info.size {
                let v = schema::message_values(m.signals, f.frame.payload());
                rec.write(&m.topic, &m.schema_name, &m.schema, log_time, publish, &v)?;
            }
        }
    }

    let error_schema = schema::error_frame_schema();
    for e in &log.errors {
        let publish = e.t_us * 1_000;
        rec.write(
            "/can/error",
            schema::ERROR_FRAME_SCHEMA,
            &error_schema,
            to_mono(publish),
            publish,
            &schema::error_frame(e),
        )?;
    }

    let diag_schema = schema::diagnostics_schema();
    let pulse_schema = schema::predicted_pulse_schema();
    let log_schema = schema::log_schema();
    let mut last_pulse: Option<schema::PulseMessage> = None;
    let mut prev = None;
    for d in &diagnostics.0 {
        if let Some(log) = schema::mode_change_log(prev, d) {
            rec.write(
                "/ecu/log",
                schema::LOG_SCHEMA,
                &log_schema,
                d.timestamp_ns,
                d.timestamp_ns,
                &log,
            )?;
        }
        prev = Some(d);
        let pulse = schema::predicted_pulse(d);
        if last_pulse.as_ref() != Some(&pulse) {
            rec.write(
                "/ecu/predicted_pulse",
                schema::PULSE_SCHEMA,
                &pulse_schema,
                d.timestamp_ns,
                d.timestamp_ns,
                &pulse,
            )?;
            last_pulse = Some(pulse);
        }
        rec.write(
            "/ecu/diagnostics",
            schema::DIAGNOSTICS_SCHEMA,
            &diag_schema,
            d.timestamp_ns,
            d.timestamp_ns,
            &schema::diagnostics(d),
        )?;
    }

    // What the sensor feeds published, at the publish time (the measurement's own time is in
    // the message).
    let (object_schema, accel_schema) = (schema::object_schema(), schema::accel_batch_schema());
    let satellite_schema = schema::satellite_schema();
    for r in &feeds.0 {
        let t = r.published_ns;
        match &r.item {
            FeedItem::Object(o) => rec.write(
                "/sensors/object",
                schema::OBJECT_SCHEMA,
                &object_schema,
                t,
                t,
                &schema::object(o),
            )?,
            FeedItem::CrashAccel(b) => rec.write(
                "/sensors/crash_accel",
                schema::ACCEL_SCHEMA,
                &accel_schema,
                t,
                t,
                &schema::accel_batch(b),
            )?,
            FeedItem::SafingAccel(b) => rec.write(
                "/sensors/safing_accel",
                schema::ACCEL_SCHEMA,
                &accel_schema,
                t,
                t,
                &schema::accel_batch(b),
            )?,
            FeedItem::SatelliteLeft(b) | FeedItem::SatelliteRight(b) => rec.write(
                if matches!(r.item, FeedItem::SatelliteLeft(_)) {
                    "/sensors/satellite_left"
                } else {
                    "/sensors/satellite_right"
                },
                schema::SATELLITE_SCHEMA,
                &satellite_schema,
                t,
                t,
                &schema::satellite_batch(b),
            )?,
        }
    }

    let commands_schema = schema::records_schema(
        &commands,
        "restraint_bench.StubsCommand",
        "One command frame the actuator stubs received (CLOCK_MONOTONIC receive time), decoded, with its E2E and SecOC verdict (actuator-stubs/README.md)",
    );
    if let Some(Err(e)) = &truth {
        rec.w.write_metadata(&Metadata {
            name: "truth".to_owned(),
            metadata: BTreeMap::from([("left_out".to_owned(), e.clone())]),
        })?;
    }
    let start_ns = report
        .as_ref()
        .map(|(r, _)| r.start_ns)
        .or(meta.simulated_start_ns);
    if let (Some(Ok((scenario, truth))), Some(start_ns)) = (&truth, start_ns) {
        let schema = schema::truth_schema(&truth.state(0.0));
        let steps = (scenario.duration_s * 1e3).round() as u64;
        for k in 0..=steps {
            let t = start_ns + k * 1_000_000;
            rec.write(
                "/truth/world",
                schema::TRUTH_SCHEMA,
                &schema,
                t,
                t,
                &truth.state(k as f64 * 1e-3),
            )?;
        }
    }
    for c in &commands {
        let t = c["rx_mono_ns"].as_u64().unwrap_or_default();
        rec.write(
            "/stubs/commands",
            "restraint_bench.StubsCommand",
            &commands_schema,
            t,
            t,
            c,
        )?;
    }
    if let Some((r, report_json)) = &report {
        // The channel exists in a run without actions too (no fire is an outcome; a layout's
        // panel then shows an empty topic, not a missing one).
        let actions = report_json["actions"]
            .as_array()
            .map(Vec::as_slice)
            .unwrap_or(&[]);
        let actions_schema = schema::records_schema(
            actions,
            "restraint_bench.StubsAction",
            "One action of a restraint module the stubs act as (airbag fire, pretensioner fire or release …), at the stubs' clock",
        );
        rec.topic(
            "/stubs/actions",
            "restraint_bench.StubsAction",
            &actions_schema,
        )?;
        for (a, v) in r.actions.iter().zip(actions) {
            let t = r.start_ns.saturating_add((a.t_ms * 1e6).round() as u64);
            rec.write(
                "/stubs/actions",
                "restraint_bench.StubsAction",
                &actions_schema,
                t,
                t,
                v,
            )?;
        }
        let end = log
            .frames
            .last()
            .map_or(r.start_ns, |f| to_mono(f.t_us * 1_000));
        let mut verdict = report_json.clone();
        if let Some(o) = verdict.as_object_mut() {
            o.remove("actions");
        }
        let verdict_schema = schema::records_schema(
            [&verdict],
            "restraint_bench.StubsReport",
            "The stubs' verdict on the run: the occupant outcome with the adaptive and the reference restraint, the modes, the required fire time and the airbag's margin (report.json without its actions)",
        );
        rec.write(
            "/stubs/verdict",
            "restraint_bench.StubsReport",
            &verdict_schema,
            end,
            end,
            &verdict,
        )?;
    }
    rec.w.finish()?;
    let counts = rec.counts;
    drop(rec.w);
    let bytes = std::fs::metadata(out)?.len();
    if counts.get("/can/raw").copied().unwrap_or(0) != log.frames.len() as u64 {
        bail!("not every frame of {} was recorded", candump_path.display());
    }
    Ok(WriteSummary {
        messages: counts,
        realtime_minus_monotonic_ns: offset,
        bytes,
    })
}
