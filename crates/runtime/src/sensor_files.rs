//! Depth images and object masks from a sensor's files: `.npy` float32 metres (gqcnn's
//! format, shape (H, W) or (H, W, 1)) and 16-bit PNG millimetres for depth, a PNG whose
//! non-zero pixels are the object for masks. Missing depth (NaN, infinities, 0) reads as 0.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use mvgrasp_geometry::one_line;
use mvgrasp_planner::{Mask, PlannerError};

/// `Result` with the planner's error (a sensor file's errors are [`PlannerError::File`]).
pub type Result<T, E = PlannerError> = std::result::Result<T, E>;

/// A depth image as read, before it is paired with intrinsics.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorDepth {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Depth along the optical axis, metres, row-major; 0 where missing.
    pub depth_m: Vec<f32>,
}

/// The median depth of a real tabletop scene is between these, metres: outside, the file is
/// in another unit.
const PLAUSIBLE_MEDIAN_M: [f32; 2] = [0.05, 10.0];

/// Reads a depth image: `.npy` (float32 or float64 metres, shape (H, W) or (H, W, 1), C or
/// Fortran order) or `.png` (16-bit grey, millimetres).
///
/// # Errors
/// [`PlannerError::File`] naming the file: unreadable, another format or shape, no valid
/// pixel, or a median depth that says the unit is not metres ("looks like millimetres").
pub fn read_depth(path: impl AsRef<Path>) -> Result<SensorDepth> {
    read_depth_in_units(path, 1000.0)
}

/// [`read_depth`] with a PNG's values in `png_units_per_m` units a metre (1000: millimetres;
/// `render`'s datasets write 10,000: tenths of a millimetre).
///
/// # Errors
/// See [`read_depth`].
pub fn read_depth_in_units(path: impl AsRef<Path>, png_units_per_m: f32) -> Result<SensorDepth> {
    let path = path.as_ref();
    let fail = |detail: String| PlannerError::File {
        path: path.to_path_buf(),
        detail,
    };
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let depth = match extension.as_deref() {
        Some("npy") => read_npy(path).map_err(fail)?,
        Some("png") => read_png_depth(path, png_units_per_m).map_err(fail)?,
        _ => {
            return Err(fail(
                "unknown depth format: expected .npy (float32 metres) or .png (16-bit millimetres)"
                    .into(),
            ));
        }
    };
    let mut valid: Vec<f32> = depth.depth_m.iter().copied().filter(|&d| d > 0.0).collect();
    if valid.is_empty() {
        return Err(fail(format!(
            "no valid depth: all {} pixels are missing (0, NaN or infinite)",
            depth.depth_m.len()
        )));
    }
    let middle = valid.len() / 2;
    let median = *valid.select_nth_unstable_by(middle, f32::total_cmp).1;
    if median > PLAUSIBLE_MEDIAN_M[1] {
        return Err(fail(format!(
            "median depth {median} m: looks like millimetres; expected metres"
        )));
    }
    if median < PLAUSIBLE_MEDIAN_M[0] {
        return Err(fail(format!(
            "median depth {median} m is below 5 cm: expected metres"
        )));
    }
    Ok(depth)
}

/// Refuses a `.npy` whose preamble declares a header longer than the file (`npyz` would
/// allocate the declared length, up to 4 GiB, before reading it).
fn check_npy_header_length(file: &mut File) -> std::result::Result<(), String> {
    use std::io::{Read, Seek};
    let size = file.metadata().map_err(|e| e.to_string())?.len();
    let mut preamble = [0u8; 12];
    let read = file.read(&mut preamble).map_err(|e| e.to_string())?;
    file.rewind().map_err(|e| e.to_string())?;
    if read < 10 || &preamble[..6] != b"\x93NUMPY" {
        return Ok(()); // npyz names what is wrong with it
    }
    let (start, length) = if preamble[6] == 1 {
        (
            10,
            u64::from(u16::from_le_bytes([preamble[8], preamble[9]])),
        )
    } else if read == 12 {
        let bytes = [preamble[8], preamble[9], preamble[10], preamble[11]];
        (12, u64::from(u32::from_le_bytes(bytes)))
    } else {
        return Err(format!("a .npy of {size} bytes, shorter than its preamble"));
    };
    if start + length > size {
        return Err(format!(
            "not a .npy: its header declares {length} bytes, the file has {size} bytes in all"
        ));
    }
    Ok(())
}

fn read_npy(path: &Path) -> std::result::Result<SensorDepth, String> {
    let mut file = File::open(path).map_err(|e| e.to_string())?;
    check_npy_header_length(&mut file)?;
    let npy = npyz::NpyFile::new(BufReader::new(file))
        .map_err(|e| format!("not a .npy: {}", one_line(&e.to_string())))?;
    let shape = npy.shape().to_vec();
    let (height, width) = match shape[..] {
        [h, w] | [h, w, 1] => (h, w),
        _ => {
            return Err(format!("shape {shape:?}: expected (H, W) or (H, W, 1)"));
        }
    };
    if width == 0 || height == 0 {
        return Err(format!("shape {shape:?}: an empty image"));
    }
    let (width, height) = (
        u32::try_from(width).map_err(|e| e.to_string())?,
        u32::try_from(height).map_err(|e| e.to_string())?,
    );
    let order = npy.order();
    let dtype = npy.dtype();
    let values: Vec<f32> = match dtype.descr().trim_matches('\'') {
        "<f4" | ">f4" => npy.into_vec::<f32>().map_err(|e| e.to_string())?,
        "<f8" | ">f8" => npy
            .into_vec::<f64>()
            .map_err(|e| e.to_string())?
            .into_iter()
            .map(|v| v as f32)
            .collect(),
        other => return Err(format!("dtype {other}: expected float32 metres")),
    };
    let mut depth_m = match order {
        npyz::Order::C => values,
        // Column-major: element (v, u) is at u * height + v.
        npyz::Order::Fortran => {
            let (w, h) = (width as usize, height as usize);
            (0..w * h).map(|i| values[(i % w) * h + i / w]).collect()
        }
    };
    for d in &mut depth_m {
        if !(d.is_finite() && *d > 0.0) {
            *d = 0.0;
        }
    }
    Ok(SensorDepth {
        width,
        height,
        depth_m,
    })
}

fn read_png_depth(path: &Path, units_per_m: f32) -> std::result::Result<SensorDepth, String> {
    let (info, bytes) = decode_png(path, png::Transformations::IDENTITY)?;
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Sixteen {
        return Err(format!(
            "a {:?} {:?}-bit PNG: expected 16-bit grey depth in millimetres",
            info.color_type, info.bit_depth as u8
        ));
    }
    let depth_m = bytes
        .chunks_exact(2)
        .map(|b| f32::from(u16::from_be_bytes([b[0], b[1]])) / units_per_m)
        .collect();
    Ok(SensorDepth {
        width: info.width,
        height: info.height,
        depth_m,
    })
}

fn decode_png(
    path: &Path,
    transformations: png::Transformations,
) -> std::result::Result<(png::OutputInfo, Vec<u8>), String> {
    let file = File::open(path).map_err(|e| e.to_string())?;
    let file_bytes = file.metadata().map_err(|e| e.to_string())?.len();
    let mut decoder = png::Decoder::new(BufReader::new(file));
    decoder.set_transformations(transformations);
    let mut reader = decoder.read_info().map_err(|e| format!("not a PNG: {e}"))?;
    let (width, height) = (reader.info().width, reader.info().height);
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| format!("{width} x {height} pixels: too large to hold"))?;
    // Deflate expands a byte into at most 1032, so the header's size is checked against the
    // file's before the image is allocated (a 300-byte file may declare a terabyte).
    if u64::try_from(size).unwrap_or(u64::MAX) > file_bytes.saturating_mul(1032) + (1 << 20) {
        return Err(format!(
            "not a PNG: its header declares {width} x {height} pixels ({size} bytes), more \
             than its {file_bytes} bytes can hold"
        ));
    }
    let mut bytes = vec![0; size];
    let info = reader
        .next_frame(&mut bytes)
        .map_err(|e| format!("not a PNG: {e}"))?;
    bytes.truncate(info.buffer_size());
    Ok((info, bytes))
}

/// Reads an 8-bit RGB (or RGBA, the alpha dropped) PNG as `(width, height, pixels)`, row-major.
///
/// # Errors
/// [`PlannerError::File`] naming the file: unreadable, not a PNG, or not 8-bit colour.
pub fn read_rgb(path: impl AsRef<Path>) -> Result<(u32, u32, Vec<[u8; 3]>)> {
    let path = path.as_ref();
    let fail = |detail: String| PlannerError::File {
        path: path.to_path_buf(),
        detail,
    };
    let (info, bytes) = decode_png(path, png::Transformations::IDENTITY).map_err(fail)?;
    let channels = match (info.color_type, info.bit_depth) {
        (png::ColorType::Rgb, png::BitDepth::Eight) => 3,
        (png::ColorType::Rgba, png::BitDepth::Eight) => 4,
        (colour, depth) => {
            return Err(fail(format!(
                "a {colour:?} {}-bit PNG: expected an 8-bit RGB image",
                depth as u8
            )));
        }
    };
    let pixels = bytes
        .chunks_exact(channels)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok((info.width, info.height, pixels))
}

/// Reads an object mask: a PNG (any colour type and depth) whose non-zero pixels (in any
/// colour channel; alpha is ignored) are the object, for a `width` x `height` depth image.
///
/// # Errors
/// [`PlannerError::File`] naming the file: unreadable, another size than the depth image, or
/// no object pixel.
pub fn read_mask(path: impl AsRef<Path>, width: u32, height: u32) -> Result<Mask> {
    read_mask_of(path, width, height, None)
}

/// [`read_mask`] where the object is the pixels of value `object_id` (of a grey 8-bit mask,
/// as `render`'s datasets write: 0 background, 1 object, 2 table), or every non-zero pixel
/// for `None`.
///
/// # Errors
/// See [`read_mask`].
pub fn read_mask_of(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    object_id: Option<u8>,
) -> Result<Mask> {
    let path = path.as_ref();
    let fail = |detail: String| PlannerError::File {
        path: path.to_path_buf(),
        detail,
    };
    let (info, bytes) = decode_png(path, png::Transformations::EXPAND).map_err(fail)?;
    let channels = info.color_type.samples();
    let colour = match info.color_type {
        png::ColorType::GrayscaleAlpha => 1,
        png::ColorType::Rgba => 3,
        _ => channels,
    };
    let sample_bytes = if info.bit_depth == png::BitDepth::Sixteen {
        2
    } else {
        1
    };
    let pixel_bytes = channels * sample_bytes;
    let pixels: Vec<bool> = bytes
        .chunks_exact(pixel_bytes)
        .map(|p| match object_id {
            Some(id) => p[0] == id,
            None => p[..colour * sample_bytes].iter().any(|&b| b != 0),
        })
        .collect();
    if (info.width, info.height) != (width, height) {
        return Err(fail(format!(
            "the mask is {} x {}, the depth image {width} x {height}",
            info.width, info.height
        )));
    }
    Mask::new(width, height, pixels).map_err(|e| fail(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use npyz::WriterBuilder;

    fn write_npy_f32(path: &Path, shape: &[u64], values: &[f32]) {
        let mut out = Vec::new();
        {
            let mut writer = npyz::WriteOptions::<f32>::new()
                .default_dtype()
                .shape(shape)
                .writer(&mut out)
                .begin_nd()
                .unwrap();
            writer.extend(values.iter().copied()).unwrap();
            writer.finish().unwrap();
        }
        std::fs::write(path, out).unwrap();
    }

    fn write_png(
        path: &Path,
        width: u32,
        height: u32,
        color: png::ColorType,
        depth: png::BitDepth,
        data: &[u8],
    ) {
        crate::images::encode(path, width, height, color, depth, data).unwrap();
    }

    #[test]
    fn depth_reads_from_npy_and_millimetre_png_with_missing_pixels_at_zero() {
        let dir = tempfile::tempdir().unwrap();
        let npy = dir.path().join("d.npy");
        write_npy_f32(
            &npy,
            &[2, 3, 1],
            &[0.7, f32::NAN, 0.0, 0.71, f32::INFINITY, 0.72],
        );
        let depth = read_depth(&npy).unwrap();
        assert_eq!((depth.width, depth.height), (3, 2));
        assert_eq!(depth.depth_m, vec![0.7, 0.0, 0.0, 0.71, 0.0, 0.72]);
        let png_path = dir.path().join("d.png");
        let mm: Vec<u8> = [700u16, 0, 710, 720]
            .iter()
            .flat_map(|v| v.to_be_bytes())
            .collect();
        write_png(
            &png_path,
            2,
            2,
            png::ColorType::Grayscale,
            png::BitDepth::Sixteen,
            &mm,
        );
        let depth = read_depth(&png_path).unwrap();
        assert_eq!(depth.depth_m, vec![0.7, 0.0, 0.71, 0.72]);
    }

    #[test]
    fn bad_depth_files_say_what_is_wrong_and_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("depth.npy");
        let err = |path: &Path| read_depth(path).unwrap_err().to_string();
        // Missing, empty, not a .npy, the wrong shape.
        assert!(err(&path).contains("depth.npy"));
        std::fs::write(&path, b"").unwrap();
        assert!(err(&path).contains("not a .npy"), "{}", err(&path));
        write_npy_f32(&path, &[2, 2, 3], &[0.7; 12]);
        assert!(err(&path).contains("expected (H, W)"), "{}", err(&path));
        // All missing; millimetres; centimetres read as metres would be fine, but 1 mm is not.
        write_npy_f32(&path, &[2, 2], &[0.0, f32::NAN, 0.0, 0.0]);
        assert!(err(&path).contains("no valid depth"), "{}", err(&path));
        write_npy_f32(&path, &[2, 2], &[700.0; 4]);
        let e = err(&path);
        assert!(
            e.contains("depth.npy") && e.contains("looks like millimetres"),
            "{e}"
        );
        write_npy_f32(&path, &[2, 2], &[0.001; 4]);
        assert!(err(&path).contains("below 5 cm"), "{}", err(&path));
        // An 8-bit PNG is not depth in millimetres; another extension is no depth format.
        let png_path = dir.path().join("depth.png");
        write_png(
            &png_path,
            2,
            2,
            png::ColorType::Grayscale,
            png::BitDepth::Eight,
            &[1, 2, 3, 4],
        );
        assert!(err(&png_path).contains("16-bit"), "{}", err(&png_path));
        let txt = dir.path().join("depth.txt");
        std::fs::write(&txt, "0.7").unwrap();
        assert!(err(&txt).contains("unknown depth format"), "{}", err(&txt));
    }

    #[test]
    fn masks_are_the_non_zero_pixels_of_the_right_size() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mask.png");
        write_png(
            &path,
            3,
            1,
            png::ColorType::Grayscale,
            png::BitDepth::Eight,
            &[0, 255, 7],
        );
        let mask = read_mask(&path, 3, 1).unwrap();
        assert_eq!(
            (0..3).map(|u| mask.at(u, 0)).collect::<Vec<_>>(),
            vec![false, true, true]
        );
        // RGBA: alpha alone is not the object.
        write_png(
            &path,
            2,
            1,
            png::ColorType::Rgba,
            png::BitDepth::Eight,
            &[0, 0, 0, 255, 0, 9, 0, 255],
        );
        let mask = read_mask(&path, 2, 1).unwrap();
        assert_eq!((mask.at(0, 0), mask.at(1, 0)), (false, true));
        let err = read_mask(&path, 3, 1).unwrap_err().to_string();
        assert!(err.contains("mask.png") && err.contains("2 x 1"), "{err}");
        write_png(
            &path,
            2,
            1,
            png::ColorType::Grayscale,
            png::BitDepth::Eight,
            &[0, 0],
        );
        let err = read_mask(&path, 2, 1).unwrap_err().to_string();
        assert!(
            err.contains("mask.png") && err.contains("no object pixel"),
            "{err}"
        );
    }
}
