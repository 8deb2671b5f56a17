//! Views that look more like photographs than the datasets' flat renders: the object and the
//! table textured (solid procedural patterns), glossy or dark objects, one to four lights fixed
//! in the room with tinted white, a coloured background, and per camera what a sensor adds
//! (white balance, exposure, blur, noise, JPEG). Every draw comes from the seed, so the same
//! seed gives the same bytes on the same renderer.
//!
//! Not drawn (limits of the renderer): cast shadows, reflections of the surroundings, image
//! textures, lens distortion.

use jpeg_encoder::{ColorType, Encoder};
use mvgrasp_geometry::{Camera, Pose3, TriangleMesh};
use mvgrasp_render::{Colors, Light, Lighting, Material, Pattern, Renderer, random_colors};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use mvgrasp_planner::seed::splitmix;

use super::{OBJECT_ID, SceneData, TABLE_HALF_SIDE_M, TABLE_ID, render_frames};
use crate::convert::rgb_view_of;
use crate::error::{Error, Result};
use crate::stereo::RgbView;

/// The look of one scene, the same for every view of it.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneLook {
    /// The room's lights and background.
    pub lighting: Lighting,
    /// The object's texture and gloss.
    pub object: Material,
    /// The object's colours: random per vertex (a confetti print, as the flat datasets'),
    /// or this one colour everywhere (then its pattern is its only texture).
    pub object_rgb: Option<[u8; 3]>,
    /// The object's colours are multiplied by this (below 1: a dark object).
    pub object_brightness: f32,
    /// The table's colour.
    pub table_rgb: [u8; 3],
    /// The table's texture and gloss.
    pub table: Material,
}

/// What one camera adds to the light that reaches it.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorLook {
    /// Per-channel gains of white balance and exposure together.
    pub gains: [f32; 3],
    /// Gaussian blur (focus, motion), pixels; 0: sharp.
    pub blur_sigma_px: f32,
    /// Read noise, 8-bit levels (standard deviation).
    pub read_noise: f32,
    /// Shot noise: the standard deviation at a full-scale pixel, levels (it grows as the
    /// square root of the level).
    pub shot_noise: f32,
    /// JPEG quality the image went through, or none.
    pub jpeg_quality: Option<u8>,
}

fn photo(problem: impl Into<String>) -> Error {
    Error::Photo {
        problem: problem.into(),
    }
}

fn uniform(rng: &mut ChaCha8Rng, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * rng.random::<f32>()
}

fn log_uniform(rng: &mut ChaCha8Rng, lo: f32, hi: f32) -> f32 {
    (lo.ln() + (hi.ln() - lo.ln()) * rng.random::<f32>()).exp()
}

fn random_rgb(rng: &mut ChaCha8Rng) -> [u8; 3] {
    [rng.random(), rng.random(), rng.random()]
}

/// A light's white: warm (tungsten) to cool (shade), scaled by `intensity`.
fn tinted(rng: &mut ChaCha8Rng, intensity: f32) -> [f32; 3] {
    let warmth = uniform(rng, -1.0, 1.0);
    let tint = if warmth > 0.0 {
        [1.0, 1.0 - 0.1 * warmth, 1.0 - 0.3 * warmth]
    } else {
        [1.0 + 0.3 * warmth, 1.0 + 0.1 * warmth, 1.0]
    };
    tint.map(|t| t * intensity)
}

fn random_pattern(rng: &mut ChaCha8Rng, plain_share: f64) -> Pattern {
    if rng.random_bool(plain_share) {
        Pattern::Plain
    } else {
        Pattern::ALL[rng.random_range(1..Pattern::ALL.len())]
    }
}

impl SceneLook {
    /// A random look: see the module's documentation for what varies.
    pub fn random(rng: &mut ChaCha8Rng) -> Self {
        let lights = rng.random_range(1..=4usize);
        let lights = (0..lights)
            .map(|i| {
                // The first light is the key light, high above; the others fill from anywhere
                // above the table.
                let elevation = if i == 0 {
                    uniform(rng, 35.0, 88.0)
                } else {
                    uniform(rng, 10.0, 80.0)
                }
                .to_radians();
                let azimuth = uniform(rng, 0.0, std::f32::consts::TAU);
                let intensity = if i == 0 {
                    uniform(rng, 0.5, 1.0)
                } else {
                    uniform(rng, 0.1, 0.45)
                };
                Light {
                    towards_world: [
                        elevation.cos() * azimuth.cos(),
                        elevation.cos() * azimuth.sin(),
                        elevation.sin(),
                    ],
                    rgb: tinted(rng, intensity),
                }
            })
            .collect();
        let ambient = uniform(rng, 0.1, 0.4);
        let ambient_rgb = tinted(rng, ambient);
        let background_rgb = if rng.random_bool(0.5) {
            [uniform(rng, 0.0, 1.0); 3]
        } else {
            std::array::from_fn(|_| uniform(rng, 0.0, 1.0))
        };
        // Gloss: most objects matte or satin, some shiny (glazed ceramic, metal, wet plastic).
        let (specular, shininess) = match rng.random_range(0..20u8) {
            0..=9 => (uniform(rng, 0.0, 0.1), log_uniform(rng, 1.0, 16.0)),
            10..=16 => (uniform(rng, 0.15, 0.6), log_uniform(rng, 8.0, 128.0)),
            _ => (uniform(rng, 0.6, 1.0), log_uniform(rng, 64.0, 512.0)),
        };
        // A third of the objects printed all over; the others one colour, most with a pattern.
        let object_rgb = (!rng.random_bool(0.3)).then(|| random_rgb(rng));
        let object = Material {
            pattern: random_pattern(rng, 0.2),
            cycles_per_m: log_uniform(rng, 20.0, 400.0),
            second_rgb: random_rgb(rng),
            contrast: uniform(rng, 0.3, 1.0),
            specular,
            shininess,
        };
        let object_brightness = if rng.random_bool(0.15) {
            uniform(rng, 0.1, 0.4)
        } else {
            1.0
        };
        let table = Material {
            pattern: random_pattern(rng, 0.2),
            cycles_per_m: log_uniform(rng, 4.0, 100.0),
            second_rgb: random_rgb(rng),
            contrast: uniform(rng, 0.1, 0.7),
            specular: uniform(rng, 0.0, 0.4),
            shininess: log_uniform(rng, 4.0, 64.0),
        };
        Self {
            lighting: Lighting::World {
                ambient_rgb,
                lights,
                background_rgb,
            },
            object,
            object_rgb,
            object_brightness,
            table_rgb: std::array::from_fn(|_| rng.random_range(40..=220)),
            table,
        }
    }
}

impl SensorLook {
    /// A random camera: white balance within 15% per channel, exposure 0.75 to 1.3, blur in
    /// half the images (up to 1.2 px), read noise up to 4 levels, shot noise up to 6 at full
    /// scale, JPEG (quality 60 to 95) in half of them.
    pub fn random(rng: &mut ChaCha8Rng) -> Self {
        let exposure = uniform(rng, 0.75, 1.3);
        Self {
            gains: std::array::from_fn(|_| exposure * uniform(rng, 0.85, 1.15)),
            blur_sigma_px: if rng.random_bool(0.5) {
                uniform(rng, 0.3, 1.2)
            } else {
                0.0
            },
            read_noise: uniform(rng, 0.0, 4.0),
            shot_noise: uniform(rng, 0.0, 6.0),
            jpeg_quality: rng.random_bool(0.5).then(|| rng.random_range(60..=95u8)),
        }
    }

    /// Applies this camera to `rgb` (`width` x `height`, row-major), its noise drawn from `rng`.
    ///
    /// # Errors
    /// A JPEG encoder or decoder failure (a bug: the sizes are checked).
    pub fn apply(
        &self,
        rgb: &mut [[u8; 3]],
        width: usize,
        height: usize,
        rng: &mut ChaCha8Rng,
    ) -> Result<()> {
        if rgb.len() != width * height {
            return Err(photo(format!(
                "{} pixels for a {width} x {height} image",
                rgb.len()
            )));
        }
        let mut planes: Vec<Vec<f32>> = (0..3)
            .map(|c| {
                rgb.iter()
                    .map(|p| f32::from(p[c]) * self.gains[c])
                    .collect()
            })
            .collect();
        if self.blur_sigma_px > 0.0 {
            for plane in &mut planes {
                gaussian_blur(plane, width, height, self.blur_sigma_px);
            }
        }
        let unit = Normal::new(0.0f32, 1.0).map_err(|e| photo(e.to_string()))?;
        for (i, pixel) in rgb.iter_mut().enumerate() {
            for (c, plane) in planes.iter().enumerate() {
                let level = plane[i].clamp(0.0, 255.0);
                let sigma =
                    (self.read_noise.powi(2) + self.shot_noise.powi(2) * level / 255.0).sqrt();
                let noisy = level + sigma * unit.sample(rng);
                pixel[c] = noisy.round().clamp(0.0, 255.0) as u8;
            }
        }
        if let Some(quality) = self.jpeg_quality {
            jpeg_round_trip(rgb, width, height, quality)?;
        }
        Ok(())
    }
}

/// Separable Gaussian blur of one channel, edges clamped.
fn gaussian_blur(plane: &mut [f32], width: usize, height: usize, sigma: f32) {
    let radius = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = (-radius..=radius)
        .map(|d| (-(d * d) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let total: f32 = kernel.iter().sum();
    let kernel: Vec<f32> = kernel.iter().map(|k| k / total).collect();
    let mut scratch = vec![0.0f32; plane.len()];
    let clamp = |x: isize, n: usize| x.clamp(0, n as isize - 1) as usize;
    for y in 0..height {
        for x in 0..width {
            scratch[y * width + x] = kernel
                .iter()
                .enumerate()
                .map(|(k, w)| w * plane[y * width + clamp(x as isize + k as isize - radius, width)])
                .sum();
        }
    }
    for y in 0..height {
        for x in 0..width {
            plane[y * width + x] = kernel
                .iter()
                .enumerate()
                .map(|(k, w)| {
                    w * scratch[clamp(y as isize + k as isize - radius, height) * width + x]
                })
                .sum();
        }
    }
}

/// Encodes `rgb` as a JPEG of `quality` and decodes it back in place.
fn jpeg_round_trip(rgb: &mut [[u8; 3]], width: usize, height: usize, quality: u8) -> Result<()> {
    let (w, h) = (
        u16::try_from(width).map_err(|_| photo(format!("{width} px too wide for JPEG")))?,
        u16::try_from(height).map_err(|_| photo(format!("{height} px too tall for JPEG")))?,
    );
    let flat: Vec<u8> = rgb.iter().flatten().copied().collect();
    let mut encoded = Vec::new();
    Encoder::new(&mut encoded, quality)
        .encode(&flat, w, h, ColorType::Rgb)
        .map_err(|e| photo(format!("JPEG encoding: {e}")))?;
    let options = zune_jpeg::zune_core::options::DecoderOptions::default()
        .jpeg_set_out_colorspace(zune_jpeg::zune_core::colorspace::ColorSpace::RGB);
    let decoded = zune_jpeg::JpegDecoder::new_with_options(
        zune_jpeg::zune_core::bytestream::ZCursor::new(&encoded),
        options,
    )
    .decode()
    .map_err(|e| photo(format!("JPEG decoding: {e}")))?;
    if decoded.len() != flat.len() {
        return Err(photo(format!(
            "JPEG decoded {} bytes, expected {}",
            decoded.len(),
            flat.len()
        )));
    }
    for (pixel, d) in rgb.iter_mut().zip(decoded.chunks_exact(3)) {
        *pixel = [d[0], d[1], d[2]];
    }
    Ok(())
}

/// What [`render_photoreal`] made.
#[derive(Clone, Debug)]
pub struct Photographed {
    /// The scene's look.
    pub look: SceneLook,
    /// Per camera, the view (colours, camera, the object's mask) and its rendered depth.
    pub views: Vec<(RgbView, Vec<f32>)>,
}

/// The views of `cameras` as [`SceneLook::random`] and [`SensorLook::random`] make them (both
/// drawn from `seed`), with the object's masks and each view's rendered (true) depth: the
/// photographic counterpart of [`crate::planner::render_rgb`] (the same table).
///
/// # Errors
/// A renderer error.
pub fn render_photoreal(
    renderer: &Renderer,
    mesh: &TriangleMesh,
    table_from_object: &Pose3,
    cameras: &[Camera],
    seed: u64,
) -> Result<Photographed> {
    let mut rng = ChaCha8Rng::seed_from_u64(splitmix(seed ^ 0x7068_6f74));
    let look = SceneLook::random(&mut rng);
    let data = SceneData::of_mesh(mesh, table_from_object, TABLE_HALF_SIDE_M);
    let colors: Vec<[u8; 3]> = match look.object_rgb {
        Some(rgb) => vec![rgb; mesh.vertices().len()],
        None => random_colors(splitmix(seed ^ 0x7267_6221), mesh.vertices().len()),
    }
    .into_iter()
    .map(|c| c.map(|x| (f32::from(x) * look.object_brightness).round() as u8))
    .collect();
    let mut inputs = data.mesh_inputs(mesh.triangles(), Colors::PerVertex(&colors), true);
    for input in &mut inputs {
        if input.instance_id == OBJECT_ID {
            input.material = look.object;
        } else if input.instance_id == TABLE_ID {
            input.material = look.table;
            input.colors = Colors::Uniform(look.table_rgb);
        }
    }
    let frames = render_frames(renderer, &inputs, cameras, &look.lighting)?;
    let mut out = Vec::with_capacity(frames.len());
    for (camera, frame) in cameras.iter().zip(frames) {
        let (mut view, depth_m) = rgb_view_of(camera, frame, OBJECT_ID);
        let sensor = SensorLook::random(&mut rng);
        let k = &camera.intrinsics;
        sensor.apply(&mut view.rgb, k.width as usize, k.height as usize, &mut rng)?;
        out.push((view, depth_m));
    }
    Ok(Photographed { look, views: out })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn looks_are_drawn_from_the_seed_and_stay_in_range() {
        let draw = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            (SceneLook::random(&mut rng), SensorLook::random(&mut rng))
        };
        assert_eq!(draw(7), draw(7));
        assert_ne!(draw(7), draw(8));
        for seed in 0..200 {
            let (scene, sensor) = draw(seed);
            let Lighting::World { lights, .. } = &scene.lighting else {
                panic!("a photographic look is lit by the room")
            };
            assert!((1..=4).contains(&lights.len()));
            assert!(
                lights.iter().all(|l| l.towards_world[2] > 0.0),
                "lights are above"
            );
            // Valid materials (the renderer would refuse the others).
            for m in [scene.object, scene.table] {
                assert!((1.0..=1024.0).contains(&m.cycles_per_m), "{m:?}");
                assert!((0.0..=1.0).contains(&m.contrast) && (0.0..=1.0).contains(&m.specular));
                assert!((1.0..=512.0).contains(&m.shininess), "{m:?}");
            }
            assert!(sensor.gains.iter().all(|g| (0.6..1.5).contains(g)));
        }
    }

    #[test]
    fn the_sensor_blurs_adds_noise_and_compresses_deterministically() {
        let (w, h) = (40, 30);
        // A sharp vertical edge.
        let image: Vec<[u8; 3]> = (0..w * h)
            .map(|i| if i % w < w / 2 { [30; 3] } else { [220; 3] })
            .collect();
        let sensor = SensorLook {
            gains: [1.0; 3],
            blur_sigma_px: 1.0,
            read_noise: 2.0,
            shot_noise: 3.0,
            jpeg_quality: Some(80),
        };
        let run = |seed| {
            let mut out = image.clone();
            sensor
                .apply(&mut out, w, h, &mut ChaCha8Rng::seed_from_u64(seed))
                .unwrap();
            out
        };
        let (a, b) = (run(1), run(1));
        assert_eq!(a, b, "same seed, same bytes");
        assert_ne!(a, run(2), "the noise comes from the seed");
        // The edge is spread over pixels on both sides of it; far from it, the level stays
        // within the noise.
        let row = 15 * w;
        let at = |x: usize| f32::from(a[row + x][0]);
        assert!(
            at(w / 2 - 1) > 45.0 && at(w / 2) < 205.0,
            "{} {}",
            at(w / 2 - 1),
            at(w / 2)
        );
        assert!((at(3) - 30.0).abs() < 12.0 && (at(w - 4) - 220.0).abs() < 15.0);
        let mut wrong = image.clone();
        assert!(
            sensor
                .apply(&mut wrong[1..], w, h, &mut ChaCha8Rng::seed_from_u64(0))
                .is_err()
        );
    }
}
