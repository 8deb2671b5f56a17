//! The one error type of `mvgrasp-geometry`.
//!
//! Every variant names the operation or fault, the values involved, and the file last, so that
//! a user reading one line knows what to fix and where.

use std::path::PathBuf;

/// Where a mesh or camera came from: a file, or memory (procedural objects, user arrays).
pub(crate) fn in_memory() -> PathBuf {
    PathBuf::from("<in-memory>")
}

/// A parser's message on one line. When the message draws a source excerpt under itself (TOML
/// and pest do: `12 | text` and `^---` lines), the excerpt is dropped and the remaining lines
/// are joined with ": "; otherwise line breaks and other control characters (a JSON key that
/// quotes the file's bytes) are written as escapes (`\n`). Errors are printed one per line (a
/// log line, a CLI's stderr), so every parser's message goes through this before it is
/// wrapped.
///
/// ```
/// use mvgrasp_geometry::one_line;
/// let toml = "TOML parse error at line 1, column 2\n  |\n1 | p\n  |  ^\nkey with no value\n";
/// assert_eq!(one_line(toml), "TOML parse error at line 1, column 2: key with no value");
/// let json = "unknown field `a\nb`, expected `K` at line 1 column 9";
/// assert_eq!(one_line(json), "unknown field `a\\nb`, expected `K` at line 1 column 9");
/// ```
pub fn one_line(message: &str) -> String {
    let excerpt = |line: &str| {
        line.split_once('|')
            .is_some_and(|(gutter, _)| gutter.trim().chars().all(|c| c.is_ascii_digit()))
    };
    if !message.lines().any(|line| excerpt(line.trim())) {
        return message
            .trim_end()
            .chars()
            .map(|c| {
                if c.is_control() {
                    c.escape_default().to_string()
                } else {
                    c.to_string()
                }
            })
            .collect();
    }
    let kept: Vec<String> = message
        .lines()
        .map(str::trim)
        .filter(|line| {
            let marker = line
                .chars()
                .all(|c| matches!(c, '^' | '-' | '~' | ' ' | '>'));
            !line.is_empty() && !excerpt(line) && !marker
        })
        .map(|line| one_line(line.trim_start_matches("= ")))
        .collect();
    kept.join(": ")
}

/// Everything that can go wrong in `mvgrasp-geometry`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GeometryError {
    /// The file does not exist.
    #[error("{path}: no such file")]
    NotFound {
        /// The missing file.
        path: PathBuf,
    },
    /// The file exists but could not be read or written.
    #[error("{path}: cannot {op}: {source}")]
    Io {
        /// What we were doing: "read", "write", "rename".
        op: &'static str,
        /// The underlying error.
        source: std::io::Error,
        /// The file.
        path: PathBuf,
    },
    /// The extension names no format we read.
    #[error("{path}: unsupported mesh format {extension:?} (expected .obj, .stl or .urdf)")]
    UnsupportedFormat {
        /// The extension found ("" when there is none).
        extension: String,
        /// The file.
        path: PathBuf,
    },
    /// The content could not be parsed.
    #[error("{path}: cannot parse {format}: {detail}")]
    Parse {
        /// "OBJ", "STL", "URDF", "intrinsics JSON", ...
        format: &'static str,
        /// What the parser said.
        detail: String,
        /// The file.
        path: PathBuf,
    },
    /// The mesh has no triangles at all.
    #[error("{path}: the mesh has no triangles")]
    NoTriangles {
        /// The file.
        path: PathBuf,
    },
    /// Some vertex coordinates are NaN or infinite.
    #[error(
        "{path}: {count} of {total} vertices have NaN or infinite coordinates (first: vertex {first})"
    )]
    NonFiniteVertices {
        /// How many vertices are bad.
        count: usize,
        /// How many vertices the mesh has.
        total: usize,
        /// The index of the first bad vertex.
        first: usize,
        /// The file.
        path: PathBuf,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "{path}: triangle {triangle} refers to vertex {index}, but the mesh has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// The triangle's position in the index list.
        triangle: usize,
        /// The offending vertex index.
        index: u64,
        /// How many vertices there are.
        vertex_count: usize,
        /// The file.
        path: PathBuf,
    },
    /// Every triangle has zero area or repeats a vertex.
    #[error("{path}: all {triangles} triangles are degenerate (zero area or repeated vertices)")]
    DegenerateOnly {
        /// How many triangles the mesh had.
        triangles: usize,
        /// The file.
        path: PathBuf,
    },
    /// The mesh is implausibly large or small for a graspable object in metres.
    #[error(
        "{path}: largest extent is {extent:.4} (expected metres, between {min_m} and {max_m}){hint}"
    )]
    AbsurdSize {
        /// The largest bounding-box extent, in file units times the load scale.
        extent: f32,
        /// The smallest accepted extent, metres.
        min_m: f32,
        /// The largest accepted extent, metres.
        max_m: f32,
        /// A hint such as "; looks like millimetres: load with scale 0.001".
        hint: String,
        /// The file.
        path: PathBuf,
    },
    /// A URDF names a mesh file that is not there.
    #[error("{path}: link {link:?} uses mesh {mesh:?}, which does not exist")]
    UrdfMeshMissing {
        /// The link.
        link: String,
        /// The resolved mesh path.
        mesh: PathBuf,
        /// The URDF.
        path: PathBuf,
    },
    /// A URDF has no geometry of the requested kind.
    #[error("{path}: no {kind} geometry in any link")]
    UrdfNoGeometry {
        /// "visual" or "collision".
        kind: &'static str,
        /// The URDF.
        path: PathBuf,
    },
    /// A URDF's joints do not form a tree rooted at one link.
    #[error("{path}: {detail}")]
    UrdfStructure {
        /// What is wrong.
        detail: String,
        /// The URDF.
        path: PathBuf,
    },
    /// A mesh inside a URDF failed to load.
    #[error("{path}: link {link:?}: {source}")]
    UrdfLink {
        /// The link.
        link: String,
        /// Why the mesh failed.
        source: Box<GeometryError>,
        /// The URDF.
        path: PathBuf,
    },
    /// A parameter is out of its valid range.
    #[error("{op}: {name} = {value} is invalid: {expected}")]
    InvalidParameter {
        /// The operation.
        op: &'static str,
        /// The parameter.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// What would be valid.
        expected: &'static str,
    },
    /// A resting pose past the list the object offers (see [`crate::RestingPoses`]).
    #[error(
        "resting pose {asked} asked for: the object offers {offered} (its stable poses that \
         neither roll nor topple, or its marginal ones when it has none), 0 to {last} ({path})",
        last = offered.saturating_sub(1)
    )]
    NoSuchPose {
        /// The pose asked for.
        asked: usize,
        /// How many are offered.
        offered: usize,
        /// The mesh's origin.
        path: PathBuf,
    },
    /// A geometric computation has no answer for this input (flat or degenerate shapes).
    #[error("{op}: {detail} ({path})")]
    Degenerate {
        /// The operation: "convex hull", "stable poses", ...
        op: &'static str,
        /// Why.
        detail: String,
        /// The mesh's origin.
        path: PathBuf,
    },
}

/// `Result` with [`GeometryError`].
pub type Result<T, E = GeometryError> = std::result::Result<T, E>;
