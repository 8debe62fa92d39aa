//! The files and frames a case plays instead of the library's: a damaged table, a scenario
//! variant or lengthened, a recorded fire command to replay, forged ones to inject.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

use super::Variant;

/// The damaged LUT file for a case.
pub(super) fn damaged_lut(repo: &Path, dir: &Path, truncated: bool) -> Result<PathBuf> {
    let src = repo.join("data/default.lut");
    let mut bytes = std::fs::read(&src).with_context(|| format!("reading {}", src.display()))?;
    let mid = bytes.len() / 2;
    if truncated {
        bytes.truncate(mid);
    } else if let Some(b) = bytes.get_mut(mid) {
        *b ^= 0x10;
    }
    std::fs::create_dir_all(dir)?;
    let path = dir.join(if truncated {
        "truncated.lut"
    } else {
        "corrupt.lut"
    });
    std::fs::write(&path, bytes)?;
    Ok(path)
}

/// The stale-objects variant of a scenario (adds a `freezes` window), written to `dir`.
pub(crate) fn frozen_scenario(src: &Path, dir: &Path, from_s: f64, to_s: f64) -> Result<PathBuf> {
    let text =
        std::fs::read_to_string(src).with_context(|| format!("reading {}", src.display()))?;
    let mut doc: toml::Table = text.parse().context("scenario TOML")?;
    let sensor = doc
        .entry("sensor")
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    let Some(sensor) = sensor.as_table_mut() else {
        bail!("[sensor] is not a table");
    };
    let mut w = toml::Table::new();
    w.insert("start_s".into(), toml::Value::Float(from_s));
    w.insert("end_s".into(), toml::Value::Float(to_s));
    sensor.insert(
        "freezes".into(),
        toml::Value::Array(vec![toml::Value::Table(w)]),
    );
    write_variant(src, dir, doc)
}

/// The variant of a scenario a [`Fault::Variant`] plays, written to `dir`, with the `[expect]`
/// it must meet: a misreported crash still fires (no worse than the reference restraint, the
/// judge checks); a dead or stuck accelerometer is on the bus before the contact and the
/// crash gets the reference restraint; every other variant keeps the base's expectations.
pub fn variant_scenario(src: &Path, dir: &Path, v: Variant) -> Result<PathBuf> {
    let base = world::Scenario::load(src)?;
    let contact_s = world::Truth::new(&base)
        .map_err(anyhow::Error::msg)?
        .contact_s;
    let text =
        std::fs::read_to_string(src).with_context(|| format!("reading {}", src.display()))?;
    let mut doc: toml::Table = text.parse().context("scenario TOML")?;
    let table = |doc: &mut toml::Table, name: &str| -> Result<toml::Table> {
        match doc.remove(name) {
            Some(toml::Value::Table(t)) => Ok(t),
            None => Ok(toml::Table::new()),
            Some(_) => bail!("[{name}] is not a table"),
        }
    };
    let mut sensor = table(&mut doc, "sensor")?;
    let mut expect = table(&mut doc, "expect")?;
    let window = |start_s: f64, extra: Option<(&str, &str)>| {
        let mut w = toml::Table::new();
        w.insert("start_s".into(), toml::Value::Float(start_s));
        w.insert("end_s".into(), toml::Value::Float(1000.0));
        if let Some((k, val)) = extra {
            w.insert(k.into(), toml::Value::String(val.into()));
        }
        toml::Value::Array(vec![toml::Value::Table(w)])
    };
    let before_contact = |lead_s: f64| -> Result<f64> {
        Ok((contact_s.context("the variant needs a contact")? - lead_s).max(0.0))
    };
    match v {
        Variant::AsIs => {}
        Variant::MassMisreport {
            true_kg,
            reported_kg,
        } => {
            let mut opp = table(&mut doc, "opponent")?;
            opp.insert("mass_kg".into(), toml::Value::Float(true_kg));
            opp.remove("class");
            doc.insert("opponent".into(), toml::Value::Table(opp));
            sensor.insert("mass_estimate_kg".into(), toml::Value::Float(reported_kg));
        }
        Variant::SpeedBias { mps } => {
            sensor.insert("speed_bias_mps".into(), toml::Value::Float(mps));
            // A bias that takes the prediction beyond the table gives no pre-crash preset.
            expect.remove("pretensioner_before_contact");
        }
        Variant::AccelDead { before_contact_s } => {
            let from = before_contact(before_contact_s)?;
            sensor.insert("dropouts".into(), window(from, Some(("target", "accel"))));
        }
        Variant::AccelStuck { before_contact_s } => {
            let from = before_contact(before_contact_s)?;
            sensor.insert("accel_faults".into(), window(from, Some(("kind", "stuck"))));
        }
        Variant::Dropout { target, from_s } => {
            sensor.insert("dropouts".into(), window(from_s, Some(("target", target))));
            expect.insert("reference_fallback".into(), toml::Value::Boolean(true));
        }
        Variant::Frozen { from_s } => {
            sensor.insert("freezes".into(), window(from_s, None));
            expect.insert("reference_fallback".into(), toml::Value::Boolean(true));
        }
    }
    if matches!(v, Variant::AccelDead { .. } | Variant::AccelStuck { .. }) {
        expect.insert(
            "accel_fault_before_contact".into(),
            toml::Value::Boolean(true),
        );
        expect.remove("pretensioner_before_contact");
        if expect.get("airbag_fires") == Some(&toml::Value::Boolean(true)) {
            expect.insert("reference_fallback".into(), toml::Value::Boolean(true));
        }
    }
    doc.insert("sensor".into(), toml::Value::Table(sensor));
    doc.insert("expect".into(), toml::Value::Table(expect));
    write_variant(src, dir, doc)
}

/// A number from a TOML table (integers are numbers too).
fn toml_f64(t: &toml::Table, key: &str) -> Option<f64> {
    match t.get(key)? {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// The scenario with `extra_s` more of steady approach before everything happens: longer
/// duration, braking `extra_s` later, the opponent further away by `extra_s` × closing speed —
/// the same crash at `extra_s` later. In a TCG guest on host time a restarted feed is back
/// ≈ 1.2 s after its restart (measured; emulated CPUs; 41 ms in virtual time), so it needs
/// this head room to be back before the pre-crash phase on either clock.
pub fn lengthened_scenario(src: &Path, dir: &Path, extra_s: f64) -> Result<PathBuf> {
    let text =
        std::fs::read_to_string(src).with_context(|| format!("reading {}", src.display()))?;
    let mut doc: toml::Table = text.parse().context("scenario TOML")?;
    let speed = |doc: &toml::Table, part: &str| {
        doc.get(part)
            .and_then(toml::Value::as_table)
            .and_then(|t| toml_f64(t, "speed_kph"))
            .with_context(|| format!("[{part}] speed_kph"))
    };
    let closing_mps = (speed(&doc, "ego")? + speed(&doc, "opponent")?) / 3.6;
    let duration_s = toml_f64(&doc, "duration_s").context("duration_s")?;
    doc.insert(
        "duration_s".into(),
        toml::Value::Float(duration_s + extra_s),
    );
    for part in ["ego", "opponent"] {
        let Some(t) = doc.get_mut(part).and_then(toml::Value::as_table_mut) else {
            bail!("[{part}] missing");
        };
        if let Some(b) = t.get_mut("braking").and_then(toml::Value::as_table_mut) {
            let start_s = toml_f64(b, "start_s").context("braking.start_s")?;
            b.insert("start_s".into(), toml::Value::Float(start_s + extra_s));
        }
        if part == "opponent" {
            let d = toml_f64(t, "initial_distance_m").context("opponent.initial_distance_m")?;
            t.insert(
                "initial_distance_m".into(),
                toml::Value::Float(d + extra_s * closing_mps),
            );
        }
    }
    write_variant(src, dir, doc)
}

/// Where the first airbag Fire command is in a candump log (an `AirbagStageCmd` whose `Fire`
/// signal says Fire, as the bits lie).
pub fn first_airbag_fire(log: &bus::candump::CandumpLog) -> Option<usize> {
    log.frames.iter().position(|l| {
        let f = &l.frame;
        f.id == bus::AirbagStageCmd::RAW_ID
            && matches!(
                bus::decode(f.id, f.payload()),
                Ok(bus::Messages::AirbagStageCmd(m))
                    if matches!(m.fire(), bus::codec::AirbagStageCmdFire::Fire)
            )
    })
}

/// The first Fire command of a candump log and the authenticator after it, as cansend args.
pub fn recorded_fire_pair(candump_log: &Path) -> Result<(String, String)> {
    let log = bus::candump::CandumpLog::read(candump_log)
        .with_context(|| format!("reading {}", candump_log.display()))?;
    if let Some(k) = first_airbag_fire(&log) {
        let cmd = &log.frames[k].frame;
        if let Some(auth) = log.frames[k + 1..]
            .iter()
            .find(|l| l.frame.id == bus::AirbagStageAuth::RAW_ID)
        {
            return Ok((
                bus::candump::cansend_arg(cmd),
                bus::candump::cansend_arg(&auth.frame),
            ));
        }
    }
    bail!(
        "{}: no Fire command followed by its authenticator",
        candump_log.display()
    )
}

pub(super) fn forged_frames(bin_dir: &Path, pairs: u32) -> Result<Vec<String>> {
    let mut v = Vec::new();
    for i in 0..pairs {
        let o = Command::new(bin_dir.join("bus-inject"))
            .args(["forge-fire", "--counter"])
            .arg((i % 16).to_string())
            .arg("--freshness")
            .arg((i + 1).to_string())
            .arg("--mac")
            .arg((0x005A_5A5A_5A00_u64 + u64::from(i)).to_string())
            .output()
            .context("bus-inject forge-fire")?;
        if !o.status.success() {
            bail!("bus-inject forge-fire failed");
        }
        v.extend(
            String::from_utf8_lossy(&o.stdout)
                .split_whitespace()
                .map(str::to_owned),
        );
    }
    Ok(v)
}

/// Writes a variant `doc` of the scenario `src` to `dir` under its file name. A `[pulse]` file
/// named relative to the scenario's folder is named absolutely, so the variant elsewhere reads
/// the same pulse.
fn write_variant(src: &Path, dir: &Path, mut doc: toml::Table) -> Result<PathBuf> {
    let folder = src.parent().unwrap_or(Path::new(""));
    if let Some(file) = doc
        .get_mut("pulse")
        .and_then(|p| p.as_table_mut())
        .and_then(|p| p.get_mut("file"))
    {
        if let Some(rel) = file.as_str().filter(|f| Path::new(f).is_relative()) {
            *file = toml::Value::String(folder.join(rel).display().to_string());
        }
    }
    std::fs::create_dir_all(dir)?;
    let path = dir.join(src.file_name().context("scenario file name")?);
    std::fs::write(&path, toml::to_string(&doc)?)?;
    Ok(path)
}
