//! Reading a measured compartment accelerometer channel: a CSV trace or an ISO-MME channel
//! file (ISO/TS 13499, the exchange format of crash-test laboratories and NHTSA's database).
//!
//! Both give one channel at a uniform step with the time of its first sample; time 0 is the
//! first contact (a laboratory's T0), so samples before it are the pre-trigger. Sign
//! convention: SAE J211 vehicle axis (x forward), so a frontal crash's deceleration reads
//! negative — what every crash-test channel of the x direction carries.
//!
//! * **CSV**: a header naming the two columns with their units, `time_s` or `time_ms`, then
//!   `accel_g` or `accel_mps2`; one sample per line; `#` comments and blank lines ignored.
//! * **ISO-MME channel file**: `Name of the key  :value` header lines — of them this reads
//!   `Unit` (`g`, `m/s**2`, `m/s^2`, `m/s2`), `Sampling interval` (s), `Time of first sample`
//!   (s) and, when present, `Number of samples` (checked) — then one value per line.
//!
//! The step must be uniform within 1 %; every value finite; at least [`MIN_SAMPLES`].

use std::{format, string::String, vec::Vec};

/// Fewest samples a trace may have.
pub const MIN_SAMPLES: usize = 16;

/// One accelerometer channel at a uniform step.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    /// Time of the first sample [s] (0 = first contact; negative = pre-trigger).
    pub start_s: f64,
    /// Sampling step [s].
    pub step_s: f64,
    /// Compartment acceleration along the vehicle's x axis [m/s²] (a crash reads negative).
    pub accel_mps2: Vec<f64>,
}

impl Trace {
    /// The trace from the first contact on, linearly interpolated onto a grid of `step_s`
    /// (sample k at k·step after contact): up to the trace's last sample and at most `max`
    /// samples. A trace that begins after the contact has nothing to say about it: empty.
    pub fn from_contact(&self, step_s: f64, max: usize) -> Vec<f64> {
        let n = self.accel_mps2.len();
        if !(step_s > 0.0) || !(self.step_s > 0.0) || n < 2 || self.start_s > 0.0 {
            return Vec::new();
        }
        let end_s = self.start_s + (n - 1) as f64 * self.step_s;
        let mut out = Vec::new();
        for k in 0..max {
            let t = k as f64 * step_s;
            if t > end_s + 1e-12 {
                break;
            }
            let x = (t - self.start_s) / self.step_s;
            let i = (x.floor() as usize).min(n - 2);
            let f = (x - i as f64).clamp(0.0, 1.0);
            let (a, b) = (self.accel_mps2[i], self.accel_mps2[i + 1]);
            out.push(a + (b - a) * f);
        }
        out
    }
}

/// Reads either format: an ISO-MME channel file when its first line is a `key :value` header
/// line, else a CSV trace.
pub fn parse(text: &str) -> Result<Trace, String> {
    let first = text.lines().map(str::trim).find(|l| !l.is_empty());
    if first.is_some_and(|l| l.contains(':')) {
        parse_iso_mme(text)
    } else {
        parse_csv(text)
    }
}

/// A CSV trace (module docs).
pub fn parse_csv(text: &str) -> Result<Trace, String> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (_, header) = lines.next().ok_or("empty trace file")?;
    let cols: Vec<String> = header
        .split(',')
        .map(|c| c.trim().to_ascii_lowercase())
        .collect();
    let [time, accel] = cols.as_slice() else {
        return Err(format!("header must name two columns, got `{header}`"));
    };
    let time_scale = match time.as_str() {
        "time_s" | "t_s" => 1.0,
        "time_ms" | "t_ms" => 1.0e-3,
        other => {
            return Err(format!(
                "first column must be time_s or time_ms, got `{other}`"
            ))
        }
    };
    let accel_scale = match accel.as_str() {
        "accel_g" | "a_g" => crate::defaults::STANDARD_GRAVITY_MPS2,
        "accel_mps2" | "a_mps2" => 1.0,
        other => {
            return Err(format!(
                "second column must be accel_g or accel_mps2, got `{other}`"
            ))
        }
    };
    let mut times = Vec::new();
    let mut accel = Vec::new();
    for (line_no, line) in lines {
        let mut it = line.split(',');
        let mut next = || number(it.next(), line_no);
        times.push(next()? * time_scale);
        accel.push(next()? * accel_scale);
        if it.next().is_some() {
            return Err(format!("line {line_no}: more than two columns"));
        }
    }
    let (start_s, step_s) = uniform_step(&times)?;
    Ok(Trace {
        start_s,
        step_s,
        accel_mps2: accel,
    })
}

/// An ISO-MME channel file (module docs).
pub fn parse_iso_mme(text: &str) -> Result<Trace, String> {
    let (mut unit, mut step_s, mut start_s, mut count) = (None, None, None, None);
    let mut values = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let (line_no, line) = (i + 1, raw.trim());
        if line.is_empty() {
            continue;
        }
        match line.split_once(':') {
            Some(_) if !values.is_empty() => {
                return Err(format!("line {line_no}: a header line among the values"))
            }
            Some((key, value)) => {
                let value = value.trim();
                match key.trim().to_ascii_lowercase().as_str() {
                    "unit" => unit = Some(value.to_ascii_lowercase()),
                    "sampling interval" => step_s = Some(number(Some(value), line_no)?),
                    "time of first sample" => start_s = Some(number(Some(value), line_no)?),
                    "number of samples" => {
                        count = Some(value.parse::<usize>().map_err(|_| {
                            format!("line {line_no}: not a sample count: `{value}`")
                        })?)
                    }
                    _ => {}
                }
            }
            None => values.push(number(Some(line), line_no)?),
        }
    }
    let scale = match unit.as_deref() {
        Some("g") => crate::defaults::STANDARD_GRAVITY_MPS2,
        Some("m/s**2" | "m/s^2" | "m/s2" | "m/s²") => 1.0,
        Some(other) => return Err(format!("unit must be g or m/s**2, got `{other}`")),
        None => return Err("no `Unit` line".into()),
    };
    let step_s = step_s.ok_or("no `Sampling interval` line")?;
    if !(step_s > 0.0) {
        return Err(format!("sampling interval must be > 0, got {step_s}"));
    }
    let start_s = start_s.ok_or("no `Time of first sample` line")?;
    if let Some(n) = count.filter(|n| *n != values.len()) {
        return Err(format!(
            "`Number of samples` says {n}, the file has {}",
            values.len()
        ));
    }
    if values.len() < MIN_SAMPLES {
        return Err(format!(
            "trace has {} samples, need at least {MIN_SAMPLES}",
            values.len()
        ));
    }
    values.iter_mut().for_each(|v| *v *= scale);
    Ok(Trace {
        start_s,
        step_s,
        accel_mps2: values,
    })
}

/// A finite number from an optional field of line `line_no`.
fn number(field: Option<&str>, line_no: usize) -> Result<f64, String> {
    let s = field
        .ok_or(format!("line {line_no}: missing column"))?
        .trim();
    let v: f64 = s
        .parse()
        .map_err(|_| format!("line {line_no}: not a number: `{s}`"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("line {line_no}: non-finite value"))
    }
}

/// The first time and the step of a time column that must be uniform within 1 %.
fn uniform_step(times: &[f64]) -> Result<(f64, f64), String> {
    let (Some(&first), Some(&last)) = (times.first(), times.last()) else {
        return Err("no samples".into());
    };
    if times.len() < MIN_SAMPLES {
        return Err(format!(
            "trace has {} samples, need at least {MIN_SAMPLES}",
            times.len()
        ));
    }
    let step_s = (last - first) / (times.len() - 1) as f64;
    if !(step_s > 0.0) {
        return Err("time column must increase".into());
    }
    for (i, w) in times.windows(2).enumerate() {
        if ((w[1] - w[0]) - step_s).abs() > 0.01 * step_s {
            return Err(format!("non-uniform time step at sample {}", i + 2));
        }
    }
    Ok((first, step_s))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn iso(unit: &str, count: usize, values: &[f64]) -> String {
        let mut s = String::from(
            "Data format edition number  :1.6\nChannel code                :10VEHC0000ACXP\n",
        );
        s += &format!("Unit                        :{unit}\n");
        s += "Sampling interval           :0.0001\nTime of first sample        :-0.0010\n";
        s += &format!("Number of samples           :{count}\n");
        for v in values {
            s += &format!("{v}\n");
        }
        s
    }

    #[test]
    fn an_iso_mme_file_gives_its_start_step_and_values_in_si() {
        let v: Vec<f64> = (0..20).map(|k| -(k as f64)).collect();
        let t = parse(&iso("g", 20, &v)).unwrap();
        assert_eq!((t.start_s, t.step_s), (-0.001, 0.0001));
        assert!((t.accel_mps2[3] + 3.0 * 9.806_65).abs() < 1e-9);
        let t = parse(&iso("m/s**2", 20, &v)).unwrap();
        assert_eq!(t.accel_mps2[3], -3.0);
        assert!(parse(&iso("km", 20, &v)).unwrap_err().contains("unit"));
        assert!(parse(&iso("g", 21, &v)).unwrap_err().contains("21"));
        assert!(parse(&iso("g", 5, &v[..5])).unwrap_err().contains("16"));
        let bad = iso("g", 20, &v).replace("\n-4\n", "\nx\n");
        assert!(parse(&bad).unwrap_err().contains("line 11"));
    }

    #[test]
    fn a_csv_trace_keeps_its_first_time() {
        let mut csv = String::from("# pre-trigger of 2 ms\ntime_ms,accel_g\n");
        for k in 0..20 {
            csv += &format!("{},{}\n", -2.0 + 0.5 * k as f64, -1.0);
        }
        let t = parse(&csv).unwrap();
        assert!((t.start_s + 0.002).abs() < 1e-12 && (t.step_s - 0.0005).abs() < 1e-12);
        assert!(parse("time_s,accel_g,x\n0,1,2\n")
            .unwrap_err()
            .contains("two columns"));
    }

    /// Linear interpolation from the contact on: a ramp a = t (m/s² per s) sampled at 0.5 ms
    /// from −1 ms reads t on any finer grid, and stops at the trace's last sample.
    #[test]
    fn from_contact_interpolates_the_ramp_and_stops_at_its_end() {
        let t = Trace {
            start_s: -0.001,
            step_s: 0.0005,
            accel_mps2: (0..20).map(|k| -0.001 + 0.0005 * k as f64).collect(),
        };
        let g = t.from_contact(0.0001, 1000);
        assert_eq!(g.len(), 86); // 0 … 8.5 ms
        for (k, a) in g.iter().enumerate() {
            assert!((a - k as f64 * 0.0001).abs() < 1e-12, "{k}: {a}");
        }
        assert_eq!(t.from_contact(0.0001, 10).len(), 10);
        let late = Trace {
            start_s: 0.001,
            ..t.clone()
        };
        assert!(late.from_contact(0.0001, 10).is_empty());
    }
}
