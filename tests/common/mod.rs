//! What the integration tests share.

use mvgrasp::render::{Backend, INSTALL_HINT, Renderer};

/// The renderer of the GPU tests, or `None` (skipped) when `MVGRASP_SKIP_GPU_TESTS=1`. A machine
/// without a graphics adapter fails loudly with the install hint.
pub fn renderer() -> Option<Renderer> {
    if std::env::var("MVGRASP_SKIP_GPU_TESTS").is_ok_and(|v| v == "1") {
        eprintln!("MVGRASP_SKIP_GPU_TESTS=1: skipping a GPU test");
        return None;
    }
    match Renderer::new(Backend::Auto) {
        Ok(r) => Some(r),
        Err(e) => {
            panic!("no graphics adapter ({e}); {INSTALL_HINT}; or set MVGRASP_SKIP_GPU_TESTS=1")
        }
    }
}

/// Renders the RGB-D dataset of one built-in object of `category` into `out` with the
/// `render` command (its `CATEGORY_000/{train,test}` folders).
pub fn render_dataset(out: &std::path::Path, category: &str) {
    let rendered = std::process::Command::new(env!("CARGO_BIN_EXE_render"))
        .args([
            "--out",
            out.to_str().unwrap(),
            "--categories",
            category,
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(
        rendered.status.success(),
        "{}",
        String::from_utf8_lossy(&rendered.stderr)
    );
}
