//! The JSON results the tools write (`report.json`, `campaign.json`, the ECU's
//! `--json`, …): each document carries `schema_version` as its first key, the version
//! of its own fields, so a script that reads it can refuse a layout it does not know. Each
//! document's version is a constant next to its type; docs/using.md, "JSON results", lists
//! them, and the tests check the two agree.

use serde::Serialize;

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
