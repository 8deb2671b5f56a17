//! One rendered view: RGB, depth and instance mask, row-major from the top-left pixel.

/// The images of one view. Pixel (u, v) is at index `v * width + u`.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Shaded colour, `height x width x 3` bytes; black where nothing was drawn.
    pub rgb: Vec<u8>,
    /// Depth z along the optical axis (OpenCV camera frame), metres; 0 where nothing was drawn.
    pub depth_m: Vec<f32>,
    /// Instance id of the mesh seen at each pixel; 0 for the background.
    pub mask: Vec<u8>,
}

impl Frame {
    /// Index of pixel (u, v) in `depth_m` and `mask`, or `None` outside the image.
    pub fn index(&self, u: u32, v: u32) -> Option<usize> {
        (u < self.width && v < self.height).then(|| v as usize * self.width as usize + u as usize)
    }

    /// Depth at pixel (u, v) in metres (0 = nothing), or `None` outside the image.
    pub fn depth_at(&self, u: u32, v: u32) -> Option<f32> {
        self.index(u, v).and_then(|i| self.depth_m.get(i).copied())
    }

    /// Instance id at pixel (u, v) (0 = background), or `None` outside the image.
    pub fn mask_at(&self, u: u32, v: u32) -> Option<u8> {
        self.index(u, v).and_then(|i| self.mask.get(i).copied())
    }

    /// Colour at pixel (u, v), or `None` outside the image.
    pub fn rgb_at(&self, u: u32, v: u32) -> Option<[u8; 3]> {
        let i = 3 * self.index(u, v)?;
        Some([
            *self.rgb.get(i)?,
            *self.rgb.get(i + 1)?,
            *self.rgb.get(i + 2)?,
        ])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_access_is_bounds_checked() {
        let f = Frame {
            width: 2,
            height: 1,
            rgb: vec![1, 2, 3, 4, 5, 6],
            depth_m: vec![0.0, 0.5],
            mask: vec![0, 9],
        };
        assert_eq!(f.rgb_at(1, 0), Some([4, 5, 6]));
        assert_eq!(f.depth_at(1, 0), Some(0.5));
        assert_eq!(f.mask_at(1, 0), Some(9));
        assert_eq!(f.mask_at(2, 0), None);
        assert_eq!(f.depth_at(0, 1), None);
    }
}
