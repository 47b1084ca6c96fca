//! One problem found in a scene before it is located in the file ([`Issue`]), and the small
//! helpers every section's checks share.

/// Where an issue's location comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Origin {
    /// `(--set)` if the key was overridden, else the line of the key in the original text.
    Auto,
    /// Always `(--set)`: a problem with the override itself.
    Override,
}

#[derive(Clone, Debug)]
pub(super) struct Issue {
    pub(super) key: String,
    pub(super) message: String,
    pub(super) origin: Origin,
    /// Another key whose location is reported when `key` itself is nowhere in the file (e.g.
    /// `analysis.mode` for a section that the mode requires).
    pub(super) anchor: Option<&'static str>,
}

pub(super) fn issue(key: impl Into<String>, message: impl Into<String>) -> Issue {
    Issue {
        key: key.into(),
        message: message.into(),
        origin: Origin::Auto,
        anchor: None,
    }
}

/// An issue about a key that may be absent from the file: located at `anchor` in that case.
pub(super) fn issue_near(
    key: impl Into<String>,
    message: impl Into<String>,
    anchor: &'static str,
) -> Issue {
    Issue {
        anchor: Some(anchor),
        ..issue(key, message)
    }
}

pub(super) fn positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

pub(super) fn quoted_list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

pub(super) fn table_has(doc: &toml::Table, section: &str, key: &str) -> bool {
    matches!(doc.get(section), Some(toml::Value::Table(t)) if t.contains_key(key))
}

/// The values of a law's section by key: those of the `known` keys in that order, then any
/// others (in key order), as the section's messages and serialisation list them.
pub(super) fn ordered_values<'a>(
    values: &'a std::collections::BTreeMap<String, f64>,
    known: &[&'static str],
) -> Vec<(&'a str, f64)> {
    let mut out: Vec<(&str, f64)> = known
        .iter()
        .filter_map(|k| values.get(*k).map(|v| (*k, *v)))
        .collect();
    out.extend(
        values
            .iter()
            .filter(|(k, _)| !known.contains(&k.as_str()))
            .map(|(k, v)| (k.as_str(), *v)),
    );
    out
}
