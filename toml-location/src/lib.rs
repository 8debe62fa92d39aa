//! Where something is in a TOML file, for error messages that name `file:line:column` and the
//! dotted field: from the spans the parsed document keeps (`toml_edit`), not from searching
//! the text. The ECU's configuration and the world's scenario files both report this way; a
//! crate of its own because neither may depend on the other (the world has no process side,
//! the ECU no simulated world).

use std::ops::Range;
use toml_edit::{ImDocument, Item, TableLike};

/// 1-based (line, column) of byte `offset` in `text` (column counted in characters).
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = text.get(..offset.min(text.len())).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// Whether `offset` lies in `span`.
fn contains(span: Option<Range<usize>>, offset: usize) -> bool {
    span.is_some_and(|s| s.contains(&offset))
}

/// The dotted path of the innermost key whose key or value contains byte `offset` (how a
/// parse error's span, which points at the value, becomes a field name); a table header names
/// its table, an array of tables its element (`accel_event[1].axis`).
pub fn field_at(text: &str, offset: usize) -> Option<String> {
    let doc = ImDocument::parse(text).ok()?;
    let mut path = Vec::new();
    find(doc.as_table(), offset, &mut path);
    (!path.is_empty()).then(|| path.join("."))
}

fn find(table: &dyn TableLike, offset: usize, path: &mut Vec<String>) {
    for (name, _) in table.iter() {
        let Some((key, item)) = table.get_key_value(name) else {
            continue;
        };
        if let Some(tables) = item.as_array_of_tables() {
            for (i, t) in tables.iter().enumerate() {
                if contains(t.span(), offset) || entries_contain(t, offset) {
                    path.push(format!("{name}[{i}]"));
                    find(t, offset, path);
                    return;
                }
            }
            continue;
        }
        let inside = contains(key.span(), offset) || contains(item.span(), offset);
        match item.as_table_like() {
            Some(sub) if inside || entries_contain(sub, offset) => {
                path.push(name.to_owned());
                find(sub, offset, path);
                return;
            }
            _ if inside => {
                path.push(name.to_owned());
                return;
            }
            _ => {}
        }
    }
}

/// A table's own span is its header only: whether one of its entries holds `offset`.
fn entries_contain(table: &dyn TableLike, offset: usize) -> bool {
    table.iter().any(|(name, item)| {
        table
            .get_key_value(name)
            .is_some_and(|(k, _)| contains(k.span(), offset))
            || contains(item.span(), offset)
            || item
                .as_table_like()
                .is_some_and(|t| entries_contain(t, offset))
    })
}

/// Walks `field` (`table.key`, `table.array[i].key`, `key`): the span of the deepest part the
/// file has, and whether that is the whole field.
fn walk(text: &str, field: &str) -> Option<(Range<usize>, bool)> {
    let doc = ImDocument::parse(text).ok()?;
    let mut table: &dyn TableLike = doc.as_table();
    let mut found: Option<Range<usize>> = None;
    let parts: Vec<&str> = field.split('.').collect();
    for (n, part) in parts.iter().enumerate() {
        let (name, index) = match part.split_once('[') {
            Some((n, i)) => (n, i.trim_end_matches(']').parse::<usize>().ok()),
            None => (*part, None),
        };
        let Some((key, item)) = table.get_key_value(name) else {
            return found.map(|s| (s, false));
        };
        found = key.span().or_else(|| item.span());
        let next: Option<&dyn TableLike> = match (index, item) {
            (Some(i), Item::ArrayOfTables(a)) => a.get(i).map(|t| {
                found = t.span().or(found.clone());
                t as &dyn TableLike
            }),
            _ => item.as_table_like(),
        };
        match next {
            Some(t) => table = t,
            None => return found.map(|s| (s, n + 1 == parts.len())),
        }
    }
    found.map(|s| (s, true))
}

/// 1-based line where the file sets `field`, or `None` when it does not (the value came from
/// somewhere else: a default, the environment, a flag).
pub fn line_of_key(text: &str, field: &str) -> Option<usize> {
    walk(text, field).and_then(|(s, whole)| whole.then(|| line_col(text, s.start).0))
}

/// 1-based line of `field` for an error about it: its own line, or, where the file does not
/// set it (a required value missing), the header of the nearest table that is there.
pub fn line_of_field(text: &str, field: &str) -> Option<usize> {
    walk(text, field).map(|(s, _)| line_col(text, s.start).0)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "period_us = 1000\n\n[rt]\nmlockall = \"yes\"\n\n[[accel_event]]\nat_s = 1.0\n\n[[accel_event]]\nat_s = 2.0\naxis = 7\n";

    #[test]
    fn offsets_become_lines_columns_and_fields() {
        let at = |needle: &str| TEXT.find(needle).unwrap();
        assert_eq!(line_col(TEXT, 0), (1, 1));
        assert_eq!(line_col(TEXT, at("\"yes\"")), (4, 12));
        assert_eq!(
            field_at(TEXT, at("\"yes\"")).as_deref(),
            Some("rt.mlockall")
        );
        assert_eq!(field_at(TEXT, at("1000")).as_deref(), Some("period_us"));
        assert_eq!(
            field_at(TEXT, at("7")).as_deref(),
            Some("accel_event[1].axis")
        );
        assert_eq!(
            line_col(TEXT, usize::MAX).0,
            12,
            "past the end: the last line"
        );
    }

    #[test]
    fn a_field_the_file_sets_has_its_line_and_an_absent_one_only_its_table() {
        assert_eq!(line_of_key(TEXT, "rt.mlockall"), Some(4));
        assert_eq!(line_of_key(TEXT, "accel_event[1].axis"), Some(11));
        assert_eq!(line_of_key(TEXT, "rt.sched_fifo_priority"), None);
        assert_eq!(line_of_field(TEXT, "rt.sched_fifo_priority"), Some(3));
        assert_eq!(line_of_key(TEXT, "can.interface"), None);
        assert_eq!(line_of_field(TEXT, "can.interface"), None);
        assert_eq!(line_of_field(TEXT, "period_us"), Some(1));
    }
}
