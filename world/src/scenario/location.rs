//! Where a scenario error is: the file, line, column and dotted field, from the spans of the
//! parsed document (`toml_edit` keeps them), not from searching the text.

use std::fmt;
use toml_edit::{ImDocument, Item, TableLike};

/// A scenario-file error: where and what.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioError {
    /// File name as given.
    pub file: String,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// 1-based column, when known.
    pub column: Option<usize>,
    /// Dotted field path (`ego.mass_kg`), when known.
    pub field: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
            if let Some(c) = self.column {
                write!(f, ":{c}")?;
            }
        }
        write!(f, ": ")?;
        if let Some(field) = &self.field {
            write!(f, "field `{field}`: ")?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for ScenarioError {}

/// 1-based (line, column) of byte offset `pos` in `text`.
pub(crate) fn line_col(text: &str, pos: usize) -> (usize, usize) {
    let before = text.get(..pos.min(text.len())).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Whether `offset` lies in `span`.
fn contains(span: Option<std::ops::Range<usize>>, offset: usize) -> bool {
    span.is_some_and(|s| s.contains(&offset))
}

/// The dotted path of the innermost key whose key or value contains byte `offset` (how a type
/// error's span becomes a field name); a table header names its table.
pub(crate) fn field_at(text: &str, offset: usize) -> Option<String> {
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

/// 1-based line of `field` (`table.key`, `table.array[i].key` or `key`), for semantic errors;
/// a key that is absent (a required value missing) points at its table's header.
pub(crate) fn line_of_field(text: &str, field: &str) -> Option<usize> {
    let doc = ImDocument::parse(text).ok()?;
    let mut table: &dyn TableLike = doc.as_table();
    let mut found: Option<std::ops::Range<usize>> = None;
    for part in field.split('.') {
        let (name, index) = match part.split_once('[') {
            Some((n, i)) => (n, i.trim_end_matches(']').parse::<usize>().ok()),
            None => (part, None),
        };
        let Some((key, item)) = table.get_key_value(name) else {
            break; // absent: the table found so far
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
            None => break,
        }
    }
    found.map(|s| line_col(text, s.start).0)
}
