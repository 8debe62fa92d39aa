//! Reading back what [`crate::write`] put in a `run.mcap`, for a replay judged against the run
//! it replays: the actuator stubs' report as their `report.json` was — `/stubs/verdict` with
//! the `/stubs/actions` put back in its `actions`.

use anyhow::{bail, Context, Result};
use serde_json::Value;

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
