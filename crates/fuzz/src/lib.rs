//! Fuzz targets for every reader of outside bytes in mvgrasp, and the loop that runs them on
//! stable Rust.
//!
//! Why not `cargo fuzz` or AFL: both need instrumentation that stable Rust does not give
//! (libFuzzer's sanitizer coverage is nightly-only; AFL needs its own toolchain), and CI runs
//! stable. So the loop here is coverage-blind but structure-aware: it starts from valid files
//! of each format, mutates them with byte-level and text-level mutations and a dictionary of
//! the format's tokens, and keeps an input whenever the reader's answer reads differently
//! from every earlier one (each distinct error message is a path through the reader). Every
//! input is checked for a panic, a run over 1 s, a single allocation over 256 MiB, and a
//! refusal that is not one line naming the file. A target is a plain `fn(&Path)`, so the
//! same targets can be handed to libFuzzer later without change.
//!
//! `cargo run --release -p mvgrasp-fuzz -- run --seconds 600` is the long pass (each target
//! in its own process, so that an abort or a stack overflow is caught with its input);
//! `tests/smoke.rs` runs every target for a few seconds and replays `regressions/`.

pub mod alloc;
pub mod engine;
pub mod mutate;
pub mod targets;

pub use engine::{Finding, Outcome, Summary, check_one, fuzz, regression_inputs};
pub use targets::{TARGETS, Target, target};

#[global_allocator]
static ALLOCATOR: alloc::Counting = alloc::Counting;

/// Where the committed regression inputs live: `crates/fuzz/regressions/<target>/`.
pub fn regressions_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions")
}

/// A fresh work folder for `target` inside `parent`, with the target's companion files.
///
/// # Errors
/// The folder cannot be made or written.
pub fn work_folder(
    parent: &std::path::Path,
    target: &Target,
) -> std::io::Result<std::path::PathBuf> {
    let dir = parent.join(target.name);
    if dir.exists() {
        std::fs::remove_dir_all(&dir)?;
    }
    std::fs::create_dir_all(&dir)?;
    (target.setup)(&dir)?;
    Ok(dir)
}
