//! The scratch-directory guard of `tests/common/tempdir.rs`: removed when the test passes, kept
//! when it panics and when `TREAD_KEEP_TEST_OUTPUT` is set. One test function, because it sets
//! the environment variable and the harness runs tests of one binary on parallel threads.

#[path = "common/tempdir.rs"]
mod tempdir;

use tempdir::{TestDir, KEEP_VAR};

#[test]
fn test_dir_is_removed_on_success_and_kept_on_panic_or_request() {
    std::env::remove_var(KEEP_VAR);

    // Created empty (a stale directory from an earlier run is emptied), removed on drop.
    let d = TestDir::new("guard", "ok");
    let path = d.to_path_buf();
    assert!(path.starts_with(std::env::temp_dir()));
    assert!(path
        .file_name()
        .unwrap()
        .to_string_lossy()
        .starts_with(&format!("tread-guard-{}-", std::process::id())));
    std::fs::write(d.join("stale.txt"), "x").unwrap();
    drop(d);
    assert!(!path.exists(), "removed after a passing test");
    std::fs::create_dir_all(&path).unwrap();
    std::fs::write(path.join("stale.txt"), "x").unwrap();
    let d = TestDir::new("guard", "ok");
    assert_eq!(std::fs::read_dir(&*d).unwrap().count(), 0, "not emptied");
    drop(d);

    // A panic while the guard is alive (a failing test) keeps the directory.
    let kept = std::panic::catch_unwind(|| {
        let d = TestDir::new("guard", "panic");
        std::fs::write(d.join("out.csv"), "a,b\n").unwrap();
        let p = d.to_path_buf();
        if p.exists() {
            panic!("test failure (expected by this test)");
        }
        p
    });
    assert!(kept.is_err());
    let panicked = std::env::temp_dir().join(format!("tread-guard-{}-panic", std::process::id()));
    assert!(panicked.join("out.csv").exists(), "kept after a panic");
    std::fs::remove_dir_all(&panicked).unwrap();

    // TREAD_KEEP_TEST_OUTPUT keeps it too.
    std::env::set_var(KEEP_VAR, "1");
    let d = TestDir::new("guard", "keep");
    let path = d.to_path_buf();
    drop(d);
    std::env::remove_var(KEEP_VAR);
    assert!(path.exists(), "kept with {KEEP_VAR} set");
    std::fs::remove_dir_all(&path).unwrap();
}
