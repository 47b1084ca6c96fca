//! The loading context: `--set` overrides, the schema pass (unknown sections and keys, types,
//! required keys; every problem collected, offending entries dropped) and serde deserialisation of
//! each section. Errors are located from the spans of the original text.

use super::errors::{SceneError, SceneErrors, OVERRIDE_TAG};
use super::issue::{issue, Issue, Origin};
use super::material::{validate_material, MaterialModel, MaterialSpec, RegionMaterial};
use super::schema::{
    check_kind, describe_value, section_list, section_schema, Kind, SCHEMA, STEADY_UNUSED_TIME,
};
use super::spans::Locator;
use serde::de::DeserializeOwned;
use std::collections::BTreeSet;

pub(super) struct Ctx<'a> {
    pub(super) source_name: &'a str,
    pub(super) locator: &'a Locator,
    pub(super) overridden: BTreeSet<String>,
    pub(super) issues: Vec<Issue>,
    /// `[[material]]` regions and the index of the array element that names each.
    pub(super) region_elements: Vec<(String, usize)>,
}

impl Ctx<'_> {
    pub(super) fn push(&mut self, key: impl Into<String>, message: impl Into<String>) {
        self.issues.push(issue(key, message));
    }

    pub(super) fn push_override(&mut self, key: impl Into<String>, message: impl Into<String>) {
        self.issues.push(Issue {
            key: key.into(),
            message: message.into(),
            origin: Origin::Override,
            anchor: None,
        });
    }

    pub(super) fn apply_overrides(&mut self, doc: &mut toml::Table, overrides: &[String]) {
        for ov in overrides {
            let Some((raw_key, raw_value)) = ov.split_once('=') else {
                self.push_override(
                    ov.trim(),
                    format!("malformed override `{ov}`: expected `section.key=value`"),
                );
                continue;
            };
            let key = raw_key.trim();
            let parts: Vec<&str> = key.split('.').map(str::trim).collect();
            if !(2..=3).contains(&parts.len()) || parts.iter().any(|p| p.is_empty()) {
                self.push_override(
                    key,
                    format!(
                        "malformed override `{ov}`: the key must be `section.key` (or \
                         `section.table.key` for a sub-table such as `material.viscoelastic`)"
                    ),
                );
                continue;
            }
            if parts.len() == 3 {
                self.apply_sub_table_override(doc, ov, &parts, raw_value.trim());
                continue;
            }
            let (sec_name, field_name) = (parts[0], parts[1]);
            let key = format!("{sec_name}.{field_name}");
            let Some(sec) = section_schema(sec_name) else {
                self.push_override(
                    key,
                    format!(
                        "unknown section `[{sec_name}]` in override `{ov}`; sections are {}",
                        section_list()
                    ),
                );
                continue;
            };
            let Some(field) = sec.field(field_name) else {
                self.push_override(
                    key,
                    format!(
                        "unknown key in override `{ov}`; keys of [{sec_name}] are {}",
                        sec.key_list()
                    ),
                );
                continue;
            };
            let value = parse_override_value(raw_value.trim(), field.kind);
            let entry = doc
                .entry(sec_name.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            match entry {
                toml::Value::Table(t) => {
                    t.insert(field_name.to_string(), value);
                    self.overridden.insert(key);
                }
                other => {
                    let found = describe_value(other);
                    self.push_override(
                        key,
                        format!(
                            "cannot apply override `{ov}`: `{sec_name}` in the file is {found}, not a table"
                        ),
                    );
                }
            }
        }
    }

    /// `section.table.key=value`: a key of a sub-table of a section (e.g.
    /// `material.viscoelastic.gamma`), checked against the sub-table's schema.
    fn apply_sub_table_override(
        &mut self,
        doc: &mut toml::Table,
        ov: &str,
        parts: &[&str],
        raw_value: &str,
    ) {
        let (sec_name, sub_name, field_name) = (parts[0], parts[1], parts[2]);
        let key = parts.join(".");
        let Some(sec) = section_schema(sec_name) else {
            self.push_override(
                key,
                format!(
                    "unknown section `[{sec_name}]` in override `{ov}`; sections are {}",
                    section_list()
                ),
            );
            return;
        };
        let sub = match sec.field(sub_name).map(|f| f.kind) {
            Some(Kind::Table(sub)) => sub,
            Some(_) => {
                self.push_override(
                    key,
                    format!(
                        "malformed override `{ov}`: `{sec_name}.{sub_name}` is a value, not a \
                         table; write `{sec_name}.{sub_name}=value`"
                    ),
                );
                return;
            }
            None => {
                self.push_override(
                    key,
                    format!(
                        "unknown key in override `{ov}`; keys of [{sec_name}] are {}",
                        sec.key_list()
                    ),
                );
                return;
            }
        };
        let Some(field) = sub.iter().find(|f| f.key == field_name) else {
            self.push_override(
                key,
                format!(
                    "unknown key in override `{ov}`; keys of [{sec_name}.{sub_name}] are {}",
                    sub.iter().map(|f| f.key).collect::<Vec<_>>().join(", ")
                ),
            );
            return;
        };
        let value = parse_override_value(raw_value, field.kind);
        let entry = doc
            .entry(sec_name.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let toml::Value::Table(section) = entry else {
            let found = describe_value(entry);
            self.push_override(
                key,
                format!(
                    "cannot apply override `{ov}`: `{sec_name}` in the file is {found}, not a table"
                ),
            );
            return;
        };
        let table = section
            .entry(sub_name.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        match table {
            toml::Value::Table(t) => {
                t.insert(field_name.to_string(), value);
                self.overridden.insert(key);
            }
            other => {
                let found = describe_value(other);
                self.push_override(
                    key,
                    format!(
                        "cannot apply override `{ov}`: `{sec_name}.{sub_name}` in the file is \
                         {found}, not a table"
                    ),
                );
            }
        }
    }

    /// Check sections and keys against [`SCHEMA`]; return a copy of the document without the
    /// offending entries, so that the remaining sections can still be deserialized and validated.
    pub(super) fn check_schema(&mut self, doc: &toml::Table) -> toml::Table {
        let mut clean = toml::Table::new();
        let steady = doc
            .get("analysis")
            .and_then(|a| a.get("mode"))
            .and_then(|m| m.as_str())
            == Some("steady");
        // A sweep file is not a scene: one error that says what to run, not one per section.
        if doc.contains_key("sweep") && !doc.contains_key("scene") {
            self.push(
                "sweep",
                "this is a sweep file (a [sweep] table, no [scene]): run it with \
                 `tread sweep run FILE` (or list its runs with `tread sweep plan FILE`)",
            );
            return clean;
        }
        for (sec_name, sec_value) in doc {
            let Some(sec) = section_schema(sec_name) else {
                self.push(
                    sec_name.clone(),
                    format!("unknown section; sections are {}", section_list()),
                );
                continue;
            };
            let toml::Value::Table(table) = sec_value else {
                self.push(
                    sec_name.clone(),
                    format!(
                        "expected a table [{sec_name}], found {}",
                        describe_value(sec_value)
                    ),
                );
                continue;
            };
            let mut clean_table = toml::Table::new();
            for (key, value) in table {
                let dotted = format!("{sec_name}.{key}");
                match sec.field(key) {
                    None => self.push(
                        dotted,
                        format!("unknown key; keys of [{sec_name}] are {}", sec.key_list()),
                    ),
                    Some(field) => match (check_kind(field.kind, value), field.kind, value) {
                        (Ok(()), Kind::Table(sub), toml::Value::Table(t)) => {
                            // A sub-table: its keys are checked like a section's; it is kept
                            // only when all of them are valid.
                            let before = self.issues.len();
                            for (k, v) in t {
                                match sub.iter().find(|f| f.key == k) {
                                    None => self.push(
                                        format!("{dotted}.{k}"),
                                        format!(
                                            "unknown key; keys of [{dotted}] are {}",
                                            sub.iter()
                                                .map(|f| f.key)
                                                .collect::<Vec<_>>()
                                                .join(", ")
                                        ),
                                    ),
                                    Some(f) => {
                                        if let Err(msg) = check_kind(f.kind, v) {
                                            self.push(format!("{dotted}.{k}"), msg);
                                        }
                                    }
                                }
                            }
                            for f in sub.iter().filter(|f| f.required) {
                                if !t.contains_key(f.key) {
                                    self.push(
                                        format!("{dotted}.{}", f.key),
                                        "required key is missing",
                                    );
                                }
                            }
                            if self.issues.len() == before {
                                clean_table.insert(key.clone(), value.clone());
                            }
                        }
                        (Ok(()), _, _) => {
                            clean_table.insert(key.clone(), value.clone());
                        }
                        (Err(msg), _, _) => self.push(dotted, msg),
                    },
                }
            }
            for field in sec.fields.iter().filter(|f| f.required) {
                if table.contains_key(field.key) {
                    continue;
                }
                if steady && sec_name == "time" && STEADY_UNUSED_TIME.contains(&field.key) {
                    // The steady mode uses [time] for strain_rate_damping only: the transient
                    // keys it does not read stand in as NaN ([`TimeSpec::steady_only`]; not
                    // written back by `Scene::to_toml_string`, refused by the transient runs).
                    clean_table.insert(field.key.to_string(), toml::Value::Float(f64::NAN));
                    continue;
                }
                self.push(
                    format!("{sec_name}.{}", field.key),
                    "required key is missing",
                );
            }
            clean.insert(sec_name.clone(), toml::Value::Table(clean_table));
        }
        for sec in SCHEMA.iter().filter(|s| s.required) {
            if !doc.contains_key(sec.name) {
                let needs: Vec<&str> = sec
                    .fields
                    .iter()
                    .filter(|f| f.required)
                    .map(|f| f.key)
                    .collect();
                self.push(
                    sec.name,
                    format!(
                        "required section [{}] is missing (it needs {})",
                        sec.name,
                        needs.join(", ")
                    ),
                );
            }
        }
        clean
    }

    /// Take `[[material]]` out of the document: returns (region, table) per entry and puts the
    /// first entry back as `[material]`. Entries that are not tables or lack a string `region`
    /// are reported and dropped.
    pub(super) fn take_region_materials(
        &mut self,
        doc: &mut toml::Table,
    ) -> Vec<(String, toml::Table)> {
        let Some(toml::Value::Array(items)) = doc.get("material").cloned() else {
            return Vec::new();
        };
        doc.remove("material");
        let mut out: Vec<(String, toml::Table)> = Vec::new();
        for (i, item) in items.into_iter().enumerate() {
            let toml::Value::Table(mut t) = item else {
                self.push(
                    format!("material[{i}]"),
                    format!(
                        "expected a table ([[material]]), found {}",
                        describe_value(&item)
                    ),
                );
                continue;
            };
            let region = match t.remove("region") {
                Some(toml::Value::String(s)) if !s.is_empty() => s,
                Some(v) => {
                    self.push(
                        format!("material[{i}].region"),
                        format!("expected a non-empty string, found {}", describe_value(&v)),
                    );
                    continue;
                }
                None => {
                    self.push(
                        format!("material[{i}].region"),
                        "required key is missing: each [[material]] names its mesh region \
                         (a 2D physical group of mesh.file)",
                    );
                    continue;
                }
            };
            if out.iter().any(|(r, _)| *r == region) {
                self.push(
                    format!("material[{i}]"),
                    format!("region \"{region}\" given twice in [[material]]"),
                );
                continue;
            }
            self.region_elements.push((region.clone(), i));
            out.push((region, t));
        }
        // Nothing usable: the schema pass reports the section as missing.
        if let Some((_, t)) = out.first() {
            doc.insert("material".into(), toml::Value::Table(t.clone()));
        }
        out
    }

    /// Check and deserialize the `[[material]]` entries after the first (which is `[material]`);
    /// returns one placeholder per entry (the first is filled in by the caller).
    pub(super) fn region_materials(
        &mut self,
        tables: &[(String, toml::Table)],
        out: &mut Vec<Issue>,
    ) -> Vec<RegionMaterial> {
        let mut regions = Vec::new();
        let Some(schema) = section_schema("material") else {
            return regions;
        };
        for (k, (region, table)) in tables.iter().enumerate() {
            let prefix = format!("material[{region}]");
            if k == 0 {
                regions.push(RegionMaterial {
                    region: region.clone(),
                    material: MaterialSpec::new(MaterialModel::ALL[0], 0.0, &[]),
                });
                continue;
            }
            let mut clean = toml::Table::new();
            let mut complete = true;
            for (key, value) in table {
                match schema.field(key) {
                    None => self.push(
                        format!("{prefix}.{key}"),
                        format!(
                            "unknown key; keys of [[material]] are region, {}",
                            schema.key_list()
                        ),
                    ),
                    Some(field) => match check_kind(field.kind, value) {
                        Ok(()) => {
                            clean.insert(key.clone(), value.clone());
                        }
                        Err(msg) => {
                            complete = false;
                            self.push(format!("{prefix}.{key}"), msg);
                        }
                    },
                }
            }
            for field in schema.fields.iter().filter(|f| f.required) {
                if !table.contains_key(field.key) {
                    complete = false;
                    self.push(format!("{prefix}.{}", field.key), "required key is missing");
                }
            }
            if !complete {
                continue;
            }
            let Some(mut spec) =
                self.deserialize_section::<MaterialSpec>(&toml::Value::Table(clean), &prefix)
            else {
                continue;
            };
            let mut issues = Vec::new();
            validate_material(&spec, &mut issues);
            for mut i in issues {
                if let Some(rest) = i.key.strip_prefix("material.") {
                    i.key = format!("{prefix}.{rest}");
                }
                out.push(i);
            }
            spec.resolve();
            regions.push(RegionMaterial {
                region: region.clone(),
                material: spec,
            });
        }
        let incompressible: Vec<bool> = tables
            .iter()
            .map(|(_, t)| {
                matches!(t.get("model"), Some(toml::Value::String(m)) if m == "mooney_rivlin_incompressible")
            })
            .collect();
        if incompressible.iter().any(|&b| b) && !incompressible.iter().all(|&b| b) {
            out.push(issue(
                "material",
                "[[material]] regions mix incompressible and compressible models: the pressure \
                 field is common to the whole mesh, use one kind",
            ));
        }
        regions
    }

    /// Deserialize a required section; `None` if absent or incomplete (already reported).
    pub(super) fn required_section<T: DeserializeOwned>(
        &mut self,
        clean: &toml::Table,
        name: &str,
    ) -> Option<T> {
        let value = clean.get(name)?;
        let sec = section_schema(name)?;
        if let toml::Value::Table(t) = value {
            if sec
                .fields
                .iter()
                .any(|f| f.required && !t.contains_key(f.key))
            {
                return None; // missing or ill-typed required key: already reported
            }
        }
        self.deserialize_section(value, name)
    }

    /// Deserialize an optional section without defaults: `Some(None)` if absent, `Some(Some(_))`
    /// if present and valid, `None` if present but incomplete or ill-typed (already reported).
    pub(super) fn present_section<T: DeserializeOwned>(
        &mut self,
        clean: &toml::Table,
        name: &str,
    ) -> Option<Option<T>> {
        if clean.contains_key(name) {
            self.required_section(clean, name).map(Some)
        } else {
            Some(None)
        }
    }

    /// Deserialize an optional section (defaults when absent).
    pub(super) fn optional_section<T: DeserializeOwned + Default>(
        &mut self,
        clean: &toml::Table,
        name: &str,
    ) -> Option<T> {
        match clean.get(name) {
            None => {
                let present_but_bad = self
                    .issues
                    .iter()
                    .any(|i| i.key == name && i.origin == Origin::Auto);
                if present_but_bad {
                    None
                } else {
                    Some(T::default())
                }
            }
            Some(value) => self.deserialize_section(value, name),
        }
    }

    pub(super) fn deserialize_section<T: DeserializeOwned>(
        &mut self,
        value: &toml::Value,
        name: &str,
    ) -> Option<T> {
        match value.clone().try_into::<T>() {
            Ok(v) => Some(v),
            Err(e) => {
                // Backstop: the schema pass should have caught everything serde rejects.
                let key = key_from_de_error(&e, name);
                self.push(key, e.message().trim_end().to_string());
                None
            }
        }
    }

    /// Where a key comes from: `(None, true)` for an override; else its line in the file (or
    /// that of its nearest ancestor). A key found nowhere in the file whose section was touched
    /// by an override (e.g. a section created by `--set`) counts as an override.
    pub(super) fn origin_of(&self, key: &str) -> (Option<usize>, bool) {
        if self.overridden.contains(key) {
            return (None, true);
        }
        if let Some((index, rest)) = self.material_element(key) {
            return (self.locator.locate_element("material", index, rest), false);
        }
        match self.locator.locate(key) {
            Some(line) => (Some(line), false),
            None => {
                let section = key.split('.').next().unwrap_or(key);
                let touched = self
                    .overridden
                    .iter()
                    .any(|k| k.split('.').next() == Some(section));
                (None, touched)
            }
        }
    }

    /// A key of a `[[material]]` element, `material[<index or region>].<rest>`: the element's
    /// index and `<rest>` (empty for the element itself).
    fn material_element<'k>(&self, key: &'k str) -> Option<(usize, &'k str)> {
        let inner = key.strip_prefix("material[")?;
        let (name, rest) = inner.split_once(']')?;
        let rest = rest.strip_prefix('.').unwrap_or(rest);
        let index = match name.parse::<usize>() {
            Ok(i) => i,
            Err(_) => self
                .region_elements
                .iter()
                .find(|(r, _)| r == name)
                .map(|(_, i)| *i)?,
        };
        Some((index, rest))
    }

    pub(super) fn into_errors(self) -> SceneErrors {
        let mut errors: Vec<SceneError> = self
            .issues
            .iter()
            .map(|i| {
                let (line, is_override) = match i.origin {
                    Origin::Override => (None, true),
                    Origin::Auto => match (self.origin_of(&i.key), i.anchor) {
                        ((None, false), Some(anchor)) => self.origin_of(anchor),
                        (found, _) => found,
                    },
                };
                let source_name = if is_override {
                    format!("{}{OVERRIDE_TAG}", self.source_name)
                } else {
                    self.source_name.to_string()
                };
                SceneError {
                    key: i.key.clone(),
                    line,
                    message: i.message.clone(),
                    source_name,
                }
            })
            .collect();
        // File errors in line order, then those without a line (overrides last).
        errors.sort_by_key(|e| (e.line.is_none(), e.is_override(), e.line));
        SceneErrors(errors)
    }
}

/// Parse an override value as a TOML value; fall back to the bare text as a string. For
/// string-valued keys, unquoted text is always taken literally (so `scene.name=2024` works).
pub(super) fn parse_override_value(text: &str, kind: Kind) -> toml::Value {
    let parsed = format!("v = {text}")
        .parse::<toml::Table>()
        .ok()
        .filter(|t| t.len() == 1)
        .and_then(|mut t| t.remove("v"));
    match (parsed, kind) {
        // `--set output.sinks=csv,mcap` (no brackets or quotes) is a comma-separated list.
        (Some(v @ toml::Value::Array(_)), Kind::KeywordList(_)) => v,
        (_, Kind::KeywordList(_)) => toml::Value::Array(
            text.split(',')
                .map(|w| toml::Value::String(w.trim().trim_matches('"').to_string()))
                .collect(),
        ),
        // `--set output.snapshot_omegas=10,30,45` is a comma-separated list of numbers.
        (Some(v @ toml::Value::Array(_)), Kind::FloatList) => v,
        (Some(v @ (toml::Value::Integer(_) | toml::Value::Float(_))), Kind::FloatList) => {
            toml::Value::Array(vec![v])
        }
        (_, Kind::FloatList) => toml::Value::Array(
            text.split(',')
                .map(|w| {
                    let w = w.trim();
                    w.parse::<f64>()
                        .map(toml::Value::Float)
                        .unwrap_or_else(|_| toml::Value::String(w.to_string()))
                })
                .collect(),
        ),
        (Some(v @ toml::Value::String(_)), _) => v,
        (_, Kind::Str | Kind::Keyword(_)) => toml::Value::String(text.to_string()),
        (Some(v), _) => v,
        (None, _) => toml::Value::String(text.to_string()),
    }
}

pub(super) fn key_from_de_error(e: &toml::de::Error, section: &str) -> String {
    let msg = e.message();
    for prefix in ["unknown field `", "missing field `"] {
        if let Some(rest) = msg.strip_prefix(prefix) {
            if let Some(end) = rest.find('`') {
                return format!("{section}.{}", &rest[..end]);
            }
        }
    }
    // The Display of a value-deserialization error ends with "in `key`".
    let shown = e.to_string();
    if let Some(pos) = shown.rfind("in `") {
        let rest = &shown[pos + 4..];
        if let Some(end) = rest.find('`') {
            return format!("{section}.{}", &rest[..end]);
        }
    }
    section.to_string()
}
