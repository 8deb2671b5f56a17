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
