//! Reading back what [`crate::write`] put in a `run.mcap`, to replay a run and judge the replay
//! against it:
//!
//! * [`feeds`]: what the run's feeds published — the object list, both accelerometers, the two
//!   satellites — and the CAN frames the ECU received (every `/can/raw` frame whose DBC
//!   transmitter is not the ECU: the vehicle, occupant and V2X frames, and whatever else a test
//!   put on the bus), in the order and at the times they went out (`sensor-feeds --replay`);
//! * [`report`]: the actuator stubs' report as their `report.json` was — `/stubs/verdict` with
//!   the `/stubs/actions` put back in its `actions` (`hil-bench --replay` compares with it).
//!
//! Times are the bench's CLOCK_MONOTONIC: each message's `log_time` (the feed's publish,
//! candump's arrival for CAN; in UTC in a bench run's file, taken back by the offset its
//! `bench` metadata gives) and the time stamps inside the messages. A replay shifts every one
//! of them by one offset ([`Item::shifted`]), so the ECU sees the recorded run's timing on its
//! own clock; the CAN frames go out byte for byte (their E2E counters and CRCs are the
//! recorded ones).

use anyhow::{bail, Context, Result};
use bus::RawFrame;
use serde_json::Value;
use signals::{CrashAccelSample, FeedItem, ObjectState, SatelliteFrames};
use std::collections::BTreeMap;

/// The stubs' report of a recorded run.
///
/// # Errors
/// Not an MCAP file, a message that is not JSON, or no `/stubs/verdict` (a recording of a run
/// without the stubs: the offline bench's).
pub fn report(mcap_bytes: &[u8]) -> Result<Value> {
    let (mut verdict, mut actions) = (None, Vec::new());
    for m in mcap::MessageStream::new(mcap_bytes).context("reading the MCAP")? {
        let m = m.context("reading the MCAP")?;
        let topic = m.channel.topic.as_str();
        if topic != "/stubs/verdict" && topic != "/stubs/actions" {
            continue;
        }
        let v: Value = serde_json::from_slice(&m.data)
            .with_context(|| format!("{topic} at {} ns: not JSON", m.log_time))?;
        if topic == "/stubs/verdict" {
            verdict = Some(v);
        } else {
            actions.push(v);
        }
    }
    let Some(mut verdict) = verdict else {
        bail!("the recording has no /stubs/verdict (a run without the actuator stubs?)");
    };
    if let Some(o) = verdict.as_object_mut() {
        o.insert("actions".into(), Value::Array(actions));
    }
    Ok(verdict)
}

/// What a file's log time is less than the bench time it stands for, ns: the run's realtime −
/// monotonic offset where its `bench` metadata says the log times are UTC, else 0 (a simulated
/// run, a file whose log times are the bench's own clock).
pub fn log_minus_bench_ns(bench: &BTreeMap<String, String>) -> i64 {
    let utc = bench
        .get("log_time_clock")
        .is_some_and(|c| c.contains("UTC"));
    bench
        .get("realtime_minus_monotonic_ns")
        .and_then(|o| o.parse::<i64>().ok())
        .filter(|_| utc)
        .unwrap_or(0)
}

/// One thing to publish.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Item {
    /// A feed's publication (`/sensors/*`), on its iceoryx2 service.
    Feed(FeedItem),
    /// A CAN frame the ECU received (`/can/raw`).
    Can(RawFrame),
}

impl Item {
    /// The item with its time stamp (a sample's or the first sample's) moved by `offset_ns`
    /// (frames carry none).
    #[must_use]
    pub fn shifted(mut self, offset_ns: i64) -> Self {
        let t = match &mut self {
            Item::Feed(FeedItem::Object(o)) => &mut o.timestamp_ns,
            Item::Feed(FeedItem::CrashAccel(b) | FeedItem::SafingAccel(b)) => {
                &mut b.first_timestamp_ns
            }
            Item::Feed(FeedItem::SatelliteLeft(b) | FeedItem::SatelliteRight(b)) => {
                &mut b.first_timestamp_ns
            }
            Item::Can(_) => return self,
        };
        *t = t.saturating_add_signed(offset_ns);
        self
    }
}

/// A recorded run, ready to play.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The scenario's name (the recording's `bench` metadata).
    pub scenario: String,
    /// CLOCK_MONOTONIC time of the recorded run's scenario t = 0, ns.
    pub start_ns: u64,
    /// CLOCK_MONOTONIC time of its true first contact, ns (`None`: no contact).
    pub contact_ns: Option<u64>,
    /// What to publish, in time order: (publish time, item).
    pub items: Vec<(u64, Item)>,
}

/// Reads what a run's `run.mcap` holds to be played again ([`Recording`]).
///
/// # Errors
/// Not an MCAP file, no `bench` metadata with the scenario and its start, a message that is
/// not what its topic's schema says, or nothing to play.
pub fn feeds(bytes: &[u8]) -> Result<Recording> {
    let bench = bench_metadata(bytes)?;
    let get = |k: &str| {
        bench
            .get(k)
            .filter(|v| !v.is_empty())
            .with_context(|| format!("the recording's `bench` metadata has no `{k}`"))
    };
    let scenario = get("scenario")?.clone();
    let start_ns: u64 = get("start_ns")?.parse().context("bench.start_ns")?;
    // Log times in UTC (a bench run's file) back on the bench's clock, where the time stamps
    // inside the messages are.
    let log_minus_bench_ns = log_minus_bench_ns(&bench);
    let contact_ns = bench
        .get("contact_ns")
        .and_then(|v| v.parse::<u64>().ok())
        .filter(|t| *t != 0);
    let mut items = Vec::new();
    for m in mcap::MessageStream::new(bytes).context("reading the MCAP")? {
        let m = m.context("reading the MCAP")?;
        let topic = m.channel.topic.as_str();
        let parse = || -> Result<serde_json::Value> {
            serde_json::from_slice(&m.data)
                .with_context(|| format!("{topic} at {} ns: not JSON", m.log_time))
        };
        let item = match topic {
            "/sensors/object" => Item::Feed(FeedItem::Object(object(parse()?)?)),
            "/sensors/crash_accel" => Item::Feed(FeedItem::CrashAccel(accel(&parse()?)?)),
            "/sensors/safing_accel" => Item::Feed(FeedItem::SafingAccel(accel(&parse()?)?)),
            "/sensors/satellite_left" => Item::Feed(FeedItem::SatelliteLeft(satellite(&parse()?)?)),
            "/sensors/satellite_right" => {
                Item::Feed(FeedItem::SatelliteRight(satellite(&parse()?)?))
            }
            "/can/raw" => match can_input(&parse()?)? {
                Some(f) => Item::Can(f),
                None => continue,
            },
            _ => continue,
        };
        items.push((m.log_time.saturating_add_signed(-log_minus_bench_ns), item));
    }
    if items.is_empty() {
        bail!("the recording has no /sensors/* or CAN input messages to play");
    }
    // Stable: items published in the same nanosecond keep the file's order.
    items.sort_by_key(|(t, _)| *t);
    Ok(Recording {
        scenario,
        start_ns,
        contact_ns,
        items,
    })
}

/// The file's `bench` metadata (`crate::write`'s run description: clock, offset, scenario …).
pub(crate) fn bench_metadata(bytes: &[u8]) -> Result<BTreeMap<String, String>> {
    let summary = mcap::read::Summary::read(bytes)
        .context("reading the MCAP's summary")?
        .context("the MCAP has no summary section")?;
    for index in &summary.metadata_indexes {
        if index.name == "bench" {
            let m = mcap::read::metadata(bytes, index).context("reading the `bench` metadata")?;
            return Ok(m.metadata);
        }
    }
    bail!("the recording has no `bench` metadata (not a bench run's run.mcap?)")
}

fn field<'a>(v: &'a serde_json::Value, key: &str) -> Result<&'a serde_json::Value> {
    v.get(key).with_context(|| format!("no `{key}`"))
}

fn u64_of(v: &serde_json::Value, key: &str) -> Result<u64> {
    field(v, key)?
        .as_u64()
        .with_context(|| format!("`{key}` is not an unsigned integer"))
}

fn object(mut v: serde_json::Value) -> Result<ObjectState> {
    if let Some(m) = v.as_object_mut() {
        m.insert("_reserved".into(), serde_json::json!([0, 0, 0]));
    }
    serde_json::from_value(v).context("/sensors/object")
}

/// A batch's header fields and its values into `slots` (at most their number), each read by
/// `parse` (`None`: not a value of this batch, named `what`); returns (first time, sequence,
/// sample period, count).
fn batch<T>(
    v: &serde_json::Value,
    key: &str,
    slots: &mut [T],
    what: &str,
    parse: impl Fn(&serde_json::Value) -> Option<T>,
) -> Result<(u64, u64, u32, u32)> {
    let values = field(v, key)?
        .as_array()
        .with_context(|| format!("`{key}` is not an array"))?;
    if values.len() > slots.len() {
        bail!(
            "{} {key} in one batch, at most {}",
            values.len(),
            slots.len()
        );
    }
    for (slot, x) in slots.iter_mut().zip(values) {
        *slot = parse(x).with_context(|| format!("an entry of `{key}` is not {what}"))?;
    }
    Ok((
        u64_of(v, "first_timestamp_ns")?,
        u64_of(v, "sequence")?,
        u32::try_from(u64_of(v, "sample_period_ns")?)?,
        u32::try_from(u64_of(v, "count")?)?,
    ))
}

fn accel(v: &serde_json::Value) -> Result<CrashAccelSample> {
    let mut b = CrashAccelSample::EMPTY;
    (
        b.first_timestamp_ns,
        b.sequence,
        b.sample_period_ns,
        b.count,
    ) = batch(v, "accel_mps2", &mut b.accel_mps2, "a number", |x| {
        x.as_f64().map(|a| a as f32)
    })?;
    Ok(b)
}

fn satellite(v: &serde_json::Value) -> Result<SatelliteFrames> {
    let mut b = SatelliteFrames::EMPTY;
    (
        b.first_timestamp_ns,
        b.sequence,
        b.sample_period_ns,
        b.count,
    ) = batch(v, "frames", &mut b.frames, "a 16-bit word", |x| {
        x.as_u64().and_then(|f| u16::try_from(f).ok())
    })?;
    Ok(b)
}

/// A `/can/raw` frame the ECU received: a DBC message another node sends, or an id the DBC
/// does not know (a test's); the ECU's own frames are not replayed.
fn can_input(v: &serde_json::Value) -> Result<Option<RawFrame>> {
    let id = u32::try_from(u64_of(v, "id")?)?;
    let extended = field(v, "extended")?.as_bool().unwrap_or(false);
    let data: Vec<u8> = field(v, "data")?
        .as_array()
        .context("`data` is not an array")?
        .iter()
        .map(|b| b.as_u64().and_then(|b| u8::try_from(b).ok()))
        .collect::<Option<_>>()
        .context("a data byte is not 0..=255")?;
    if !extended && bus::message_info(id).is_some_and(|m| m.transmitter == bus::ECU_NODE) {
        return Ok(None);
    }
    let id = if extended { id | bus::CAN_EFF_FLAG } else { id };
    Ok(Some(RawFrame::new(id, &data)))
}
