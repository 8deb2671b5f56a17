//! Shared test helpers: where the real data lives, and skipping cleanly when it does not.

use std::path::PathBuf;

/// `../shared/data/meshes` beside the repository (or `$MVGRASP_SHARED_DATA/meshes`), or `None`
/// with a message on stderr so a skipped test says why.
pub fn shared_meshes() -> Option<PathBuf> {
    let data = std::env::var_os("MVGRASP_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"));
    let meshes = data.join("meshes");
    if meshes.is_dir() {
        Some(meshes)
    } else {
        eprintln!(
            "skipped: no shared mesh data at {} (set MVGRASP_SHARED_DATA)",
            meshes.display()
        );
        None
    }
}
