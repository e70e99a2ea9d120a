//! Where a TOML error is: the line of a key, the key at a byte offset, the table a
//! "missing field" belongs to; and the [`ConfigError`] of a TOML parse error.

use std::path::Path;

use super::error::ConfigError;

pub(super) fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

type DeTable<'i> = toml::de::DeTable<'i>;
type DeValue<'i> = toml::de::DeValue<'i>;
type Spanned<T> = toml::Spanned<T>;

/// Span of the key (or, for array elements, of the element) at a dotted path such as
/// `gnss.outage_every.length_s` or `gnss.outages[2]`; the deepest existing prefix
/// when the full path is absent.
fn toml_span_of(root: &DeTable<'_>, key: &str) -> Option<std::ops::Range<usize>> {
    let mut table = Some(root);
    let mut value: Option<&Spanned<DeValue<'_>>> = None;
    let mut best = None;
    for seg in key.split('.') {
        let (name, idx) = match seg.split_once('[') {
            Some((n, rest)) => (n, rest.trim_end_matches(']').parse::<usize>().ok()),
            None => (seg, None),
        };
        if let (None, Some(v)) = (table, value) {
            // descend into an array of tables addressed without index: take the first
            table = v
                .get_ref()
                .as_array()
                .and_then(|a| a.first())
                .and_then(|e| e.get_ref().as_table());
        }
        let t = table?;
        let Some((k, v)) = t.iter().find(|(k, _)| k.get_ref() == name) else {
            return best;
        };
        best = Some(k.span());
        let mut v = v;
        if let Some(i) = idx {
            match v.get_ref().as_array().and_then(|a| a.get(i)) {
                Some(e) => {
                    v = e;
                    best = Some(e.span());
                }
                None => return best,
            }
        }
        value = Some(v);
        table = v.get_ref().as_table();
    }
    best
}

/// The 1-based line of the dotted `key` (e.g. `run[2].config`) in `text`, or of the
/// deepest part of it that exists.
pub fn toml_line_of(text: &str, key: &str) -> Option<usize> {
    let root = DeTable::parse(text).ok()?;
    toml_span_of(root.get_ref(), key).map(|s| line_of(text, s.start))
}

/// The dotted path of the entry at byte `offset`: the deepest key whose key or value
/// span contains it.
fn toml_key_at(table: &DeTable<'_>, offset: usize, prefix: &str) -> Option<String> {
    let mut fallback = None;
    for (k, v) in table.iter() {
        let path = if prefix.is_empty() {
            k.get_ref().to_string()
        } else {
            format!("{prefix}.{}", k.get_ref())
        };
        if k.span().contains(&offset) {
            return Some(path);
        }
        if let Some(found) = value_key_at(v, offset, &path) {
            return Some(found);
        }
        if v.span().contains(&offset) && fallback.is_none() {
            fallback = Some(path);
        }
    }
    fallback
}

fn value_key_at(v: &Spanned<DeValue<'_>>, offset: usize, path: &str) -> Option<String> {
    match v.get_ref() {
        DeValue::Table(t) => toml_key_at(t, offset, path),
        DeValue::Array(a) => {
            for (i, e) in a.iter().enumerate() {
                let p = format!("{path}[{i}]");
                if let Some(found) = value_key_at(e, offset, &p) {
                    return Some(found);
                }
                if e.span().contains(&offset) {
                    return Some(p);
                }
            }
            None
        }
        _ => None,
    }
}

/// The dotted path of the table whose value span is exactly `span` ("" for the root).
fn toml_table_at(
    table: &DeTable<'_>,
    span: &std::ops::Range<usize>,
    prefix: &str,
) -> Option<String> {
    for (k, v) in table.iter() {
        let path = if prefix.is_empty() {
            k.get_ref().to_string()
        } else {
            format!("{prefix}.{}", k.get_ref())
        };
        if let DeValue::Table(t) = v.get_ref() {
            if let Some(p) = toml_table_at(t, span, &path) {
                return Some(p);
            }
            if v.span() == *span {
                return Some(path);
            }
        }
        if let DeValue::Array(a) = v.get_ref() {
            for (i, e) in a.iter().enumerate() {
                if let DeValue::Table(t) = e.get_ref() {
                    let p = format!("{path}[{i}]");
                    if let Some(found) = toml_table_at(t, span, &p) {
                        return Some(found);
                    }
                    if e.span() == *span {
                        return Some(p);
                    }
                }
            }
        }
    }
    None
}

/// The name between the first pair of backticks of a serde message.
pub(super) fn backticked(msg: &str) -> Option<&str> {
    let rest = msg.split_once('`')?.1;
    Some(rest.split_once('`')?.0)
}

/// A TOML parse error of the file `path` (text `text`) as a [`ConfigError`] naming
/// the line and the dotted key (unknown keys, wrong types, missing keys).
pub fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> ConfigError {
    let message = e.message().trim().to_string();
    let Some(span) = e.span() else {
        return ConfigError::new(path, None, None, message);
    };
    let line = Some(line_of(text, span.start));
    let Ok(root) = DeTable::parse(text) else {
        // a syntax error: no key to name
        return ConfigError::new(path, line, None, message);
    };
    let root = root.get_ref();
    let key = if message.starts_with("missing field") {
        let field = backticked(&message).unwrap_or_default();
        match toml_table_at(root, &span, "") {
            Some(t) => Some(format!("{t}.{field}")),
            None => Some(field.to_string()),
        }
    } else {
        toml_key_at(root, span.start, "")
    };
    let top_level =
        message.starts_with("missing field") && key.as_deref().is_some_and(|k| !k.contains('.'));
    if top_level {
        // A whole section is missing: say so, and where it is described.
        let section = key.clone().unwrap_or_default();
        let message = format!(
            "missing the required section [{section}] (docs/CONFIG.md lists its keys; examples/ has a configuration per dataset)"
        );
        return ConfigError::new(path, None, key, message);
    }
    ConfigError::new(path, line, key, message)
}
