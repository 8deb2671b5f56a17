// mvgrasp-render: flat-shaded meshes to RGB + instance id (one Rgba8Unorm target, id in alpha)
// and camera-frame depth z in metres (one R32Uint target holding the f32's bits: wgpu's GL
// backend refuses R32Float as a render target on desktop GL contexts). Vertices arrive in world
// coordinates, expanded three a triangle, with their face normal and material. Two looks (see
// look.rs): the headlight (mode 0: one light fixed to the camera, flat colours) and world
// lighting (mode 1: up to 4 directional lights fixed in the world, solid procedural textures and
// Blinn-Phong highlights).

struct ViewUniforms {
    // OpenCV camera frame (x right, y down, z forward) from world.
    camera_from_world: mat4x4<f32>,
    // wgpu clip space from the OpenCV camera frame (see camera.rs).
    clip_from_camera: mat4x4<f32>,
    // x: mode (0 headlight, 1 world lights); yzw: ambient light, per channel.
    mode_ambient: vec4<f32>,
    // Per light: unit direction towards it in the camera frame, w 1 when it is on.
    light_towards: array<vec4<f32>, 4>,
    // Per light: colour and intensity (rgb).
    light_rgb: array<vec4<f32>, 4>,
};

@group(0) @binding(0) var<uniform> view: ViewUniforms;

// Shadows (shadow.rs): per light, the orthographic clip (depth 0..1) of its shadow map.
struct ShadowUniforms {
    light_clip_from_world: array<mat4x4<f32>, 4>,
};

@group(1) @binding(0) var<uniform> shadow: ShadowUniforms;
@group(1) @binding(1) var shadow_maps: texture_depth_2d_array;
@group(1) @binding(2) var shadow_sampler: sampler_comparison;

// The shadow pass's light (a dynamic offset into one matrix per light).
@group(0) @binding(0) var<uniform> shadow_pass_light: mat4x4<f32>;

struct VertexIn {
    @location(0) position_world: vec3<f32>,
    @location(1) normal_world: vec3<f32>,
    @location(2) color: vec4<f32>,
    @location(3) instance_id: u32,
    // Pattern code / 255, specular, shininess and frequency (log2-coded), see look.rs.
    @location(4) material: vec4<f32>,
    // Second colour and contrast.
    @location(5) second: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) position_camera: vec3<f32>,
    @location(1) @interpolate(flat) normal_camera: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) @interpolate(flat) instance_id: u32,
    @location(4) position_world: vec3<f32>,
    @location(5) @interpolate(flat) material: vec4<f32>,
    @location(6) @interpolate(flat) second: vec4<f32>,
    @location(7) @interpolate(flat) normal_world: vec3<f32>,
};

struct FragmentOut {
    @location(0) rgb_id: vec4<f32>,
    @location(1) depth_m_bits: u32,
};

// Direction towards a light above-left of the camera, in the camera frame (unit length).
const LIGHT_CAMERA: vec3<f32> = vec3<f32>(-0.3244428, -0.4866643, -0.8111071);
const AMBIENT: f32 = 0.35;

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    var out: VertexOut;
    let p = view.camera_from_world * vec4<f32>(in.position_world, 1.0);
    out.clip = view.clip_from_camera * p;
    out.position_camera = p.xyz;
    out.normal_camera = (view.camera_from_world * vec4<f32>(in.normal_world, 0.0)).xyz;
    out.color = in.color.rgb;
    out.instance_id = in.instance_id;
    out.position_world = in.position_world;
    out.normal_world = in.normal_world;
    out.material = in.material;
    out.second = in.second;
    return out;
}

// The shadow maps' depth pass: only where the light sees.
@vertex
fn vs_shadow(@location(0) position_world: vec3<f32>) -> @builtin(position) vec4<f32> {
    return shadow_pass_light * vec4<f32>(position_world, 1.0);
}

// How much of light i reaches world point p (0 in shadow, 1 lit; 2 x 2 filtered).
fn light_reaching(i: i32, p: vec3<f32>) -> f32 {
    let c = shadow.light_clip_from_world[i] * vec4<f32>(p, 1.0);
    let uv = vec2<f32>(0.5 + 0.5 * c.x, 0.5 - 0.5 * c.y);
    if (any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) || c.z > 1.0) {
        return 1.0;
    }
    return textureSampleCompareLevel(shadow_maps, shadow_sampler, uv, i, c.z - 0.0015);
}

// A hash of a lattice point to [0, 1) (integer mixing: the same on every backend).
fn hash3(p: vec3<i32>) -> f32 {
    var h = bitcast<u32>(p.x) * 0x8da6b343u ^ bitcast<u32>(p.y) * 0xd8163841u
        ^ bitcast<u32>(p.z) * 0xcb1ab31fu;
    h = (h ^ (h >> 15u)) * 0x2c1b3c6du;
    h = (h ^ (h >> 12u)) * 0x297a2d39u;
    h = h ^ (h >> 15u);
    return f32(h >> 8u) / 16777216.0;
}

// Trilinear value noise in [0, 1) with smooth interpolation.
fn value_noise(x: vec3<f32>) -> f32 {
    let i = floor(x);
    let f = x - i;
    let s = f * f * (3.0 - 2.0 * f);
    let c = vec3<i32>(i);
    let x00 = mix(hash3(c), hash3(c + vec3<i32>(1, 0, 0)), s.x);
    let x10 = mix(hash3(c + vec3<i32>(0, 1, 0)), hash3(c + vec3<i32>(1, 1, 0)), s.x);
    let x01 = mix(hash3(c + vec3<i32>(0, 0, 1)), hash3(c + vec3<i32>(1, 0, 1)), s.x);
    let x11 = mix(hash3(c + vec3<i32>(0, 1, 1)), hash3(c + vec3<i32>(1, 1, 1)), s.x);
    return mix(mix(x00, x10, s.y), mix(x01, x11, s.y), s.z);
}

// Three octaves of value noise, in [0, 1).
fn fbm(x: vec3<f32>) -> f32 {
    return 0.5714286 * value_noise(x) + 0.2857143 * value_noise(2.03 * x + 17.0)
        + 0.1428571 * value_noise(4.01 * x + 41.0);
}

// How far a pattern blends towards the second colour at world point p, 0 to 1.
fn pattern(code: u32, p: vec3<f32>, cycles_per_m: f32) -> f32 {
    let x = p * cycles_per_m;
    switch code {
        case 1u: { return fbm(x); }
        case 2u: { return 0.5 + 0.5 * sin(6.2831853 * dot(x, vec3<f32>(0.8, 0.5, 0.33))); }
        case 3u: {
            let c = vec3<i32>(floor(x));
            return f32((c.x + c.y + c.z) & 1);
        }
        case 4u: {
            return 0.5 + 0.5 * sin(6.2831853 * (dot(x, vec3<f32>(0.6, 0.3, 0.74)) + 2.0 * fbm(0.5 * x)));
        }
        default: { return 0.0; }
    }
}

// World lighting: textured colour, Lambert diffuse and Blinn-Phong highlights of every light.
fn world_lit(in: VertexOut, n: vec3<f32>, n_world: vec3<f32>) -> vec3<f32> {
    let code = u32(round(in.material.x * 255.0));
    let specular = in.material.y;
    let shininess = exp2(in.material.z * 9.0);
    let cycles_per_m = exp2(in.material.w * 10.0);
    let t = pattern(code, in.position_world, cycles_per_m);
    let base = mix(in.color, in.second.rgb, in.second.a * t);
    let towards_eye = -normalize(in.position_camera);
    var lit = base * view.mode_ambient.yzw;
    // Looked up a little off the surface, so that it does not shadow itself.
    let lookup = in.position_world + 0.002 * n_world;
    for (var i = 0; i < 4; i++) {
        let light = view.light_towards[i];
        if (light.w > 0.0) {
            let cosine = dot(n, light.xyz);
            if (cosine > 0.0) {
                let half_way = normalize(light.xyz + towards_eye);
                let glint = specular * pow(max(dot(n, half_way), 0.0), shininess);
                let reaching = light_reaching(i, lookup);
                lit += reaching * (base * cosine + vec3<f32>(glint)) * view.light_rgb[i].rgb;
            }
        }
    }
    return lit;
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    var diffuse = 0.0;
    // Two-sided: the normal that faces the camera (the camera sits at the origin).
    var n = vec3<f32>(0.0, 0.0, -1.0);
    let len = length(in.normal_camera);
    if (len > 0.0) {
        n = in.normal_camera / len;
        if (dot(n, in.position_camera) > 0.0) {
            n = -n;
        }
        diffuse = max(dot(n, LIGHT_CAMERA), 0.0);
    }
    let shade = AMBIENT + (1.0 - AMBIENT) * diffuse;
    var rgb = in.color * shade;
    if (view.mode_ambient.x > 0.5) {
        // The world normal turned as the camera-frame one was (towards the camera).
        var n_world = in.normal_world;
        if (len > 0.0) {
            n_world = normalize(n_world);
            if (dot(in.normal_camera, in.position_camera) > 0.0) {
                n_world = -n_world;
            }
        }
        rgb = world_lit(in, n, n_world);
    }
    // The id is stored as unorm8: (id + 0.25) / 255 reads back as id whether the hardware
    // rounds to nearest or towards zero.
    let id = min((f32(in.instance_id) + 0.25) / 255.0, 1.0);
    out.rgb_id = vec4<f32>(rgb, id);
    out.depth_m_bits = bitcast<u32>(in.position_camera.z);
    return out;
}
