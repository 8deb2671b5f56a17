//! How a scene looks: each mesh's [`Material`] (a procedural solid texture and a specular
//! highlight) and the [`Lighting`] of a render call. The default, [`Lighting::Headlight`] with
//! [`Material::MATTE`], is the renderer's original look (one light fixed above-left of each
//! camera, flat colours, black background) and draws the same bytes as before materials existed;
//! [`Lighting::World`] lights the scene as a room does, the same for every view.

use crate::error::{RenderError, Result};

/// Lights [`Lighting::World`] may hold.
pub const MAX_LIGHTS: usize = 4;

/// A procedural texture, evaluated at the surface's world position (a solid texture: the same
/// point has the same colour in every view, and nothing needs texture coordinates).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Pattern {
    /// The mesh's colours alone.
    #[default]
    Plain,
    /// Value noise, three octaves (mottled plastic, cardboard, stone).
    Noise,
    /// Parallel bands (printing, wood grain, fabric).
    Stripes,
    /// A 3-D checkerboard (printed patterns, tiles).
    Checker,
    /// Bands bent by noise (marble, wood rings).
    Marble,
}

impl Pattern {
    /// Every pattern, [`Pattern::Plain`] first.
    pub const ALL: [Self; 5] = [
        Self::Plain,
        Self::Noise,
        Self::Stripes,
        Self::Checker,
        Self::Marble,
    ];

    fn code(self) -> u8 {
        match self {
            Self::Plain => 0,
            Self::Noise => 1,
            Self::Stripes => 2,
            Self::Checker => 3,
            Self::Marble => 4,
        }
    }
}

/// A mesh's surface: its colours (from [`crate::Colors`]) blended towards `second_rgb` by a
/// pattern, and a Blinn-Phong highlight. Only [`Lighting::World`] draws it; the headlight keeps
/// the flat colours.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// The texture.
    pub pattern: Pattern,
    /// Pattern frequency, cycles per metre (1 to 1024; 100 gives 1 cm features).
    pub cycles_per_m: f32,
    /// The colour the pattern blends towards.
    pub second_rgb: [u8; 3],
    /// How far the pattern blends, 0 (not at all) to 1 (all the way to `second_rgb`).
    pub contrast: f32,
    /// Strength of the specular highlight, 0 (matte) to 1.
    pub specular: f32,
    /// Blinn-Phong exponent, 1 (broad sheen) to 512 (a sharp glint).
    pub shininess: f32,
}

impl Material {
    /// No texture, no highlight.
    pub const MATTE: Self = Self {
        pattern: Pattern::Plain,
        cycles_per_m: 1.0,
        second_rgb: [0, 0, 0],
        contrast: 0.0,
        specular: 0.0,
        shininess: 1.0,
    };

    /// Checks the ranges; `mesh_index` names the mesh in the error.
    pub(crate) fn validate(&self, mesh_index: usize) -> Result<()> {
        let bad = |reason: String| RenderError::InvalidMesh { mesh_index, reason };
        let check = |name: &str, x: f32, lo: f32, hi: f32| {
            if x.is_finite() && (lo..=hi).contains(&x) {
                Ok(())
            } else {
                Err(bad(format!(
                    "material {name} is {x}, expected {lo} to {hi}"
                )))
            }
        };
        check("cycles_per_m", self.cycles_per_m, 1.0, 1024.0)?;
        check("contrast", self.contrast, 0.0, 1.0)?;
        check("specular", self.specular, 0.0, 1.0)?;
        check("shininess", self.shininess, 1.0, 512.0)
    }

    /// The eight bytes each vertex carries: pattern, specular, shininess and frequency (the
    /// last two log2-coded), then the second colour and the contrast.
    pub(crate) fn vertex_bytes(&self) -> [u8; 8] {
        let unit = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
        [
            self.pattern.code(),
            unit(self.specular),
            unit(self.shininess.log2() / 9.0),
            unit(self.cycles_per_m.log2() / 10.0),
            self.second_rgb[0],
            self.second_rgb[1],
            self.second_rgb[2],
            unit(self.contrast),
        ]
    }
}

impl Default for Material {
    fn default() -> Self {
        Self::MATTE
    }
}

/// A directional light fixed in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Direction from the scene towards the light, world frame (any length but zero).
    pub towards_world: [f32; 3],
    /// Its colour and intensity per channel (1: a surface facing it shows its full colour).
    pub rgb: [f32; 3],
}

/// The lighting of one render call.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Lighting {
    /// One light above-left of each camera, moving with it, 35% ambient, black background;
    /// materials ignored (the original look, byte for byte).
    #[default]
    Headlight,
    /// Lights fixed in the world, the same for every view, and materials drawn.
    World {
        /// Light reaching every surface, per channel.
        ambient_rgb: [f32; 3],
        /// Up to [`MAX_LIGHTS`] lights.
        lights: Vec<Light>,
        /// Colour of the pixels no mesh covers, 0 to 1 per channel.
        background_rgb: [f32; 3],
    },
}

/// Bytes of the lighting block in the per-view uniforms: a mode and ambient vec4, then the
/// lights' directions (camera frame) and colours, four vec4 each.
pub(crate) const LIGHTING_UNIFORM_BYTES: u64 = 16 + 2 * 16 * MAX_LIGHTS as u64;

impl Lighting {
    /// Checks the light count and that every number is finite and in range.
    pub(crate) fn validate(&self) -> Result<()> {
        let Self::World {
            ambient_rgb,
            lights,
            background_rgb,
        } = self
        else {
            return Ok(());
        };
        let bad = |name: &'static str, value: String, expected: &'static str| {
            Err(RenderError::InvalidParameter {
                op: "render",
                name,
                value,
                expected,
            })
        };
        if lights.len() > MAX_LIGHTS {
            return bad("lighting.lights", lights.len().to_string(), "at most 4");
        }
        if ambient_rgb.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return bad(
                "lighting.ambient_rgb",
                format!("{ambient_rgb:?}"),
                "finite and >= 0",
            );
        }
        if background_rgb.iter().any(|x| !(0.0..=1.0).contains(x)) {
            return bad(
                "lighting.background_rgb",
                format!("{background_rgb:?}"),
                "0 to 1 per channel",
            );
        }
        for light in lights {
            let length = light
                .towards_world
                .iter()
                .map(|x| x * x)
                .sum::<f32>()
                .sqrt();
            if !(length.is_finite() && length > 0.0) {
                return bad(
                    "lighting.lights[].towards_world",
                    format!("{:?}", light.towards_world),
                    "a finite, non-zero direction",
                );
            }
            if light.rgb.iter().any(|x| !x.is_finite() || *x < 0.0) {
                return bad(
                    "lighting.lights[].rgb",
                    format!("{:?}", light.rgb),
                    "finite and >= 0",
                );
            }
        }
        Ok(())
    }

    /// The clear colour of the colour target (alpha 0: the mask's background id).
    pub(crate) fn clear_color(&self) -> wgpu::Color {
        match self {
            Self::Headlight => wgpu::Color::TRANSPARENT,
            Self::World { background_rgb, .. } => wgpu::Color {
                r: f64::from(background_rgb[0]),
                g: f64::from(background_rgb[1]),
                b: f64::from(background_rgb[2]),
                a: 0.0,
            },
        }
    }

    /// The lighting block of one view's uniforms, as f32s: `[mode, ambient rgb]`, then per
    /// light its unit direction in the camera frame (w 1 when the light is on) and its colour.
    pub(crate) fn uniform_floats(&self, camera_from_world: &[[f32; 4]; 4]) -> Vec<f32> {
        let mut out = vec![0.0; LIGHTING_UNIFORM_BYTES as usize / 4];
        let Self::World {
            ambient_rgb,
            lights,
            ..
        } = self
        else {
            return out;
        };
        out[..4].copy_from_slice(&[1.0, ambient_rgb[0], ambient_rgb[1], ambient_rgb[2]]);
        for (i, light) in lights.iter().take(MAX_LIGHTS).enumerate() {
            let d = light.towards_world;
            let r = camera_from_world;
            let rotated: [f32; 3] =
                std::array::from_fn(|row| r[row][0] * d[0] + r[row][1] * d[1] + r[row][2] * d[2]);
            let length = rotated.iter().map(|x| x * x).sum::<f32>().sqrt();
            let direction = 4 + 4 * i;
            let colour = 4 + 4 * MAX_LIGHTS + 4 * i;
            for k in 0..3 {
                out[direction + k] = rotated[k] / length;
                out[colour + k] = light.rgb[k];
            }
            out[direction + 3] = 1.0;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::IDENTITY;

    #[test]
    fn a_material_packs_its_codes_and_refuses_out_of_range_numbers() {
        let m = Material {
            pattern: Pattern::Checker,
            cycles_per_m: 32.0,
            second_rgb: [1, 2, 3],
            contrast: 1.0,
            specular: 0.5,
            shininess: 512.0,
        };
        assert_eq!(m.vertex_bytes(), [3, 128, 255, 128, 1, 2, 3, 255]);
        assert_eq!(Material::MATTE.vertex_bytes(), [0; 8]);
        assert!(m.validate(0).is_ok());
        let err = Material { specular: 1.5, ..m }
            .validate(4)
            .unwrap_err()
            .to_string();
        assert!(err.contains("mesh 4") && err.contains("specular"), "{err}");
        assert!(
            Material {
                cycles_per_m: f32::NAN,
                ..m
            }
            .validate(0)
            .is_err()
        );
    }

    #[test]
    fn world_lights_turn_with_the_camera_and_bad_lights_are_refused() {
        let lighting = Lighting::World {
            ambient_rgb: [0.2; 3],
            lights: vec![Light {
                towards_world: [0.0, 0.0, 2.0],
                rgb: [1.0, 0.5, 0.25],
            }],
            background_rgb: [0.5; 3],
        };
        lighting.validate().unwrap();
        // A camera looking straight down (z forward = -z world, y down = -y world).
        let mut down = IDENTITY;
        down[1][1] = -1.0;
        down[2][2] = -1.0;
        let u = lighting.uniform_floats(&down);
        assert_eq!(&u[..4], &[1.0, 0.2, 0.2, 0.2]);
        assert_eq!(&u[4..8], &[0.0, 0.0, -1.0, 1.0]); // towards the camera
        assert_eq!(&u[20..23], &[1.0, 0.5, 0.25]);
        assert_eq!(u[8 + 3], 0.0); // the second light is off
        assert!(
            Lighting::Headlight
                .uniform_floats(&down)
                .iter()
                .all(|&x| x == 0.0)
        );
        let mut five = lighting.clone();
        if let Lighting::World { lights, .. } = &mut five {
            lights.resize(5, lights[0]);
        }
        assert!(
            five.validate()
                .unwrap_err()
                .to_string()
                .contains("at most 4")
        );
        let zero = Lighting::World {
            ambient_rgb: [0.2; 3],
            lights: vec![Light {
                towards_world: [0.0; 3],
                rgb: [1.0; 3],
            }],
            background_rgb: [0.5; 3],
        };
        assert!(zero.validate().is_err());
    }
}
