//! Where each key of a scene file is written: 1-based lines from the byte spans that the `toml`
//! crate's parser gives for every key ([`toml::de::DeTable`]).
//!
//! Every key path is recorded at the line of its key: a `[table]` or `[[array]]` header records
//! the table's path, `a.b = 1` records both `a` and `a.b`, keys inside inline tables and inside the
//! tables of an array (`[[material]]`) record their full path (array elements add no segment).
//! A key that is not in the text is located at its nearest ancestor that is (a missing key at its
//! section header). When the text has a syntax error, the parser's best-effort recovery still
//! gives the keys it could read, so a syntax error can name the key on its line.

use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// Key paths and the lines where they are written, in the order of the text.
#[derive(Debug, Default)]
pub(super) struct Locator {
    entries: Vec<(Vec<String>, usize)>,
}

impl Locator {
    /// Parse `text` (recovering from syntax errors) and record every key's line.
    pub(super) fn new(text: &str) -> Locator {
        let lines = LineIndex::new(text);
        let (root, _errors) = DeTable::parse_recoverable(text);
        let mut entries = Vec::new();
        walk_table(root.get_ref(), &mut Vec::new(), &lines, &mut entries);
        // The parser keeps keys sorted; the text's order makes the first of several equal paths
        // (the entries of an array of tables) the one written first.
        entries.sort_by_key(|(_, line)| *line);
        Locator { entries }
    }

    /// Line of a dotted key; for a key not in the text, the line where its nearest ancestor
    /// (e.g. the section header) is defined; `None` if none is.
    pub(super) fn locate(&self, dotted: &str) -> Option<usize> {
        if dotted.is_empty() {
            return None;
        }
        let target: Vec<&str> = dotted.split('.').collect();
        let mut best: Option<(usize, usize)> = None; // (matched length, line)
        for (path, line) in &self.entries {
            if path.len() > target.len() || path.iter().zip(&target).any(|(a, b)| a != b) {
                continue;
            }
            if best.is_none_or(|(len, _)| path.len() > len) {
                best = Some((path.len(), *line));
            }
        }
        best.map(|(_, line)| line)
    }

    /// Line of `key` (dotted, may be empty for the element itself) in the `index`-th (0-based)
    /// element of the array of tables `array` (`[[material]]`); the element's header line when
    /// the key is not written in it.
    pub(super) fn locate_element(&self, array: &str, index: usize, key: &str) -> Option<usize> {
        let mut headers: Vec<usize> = self
            .entries
            .iter()
            .filter(|(p, _)| p.len() == 1 && p[0] == array)
            .map(|(_, l)| *l)
            .collect();
        headers.dedup();
        let start = *headers.get(index)?;
        let end = headers.get(index + 1).copied().unwrap_or(usize::MAX);
        if key.is_empty() {
            return Some(start);
        }
        let mut target = vec![array.to_string()];
        target.extend(key.split('.').map(str::to_string));
        self.entries
            .iter()
            .find(|(p, l)| *l >= start && *l < end && *p == target)
            .map(|(_, l)| *l)
            .or(Some(start))
    }

    /// The longest key path defined on a line, dotted.
    pub(super) fn key_at_line(&self, line: usize) -> Option<String> {
        self.entries
            .iter()
            .filter(|(_, l)| *l == line)
            .max_by_key(|(p, _)| p.len())
            .map(|(p, _)| p.join("."))
    }
}

fn walk_table(
    table: &DeTable<'_>,
    path: &mut Vec<String>,
    lines: &LineIndex,
    out: &mut Vec<(Vec<String>, usize)>,
) {
    for (key, value) in table {
        path.push(key.get_ref().to_string());
        out.push((path.clone(), lines.line_of(key.span().start)));
        walk_value(value, path, lines, out);
        path.pop();
    }
}

fn walk_value(
    value: &Spanned<DeValue<'_>>,
    path: &mut Vec<String>,
    lines: &LineIndex,
    out: &mut Vec<(Vec<String>, usize)>,
) {
    match value.get_ref() {
        DeValue::Table(t) => walk_table(t, path, lines, out),
        DeValue::Array(items) => {
            for item in items.iter() {
                if let DeValue::Table(t) = item.get_ref() {
                    // An `[[array]]` element: its header line names the path again.
                    out.push((path.clone(), lines.line_of(item.span().start)));
                    walk_table(t, path, lines, out);
                }
            }
        }
        _ => {}
    }
}

/// The dotted key written on 1-based `line` of `text`, read from the text alone (for lines the
/// parser could not record, e.g. a key defined twice): the key before `=`, under the nearest
/// `[section]` or `[[array]]` header above it; a header line gives its own path.
pub(super) fn key_written_at(text: &str, line: usize) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    let here = lines.get(line.checked_sub(1)?)?.trim();
    let header = |l: &str| -> Option<String> {
        let l = l.trim();
        let inner = l.strip_prefix("[[").and_then(|r| r.split("]]").next());
        let inner = inner.or_else(|| l.strip_prefix('[').and_then(|r| r.split(']').next()))?;
        Some(inner.trim().replace(['"', '\'', ' '], ""))
    };
    if here.starts_with('[') {
        return header(here);
    }
    let (key, _) = here.split_once('=')?;
    let key = key.trim().replace(['"', '\'', ' '], "");
    if key.is_empty() {
        return None;
    }
    let section = lines[..line - 1]
        .iter()
        .rev()
        .find(|l| l.trim_start().starts_with('['))
        .and_then(|l| header(l));
    Some(match section {
        Some(s) if !s.is_empty() => format!("{s}.{key}"),
        _ => key,
    })
}

/// Byte offset to 1-based line.
pub(super) struct LineIndex {
    starts: Vec<usize>,
}

impl LineIndex {
    pub(super) fn new(text: &str) -> LineIndex {
        let mut starts = vec![0];
        starts.extend(
            text.bytes()
                .enumerate()
                .filter(|(_, b)| *b == b'\n')
                .map(|(i, _)| i + 1),
        );
        LineIndex { starts }
    }

    pub(super) fn line_of(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::scene::tests::*;

    #[test]
    fn arrays_of_tables_inline_tables_and_syntax_errors() {
        let text = "[scene]\nname = \"a\"\n\n[[material]]\nregion = \"core\"\nrho = 1\n\n[[material]]\nregion = \"tread\"\nmu = 2\n[material.viscoelastic]\ngamma = 3\n[x]\ny = { z = 1,\n  w = 2 }\n";
        let loc = Locator::new(text);
        assert_eq!(loc.locate("material"), Some(4));
        assert_eq!(loc.locate("material.rho"), Some(6));
        assert_eq!(loc.locate("material.mu"), Some(10));
        assert_eq!(loc.locate("material.viscoelastic.gamma"), Some(12));
        assert_eq!(loc.locate("x.y.w"), Some(15));
        assert_eq!(loc.key_at_line(9).as_deref(), Some("material.region"));

        // After a syntax error the keys read so far still have their lines.
        let loc = Locator::new("[geometry]\nri = 1\nro = \n[mesh]\nn_r = 2\n");
        assert_eq!(loc.locate("geometry.ri"), Some(2));
        assert_eq!(loc.key_at_line(2).as_deref(), Some("geometry.ri"));
        assert_eq!(LineIndex::new("a\nb\n").line_of(2), 2);
        assert_eq!(LineIndex::new("a\nb\n").line_of(0), 1);
    }

    #[test]
    fn locator_handles_comments_quotes_dotted_and_multiline() {
        let text = r#"# header comment [geometry]
title = """
[geometry]
ri = 99
"""
arr = [
  [1, 2],
  { ri = 3 },
]
[ "geometry" ]   # spaced, quoted header
"ri" = 1.0 # comment with ro = 5
ro = "a # not a comment" # real comment
mesh.n_r = 4
[material]
'rho'=1
"#;
        let loc = Locator::new(text);
        assert_eq!(loc.locate("geometry"), Some(10));
        assert_eq!(loc.locate("geometry.ri"), Some(11));
        assert_eq!(loc.locate("geometry.ro"), Some(12));
        assert_eq!(loc.locate("geometry.mesh.n_r"), Some(13));
        assert_eq!(loc.locate("material.rho"), Some(15));
        assert_eq!(loc.locate("material.mu"), Some(14)); // missing: section header
        assert_eq!(loc.locate("solver.tolerance"), None);
        assert_eq!(loc.locate("arr"), Some(6));
        assert_eq!(loc.key_at_line(12).as_deref(), Some("geometry.ro"));

        // Top-level dotted keys define their section implicitly.
        let loc = Locator::new("geometry.ri = 1\ngeometry.ro = 2\n");
        assert_eq!(loc.locate("geometry.ro"), Some(2));
        assert_eq!(loc.locate("geometry.x"), Some(1));
    }

    #[test]
    fn dotted_keys_in_file_get_lines() {
        let text = MINIMAL.replace("[motion]\nomega = 20.0\n", "motion.omega = -3.0\n");
        // Dotted top-level key after [analysis] means analysis.motion.omega: unknown key.
        let e = errors(&text);
        let err = e.find("analysis.motion").unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "motion.omega")));
    }
}
