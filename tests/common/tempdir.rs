#![allow(dead_code)]
//! A scratch directory for a test, removed when the test passes.
//!
//! `TestDir::new("cli", "good")` creates `$TMPDIR/tread-cli-<pid>-good` (emptied first if a
//! previous run left it). On drop the directory is removed, unless the thread is panicking (a
//! failed test: its output is kept for inspection) or `TREAD_KEEP_TEST_OUTPUT` is set; a kept
//! directory's path is printed to stderr.
//!
//! Include it with `#[path = "common/tempdir.rs"] mod tempdir;` (test files) or through
//! `fixtures::tempdir` (files that include `common/fixtures.rs`).

use std::ops::Deref;
use std::path::{Path, PathBuf};

/// Environment variable that keeps every test directory.
pub const KEEP_VAR: &str = "TREAD_KEEP_TEST_OUTPUT";

pub struct TestDir {
    path: PathBuf,
}

impl TestDir {
    /// A new, empty `tread-<prefix>-<pid>-<name>` under the system temporary directory.
    pub fn new(prefix: &str, name: &str) -> Self {
        let path =
            std::env::temp_dir().join(format!("tread-{prefix}-{}-{name}", std::process::id()));
        Self::at(path)
    }

    /// A new, empty directory at `path` (emptied first if it exists).
    pub fn at(path: PathBuf) -> Self {
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path)
            .unwrap_or_else(|e| panic!("cannot create {}: {e}", path.display()));
        TestDir { path }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Deref for TestDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for TestDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("test failed: its output is kept in {}", self.path.display());
        } else if std::env::var_os(KEEP_VAR).is_some() {
            eprintln!(
                "{KEEP_VAR} is set: test output kept in {}",
                self.path.display()
            );
        } else {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}
