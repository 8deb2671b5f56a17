//! Shared test helpers: where the real data lives, and skipping cleanly when it does not.

use std::path::PathBuf;

#[path = "../../../../tests/support/shared_data.rs"]
mod shared_data;
pub use shared_data::shared_data;

/// `../shared/data/meshes` beside the repository (or `$MVGRASP_SHARED_DATA/meshes`), or `None`
/// with a message on stderr so a skipped test says why (a failure under
/// `MVGRASP_REQUIRE_SHARED_DATA=1`).
pub fn shared_meshes() -> Option<PathBuf> {
    shared_data("meshes")
}
