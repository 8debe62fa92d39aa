//! The JSON results the tools write (`report.json`, `campaign.json`, the ECU's
//! `--json`, …): each document carries `schema_version` as its first key, the version
//! of its own fields, so a script that reads it can refuse a layout it does not know. Each
//! document's version is a constant next to its type; docs/using.md, "JSON results", lists
//! them, and the tests check the two agree.

use serde::Serialize;
use std::path::Path;

/// Whether an output path means stdout (`--json -`).
pub fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// Writes a finished JSON document to `to`: stdout for `-`, else the file (a trailing
/// newline added).
///
/// # Errors
/// The file cannot be written; the error names it.
pub fn write_json(to: &Path, text: &str) -> std::io::Result<()> {
    use std::io::Write;
    if is_stdout(to) {
        let mut out = std::io::stdout().lock();
        return writeln!(out, "{text}").and_then(|()| out.flush());
    }
    std::fs::write(to, format!("{text}\n"))
        .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", to.display())))
}

/// `doc` carrying `schema_version`: an object gets the key; a list (of runs, of rows) stays a
/// list and each object in it gets the key, so every record a script reads names its layout.
pub fn versioned_value(schema_version: u32, doc: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    let stamp = |v: Value| match v {
        Value::Object(mut m) => {
            m.insert("schema_version".into(), schema_version.into());
            Value::Object(m)
        }
        other => other,
    };
    match doc {
        Value::Array(items) => Value::Array(items.into_iter().map(stamp).collect()),
        other => stamp(other),
    }
}

/// A document with its `schema_version` before its own fields.
#[derive(Serialize)]
struct Versioned<'a, T: Serialize> {
    schema_version: u32,
    #[serde(flatten)]
    doc: &'a T,
}

/// `doc` as pretty-printed JSON with `schema_version` first (`doc` must serialize as an
/// object).
pub fn to_json_pretty<T: Serialize>(schema_version: u32, doc: &T) -> serde_json::Result<String> {
    serde_json::to_string_pretty(&Versioned {
        schema_version,
        doc,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Doc {
        a: u32,
        b: &'static str,
    }

    #[test]
    fn a_list_keeps_its_shape_and_each_record_names_its_layout() {
        let v = versioned_value(2, serde_json::json!([{"a": 1}, {"b": 2}]));
        assert_eq!(
            v,
            serde_json::json!([{"a": 1, "schema_version": 2}, {"b": 2, "schema_version": 2}])
        );
        let o = versioned_value(4, serde_json::json!({"rows": [1, 2]}));
        assert_eq!(o, serde_json::json!({"rows": [1, 2], "schema_version": 4}));
    }

    #[test]
    fn the_version_comes_first_and_the_fields_follow_unchanged() {
        let text = to_json_pretty(3, &Doc { a: 1, b: "x" }).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(
            v,
            serde_json::json!({"schema_version": 3, "a": 1, "b": "x"})
        );
        assert!(
            text.trim_start().starts_with("{\n  \"schema_version\": 3,"),
            "{text}"
        );
    }
}
