//! Scene errors: each names the dotted key, the line of the file (or `(--set)` for an override) and
//! what is wrong; [`SceneErrors`] holds them all.

use std::fmt;

/// One problem in a scene.
///
/// Displayed as `"{source_name}:{line}: key `{key}`: {message}"`, without `:{line}` when the line
/// is unknown, and without the `key` part when no key applies (e.g. some syntax errors). For a
/// value given by a `--set` override, `line` is `None` and `source_name` is
/// `"{file}:(--set)"`, so the error reads `file.toml:(--set): key `mesh.n_r`: ...`; see
/// [`SceneError::is_override`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}", render_error(.source_name, *.line, .key, .message))]
pub struct SceneError {
    /// Dotted key, e.g. `geometry.ri`; a section name for section-level problems; may be empty.
    pub key: String,
    /// 1-based line in the scene file.
    pub line: Option<usize>,
    pub message: String,
    pub source_name: String,
}

pub(super) const OVERRIDE_TAG: &str = ":(--set)";

pub(super) fn render_error(
    source_name: &str,
    line: Option<usize>,
    key: &str,
    message: &str,
) -> String {
    let mut s = String::from(source_name);
    if let Some(l) = line {
        s.push_str(&format!(":{l}"));
    }
    s.push_str(": ");
    if !key.is_empty() {
        s.push_str(&format!("key `{key}`: "));
    }
    s.push_str(message);
    s
}

impl SceneError {
    /// Whether the offending value came from a `--set` override.
    pub fn is_override(&self) -> bool {
        self.source_name.ends_with(OVERRIDE_TAG)
    }
}

/// Every problem found in a scene; displayed one per line.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneErrors(pub Vec<SceneError>);

impl fmt::Display for SceneErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for SceneErrors {}

impl From<SceneError> for SceneErrors {
    fn from(e: SceneError) -> Self {
        SceneErrors(vec![e])
    }
}

impl SceneErrors {
    /// Whether some error names exactly this dotted key.
    pub fn has_key(&self, key: &str) -> bool {
        self.0.iter().any(|e| e.key == key)
    }

    /// The first error naming exactly this dotted key.
    pub fn find(&self, key: &str) -> Option<&SceneError> {
        self.0.iter().find(|e| e.key == key)
    }
}
