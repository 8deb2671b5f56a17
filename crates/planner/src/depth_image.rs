//! A depth image with its size: what every sampler, crop and noise function takes, so that a
//! slice of the wrong length cannot reach their indexing.

use mvgrasp_geometry::{Camera, Intrinsics};

use crate::error::{PlannerError, Result};

/// Depth along the optical axis (z, not ray length), metres, row-major, with the intrinsics of
/// the camera that saw it; a missing pixel is 0 (NaN, infinities and negative values are
/// mapped to 0 when the image is made).
#[derive(Clone, Debug, PartialEq)]
pub struct DepthImage {
    intrinsics: Intrinsics,
    depth_m: Vec<f32>,
}

impl DepthImage {
    /// An image of `intrinsics.width` x `intrinsics.height` values.
    ///
    /// # Errors
    /// [`PlannerError::DepthSize`] when `depth_m` has another length.
    pub fn new(intrinsics: Intrinsics, mut depth_m: Vec<f32>) -> Result<Self> {
        let expected = intrinsics.width as usize * intrinsics.height as usize;
        if depth_m.len() != expected {
            return Err(PlannerError::DepthSize {
                width: intrinsics.width,
                height: intrinsics.height,
                expected,
                got: depth_m.len(),
            });
        }
        for d in &mut depth_m {
            if !(d.is_finite() && *d > 0.0) {
                *d = 0.0;
            }
        }
        Ok(Self {
            intrinsics,
            depth_m,
        })
    }

    /// The intrinsics of the camera that saw it.
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.intrinsics
    }

    /// Width, pixels.
    pub fn width(&self) -> u32 {
        self.intrinsics.width
    }

    /// Height, pixels.
    pub fn height(&self) -> u32 {
        self.intrinsics.height
    }

    /// The values, row-major.
    pub fn as_slice(&self) -> &[f32] {
        &self.depth_m
    }

    /// The values, row-major, to change in place (keep missing pixels at 0).
    pub fn as_mut_slice(&mut self) -> &mut [f32] {
        &mut self.depth_m
    }

    /// The values, row-major.
    pub fn into_vec(self) -> Vec<f32> {
        self.depth_m
    }

    /// The image with its missing pixels filled, as the network's crops should see it
    /// (borrowed when nothing is missing, and when nothing is observed). Each connected hole
    /// takes the farthest depth observed around it: a depth camera's holes are mostly shadows,
    /// where the projector (or the second lens) does not see past an edge, so what is missing
    /// is the surface behind the edge, not in front of it. Training renders have no holes;
    /// without the fill a crop pixel with none of its samples observed reads 0 m, a depth no
    /// training crop has (gqcnn inpaints its images for the same reason).
    pub fn with_holes_filled(&self) -> std::borrow::Cow<'_, DepthImage> {
        let d = &self.depth_m;
        if !d.contains(&0.0) || d.iter().all(|&x| x == 0.0) {
            return std::borrow::Cow::Borrowed(self);
        }
        let (w, h) = (self.width() as usize, self.height() as usize);
        let neighbours = |i: usize| {
            let (u, v) = ((i % w) as i64, (i / w) as i64);
            (-1i64..=1)
                .flat_map(move |dv| (-1i64..=1).map(move |du| (u + du, v + dv)))
                .filter(move |&(x, y)| {
                    (x, y) != (u, v) && (0..w as i64).contains(&x) && (0..h as i64).contains(&y)
                })
                .map(move |(x, y)| y as usize * w + x as usize)
        };
        let mut out = d.clone();
        let mut seen = vec![false; w * h];
        let (mut stack, mut hole) = (Vec::new(), Vec::new());
        for start in 0..w * h {
            if d[start] > 0.0 || seen[start] {
                continue;
            }
            seen[start] = true;
            stack.push(start);
            hole.clear();
            let mut farthest = 0.0f32;
            while let Some(i) = stack.pop() {
                hole.push(i);
                for j in neighbours(i) {
                    if d[j] > 0.0 {
                        farthest = farthest.max(d[j]);
                    } else if !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
            for &i in &hole {
                out[i] = farthest;
            }
        }
        std::borrow::Cow::Owned(Self {
            intrinsics: self.intrinsics,
            depth_m: out,
        })
    }

    /// The depth at column `u`, row `v`; 0 outside the image.
    pub fn at(&self, u: i64, v: i64) -> f32 {
        let (w, h) = (i64::from(self.width()), i64::from(self.height()));
        if (0..w).contains(&u) && (0..h).contains(&v) {
            self.depth_m[(v * w + u) as usize]
        } else {
            0.0
        }
    }
}

/// Pixels within this of an object's mask (along both axes) count as on it: a depth edge, and
/// so a grasp's contact, lies on either side of the object's outline.
pub const MASK_MARGIN_PX: u32 = 2;

/// Which pixels of an image are the object (a segmentation mask), row-major.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mask {
    width: u32,
    height: u32,
    pixels: Vec<bool>,
}

impl Mask {
    /// A `width` x `height` mask.
    ///
    /// # Errors
    /// [`PlannerError::Mask`] when `pixels` has another length or no pixel is set.
    pub fn new(width: u32, height: u32, pixels: Vec<bool>) -> Result<Self> {
        let expected = width as usize * height as usize;
        if pixels.len() != expected {
            return Err(PlannerError::Mask(format!(
                "{} values for a {width} x {height} image (expected {expected})",
                pixels.len()
            )));
        }
        if !pixels.contains(&true) {
            return Err(PlannerError::Mask("no object pixel".into()));
        }
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    /// Width, pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height, pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Whether column `u`, row `v` is the object; `false` outside the image.
    pub fn at(&self, u: i64, v: i64) -> bool {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        (0..w).contains(&u) && (0..h).contains(&v) && self.pixels[(v * w + u) as usize]
    }

    /// Whether an object pixel lies within `radius_px` of column `u`, row `v` along both axes.
    pub fn near(&self, u: i64, v: i64, radius_px: u32) -> bool {
        let r = i64::from(radius_px);
        (v - r..=v + r).any(|y| (u - r..=u + r).any(|x| self.at(x, y)))
    }

    /// Every pixel, row-major: `true` for the object's.
    pub fn into_pixels(self) -> Vec<bool> {
        self.pixels
    }

    /// Object pixels.
    pub fn count(&self) -> usize {
        self.pixels.iter().filter(|&&p| p).count()
    }

    /// The mask grown by `radius_px` (a square neighbourhood): a pixel is set when one within
    /// `radius_px` along both axes is.
    pub fn dilated(&self, radius_px: u32) -> Mask {
        let (w, h) = (self.width as usize, self.height as usize);
        let r = radius_px as usize;
        // Rows, then columns: two passes of a running window.
        let grow = |line: &[bool]| -> Vec<bool> {
            let n = line.len();
            let mut prefix = vec![0usize; n + 1];
            for (i, &p) in line.iter().enumerate() {
                prefix[i + 1] = prefix[i] + usize::from(p);
            }
            (0..n)
                .map(|i| prefix[(i + r + 1).min(n)] > prefix[i.saturating_sub(r)])
                .collect()
        };
        let mut rows = Vec::with_capacity(w * h);
        for line in self.pixels.chunks_exact(w) {
            rows.extend(grow(line));
        }
        let mut pixels = vec![false; w * h];
        for u in 0..w {
            let column: Vec<bool> = (0..h).map(|v| rows[v * w + u]).collect();
            for (v, p) in grow(&column).into_iter().enumerate() {
                pixels[v * w + u] = p;
            }
        }
        Mask {
            width: self.width,
            height: self.height,
            pixels,
        }
    }
}

/// One view the planner looks through: a camera (pose and intrinsics) and the depth image it
/// saw, whoever made it (the renderer, a sensor file, a depth predictor), and which of its
/// pixels are the object when that is known.
#[derive(Clone, Debug)]
pub struct View {
    /// Pose and intrinsics.
    pub camera: Camera,
    /// What it saw.
    pub depth: DepthImage,
    /// The object's pixels: grasps are sampled on its edges, and both contacts must lie on it.
    /// `None`: anything seen may be grasped.
    pub mask: Option<Mask>,
}

impl View {
    /// A view of `depth` through `camera`.
    ///
    /// # Errors
    /// [`PlannerError::ViewMismatch`] when the image was made with other intrinsics than the
    /// camera's (`view` names it in the message): the planner crops with the camera's and
    /// unprojects with the image's, so the two must be one.
    pub fn new(view: usize, camera: Camera, depth: DepthImage) -> Result<Self> {
        if camera.intrinsics != *depth.intrinsics() {
            return Err(PlannerError::ViewMismatch {
                view,
                depth: *depth.intrinsics(),
                camera: camera.intrinsics,
            });
        }
        Ok(Self {
            camera,
            depth,
            mask: None,
        })
    }

    /// This view with an object mask.
    ///
    /// # Errors
    /// [`PlannerError::Mask`] for a mask of another size than the depth image.
    pub fn with_mask(mut self, mask: Mask) -> Result<Self> {
        if (mask.width(), mask.height()) != (self.depth.width(), self.depth.height()) {
            return Err(PlannerError::Mask(format!(
                "the mask is {} x {}, the depth image {} x {}",
                mask.width(),
                mask.height(),
                self.depth.width(),
                self.depth.height()
            )));
        }
        self.mask = Some(mask);
        Ok(self)
    }

    /// The angle between the optical axis and the table plane (the seed paper's theta, the
    /// multi-view GQ-CNN's second pose input): pi/2 looking straight down.
    pub fn theta_rad(&self) -> f32 {
        theta_rad(&self.camera)
    }
}

/// The angle between a camera's optical axis and the table plane (the seed paper's theta):
/// pi/2 looking straight down, 0 looking across the table.
pub fn theta_rad(camera: &Camera) -> f32 {
    (-camera.optical_axis().z).clamp(-1.0, 1.0).asin()
}

#[cfg(test)]
mod tests {
    use super::*;
    use mvgrasp_geometry::IntrinsicsPreset;

    #[test]
    fn holes_take_the_far_side_and_a_full_image_is_not_copied() {
        let k = Intrinsics {
            width: 6,
            height: 1,
            ..Intrinsics::phoxi_s()
        };
        // An object's top at 0.6 m, a shadow of two pixels, the floor at 0.8 m.
        let image = DepthImage::new(k, vec![0.6, 0.6, 0.0, 0.0, 0.8, 0.8]).unwrap();
        let filled = image.with_holes_filled();
        assert_eq!(filled.as_slice(), [0.6, 0.6, 0.8, 0.8, 0.8, 0.8]);
        let full = DepthImage::new(k, vec![0.7; 6]).unwrap();
        assert!(matches!(
            full.with_holes_filled(),
            std::borrow::Cow::Borrowed(_)
        ));
        let empty = DepthImage::new(k, vec![0.0; 6]).unwrap();
        assert_eq!(empty.with_holes_filled().as_slice(), [0.0; 6]);
    }

    #[test]
    fn a_wrong_length_is_an_error_and_bad_values_read_missing() {
        let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        let n = (k.width * k.height) as usize;
        let err = DepthImage::new(k, vec![0.5; n - 1]).unwrap_err();
        assert!(err.to_string().contains("516 x 386"), "{err}");
        let mut values = vec![0.5; n];
        values[0] = f32::NAN;
        values[1] = f32::INFINITY;
        values[2] = -1.0;
        let image = DepthImage::new(k, values).unwrap();
        assert_eq!(&image.as_slice()[..4], &[0.0, 0.0, 0.0, 0.5]);
        assert_eq!(image.at(-1, 0), 0.0);
        assert_eq!(image.at(3, 0), 0.5);
        assert_eq!(image.at(i64::from(k.width), 0), 0.0);
    }

    #[test]
    fn masks_check_their_size_and_grow() {
        assert!(Mask::new(2, 2, vec![true; 3]).is_err());
        assert!(Mask::new(2, 2, vec![false; 4]).is_err());
        let mut pixels = vec![false; 25];
        pixels[12] = true; // the centre of 5 x 5
        let mask = Mask::new(5, 5, pixels).unwrap();
        assert_eq!(mask.count(), 1);
        let grown = mask.dilated(1);
        assert_eq!(grown.count(), 9);
        assert!(grown.at(1, 1) && grown.at(3, 3) && !grown.at(0, 2) && !grown.at(4, 4));
        assert!(mask.near(4, 4, 2) && !mask.near(4, 4, 1) && !mask.near(0, 2, 1));
        assert_eq!(mask.dilated(0), mask);
        assert_eq!(mask.dilated(9).count(), 25);
        assert!(!mask.at(-1, 0) && !mask.at(5, 0));
    }

    #[test]
    fn a_view_needs_the_image_of_its_own_camera() {
        let phoxi = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        let camera = Camera::look_at(
            phoxi,
            mvgrasp_geometry::Vec3::new(0.0, 0.0, 0.7),
            mvgrasp_geometry::Vec3::ZERO,
            mvgrasp_geometry::Vec3::Y,
        )
        .unwrap();
        let n = (phoxi.width * phoxi.height) as usize;
        assert!(View::new(0, camera, DepthImage::new(phoxi, vec![0.7; n]).unwrap()).is_ok());
        // Same size, another focal length: refused, naming the view.
        let other = Intrinsics {
            fx: 500.0,
            fy: 500.0,
            ..phoxi
        };
        let err = View::new(3, camera, DepthImage::new(other, vec![0.7; n]).unwrap()).unwrap_err();
        assert!(err.to_string().starts_with("view 3:"), "{err}");
    }
}
