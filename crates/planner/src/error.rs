//! The one error type of `mvgrasp-planner`.

/// Everything that can go wrong while planning.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlannerError {
    /// A depth image whose pixel count is not its intrinsics' width x height.
    #[error("depth image: {got} values for a {width} x {height} image (expected {expected})")]
    DepthSize {
        /// Image width, pixels.
        width: u32,
        /// Image height, pixels.
        height: u32,
        /// `width * height`.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// A view whose depth image was made with other intrinsics than its camera's.
    #[error(
        "view {view}: the depth image's intrinsics (fx {}, fy {}, cx {}, cy {}, {} x {}) are not \
         the camera's (fx {}, fy {}, cx {}, cy {}, {} x {})",
        depth.fx, depth.fy, depth.cx, depth.cy, depth.width, depth.height,
        camera.fx, camera.fy, camera.cx, camera.cy, camera.width, camera.height
    )]
    ViewMismatch {
        /// The view.
        view: usize,
        /// The depth image's intrinsics.
        depth: mvgrasp_geometry::Intrinsics,
        /// The camera's.
        camera: mvgrasp_geometry::Intrinsics,
    },
    /// A network the planner cannot feed.
    #[error(
        "network: it takes {image_px} x {image_px} crops and {pose_inputs} pose inputs; the \
         planner makes {crop_px} x {crop_px} crops and 1 (depth) or 2 (depth, theta) pose inputs"
    )]
    Network {
        /// The network's crop side, pixels.
        image_px: usize,
        /// The network's pose inputs.
        pose_inputs: usize,
        /// The planner's crop side, pixels.
        crop_px: u32,
    },
    /// A camera whose images the network cannot be fed.
    #[error("camera with fx = {fx}, fy = {fy}: {detail}")]
    Camera {
        /// Focal length along x, pixels.
        fx: f32,
        /// Focal length along y, pixels.
        fy: f32,
        /// Why not.
        detail: &'static str,
    },
    /// A sensor file (depth image, mask) that cannot be read or holds something unusable.
    #[error("{}: {detail}", path.display())]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong with it.
        detail: String,
    },
    /// A mask whose size is not its depth image's, or with no object pixel.
    #[error("mask: {0}")]
    Mask(String),
    /// The table could not be found in a depth image, or nothing stands on it.
    #[error("table: {0}")]
    Table(String),
    /// Running a network failed (or its shipped weights are broken).
    #[error(transparent)]
    Infer(#[from] mvgrasp_infer::InferError),
}

/// `Result` with [`PlannerError`].
pub type Result<T, E = PlannerError> = std::result::Result<T, E>;

impl PlannerError {
    /// [`PlannerError::File`] naming `path`.
    pub(crate) fn file(path: &std::path::Path, detail: String) -> Self {
        Self::File {
            path: path.to_path_buf(),
            detail,
        }
    }
}

/// A small model file's JSON (`what`: "ranker", "probability"), refused unless `format_of` it
/// is `format`; errors name `path`.
pub(crate) fn parse_tagged<T: serde::de::DeserializeOwned>(
    text: &str,
    path: &std::path::Path,
    what: &str,
    format: &str,
    format_of: fn(&T) -> &str,
) -> Result<T> {
    let file: T = serde_json::from_str(text).map_err(|e| {
        PlannerError::file(
            path,
            format!(
                "not a {what} file: {}",
                mvgrasp_geometry::one_line(&e.to_string())
            ),
        )
    })?;
    if format_of(&file) != format {
        return Err(PlannerError::file(
            path,
            format!("format {:?}, expected {format:?}", format_of(&file)),
        ));
    }
    Ok(file)
}
