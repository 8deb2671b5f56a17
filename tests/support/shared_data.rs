//! Where the shared real data lives (`../shared/data` beside the repository, or
//! `$MVGRASP_SHARED_DATA`), for the tests of every crate (included with `#[path]`).
//!
//! A test that needs it skips with a message when it is absent, unless
//! `MVGRASP_REQUIRE_SHARED_DATA=1` (which `.ci/run` sets when the folder is there): then a
//! missing file fails the test, so a test cannot pass by skipping where the data should be.

#![allow(dead_code, clippy::panic)]

use std::path::PathBuf;

/// The shared data folder, whether or not it exists.
pub fn shared_data_root() -> PathBuf {
    std::env::var_os("MVGRASP_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            // The workspace root (the folder with Cargo.lock) above the crate under test.
            let mut root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
            while !root.join("Cargo.lock").is_file() && root.pop() {}
            root.join("../shared/data")
        })
}

/// Whether a missing shared file fails the test instead of skipping it.
pub fn shared_data_required() -> bool {
    std::env::var("MVGRASP_REQUIRE_SHARED_DATA").is_ok_and(|v| v == "1")
}

/// `relative` under the shared data folder when it exists; else `None` after saying on stderr
/// that the test is skipped, or a panic when the data is required.
pub fn shared_data(relative: &str) -> Option<PathBuf> {
    let path = shared_data_root().join(relative);
    if path.exists() {
        return Some(path);
    }
    if shared_data_required() {
        panic!(
            "MVGRASP_REQUIRE_SHARED_DATA=1 but {} is absent (set MVGRASP_SHARED_DATA to the \
             shared data folder)",
            path.display()
        );
    }
    eprintln!(
        "skipped: no shared data at {} (set MVGRASP_SHARED_DATA)",
        path.display()
    );
    None
}
