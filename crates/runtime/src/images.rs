//! PNG output: 8-bit RGB, 8-bit masks and 16-bit depth.

use std::io::BufWriter;
use std::path::Path;

use crate::error::{Error, Result};

/// Depth PNGs hold z in units of 0.1 mm: value = round(z_m * 10000), 0 = nothing (so the
/// deepest representable z is 6.5535 m).
pub const DEPTH_PNG_UNITS_PER_M: f32 = 10_000.0;

/// Writes an 8-bit PNG with `channels` (1 = grey, 3 = RGB) of `width x height`.
pub fn write_png8(path: &Path, width: u32, height: u32, channels: u8, data: &[u8]) -> Result<()> {
    let color = if channels == 3 {
        png::ColorType::Rgb
    } else {
        png::ColorType::Grayscale
    };
    encode(path, width, height, color, png::BitDepth::Eight, data)
}

/// Writes depth in metres as a 16-bit grey PNG in [`DEPTH_PNG_UNITS_PER_M`] units, clamping at
/// 6.5535 m; missing pixels (0 or not finite) stay 0.
pub fn write_depth_png(path: &Path, width: u32, height: u32, depth_m: &[f32]) -> Result<()> {
    let bytes: Vec<u8> = depth_m
        .iter()
        .flat_map(|&z| {
            let units = if z.is_finite() && z > 0.0 {
                (z * DEPTH_PNG_UNITS_PER_M)
                    .round()
                    .clamp(1.0, f32::from(u16::MAX)) as u16
            } else {
                0
            };
            units.to_be_bytes()
        })
        .collect();
    encode(
        path,
        width,
        height,
        png::ColorType::Grayscale,
        png::BitDepth::Sixteen,
        &bytes,
    )
}

/// Encodes `data` as a PNG of the given colour type and bit depth at `path`.
pub(crate) fn encode(
    path: &Path,
    width: u32,
    height: u32,
    color: png::ColorType,
    depth: png::BitDepth,
    data: &[u8],
) -> Result<()> {
    let file = std::fs::File::create(path).map_err(Error::io("create", path))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
    encoder.set_color(color);
    encoder.set_depth(depth);
    encoder.set_compression(png::Compression::Fast);
    let png_error = |source: png::EncodingError| Error::Png {
        source,
        path: path.to_path_buf(),
    };
    let mut writer = encoder.write_header().map_err(png_error)?;
    writer.write_image_data(data).map_err(png_error)?;
    writer.finish().map_err(png_error)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_png_keeps_a_tenth_of_a_millimetre() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.png");
        write_depth_png(&path, 2, 2, &[0.0, 0.70004, f32::NAN, 9.0]).unwrap();
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut buf).unwrap();
        let values: Vec<u16> = buf
            .chunks(2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
            .collect();
        assert_eq!(values, vec![0, 7000, 0, u16::MAX]);
    }
}
