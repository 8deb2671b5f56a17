// mvgrasp-render: flat-shaded meshes to RGB + instance id (one Rgba8Unorm target, id in alpha)
// and camera-frame depth z in metres (one R32Uint target holding the f32's bits: wgpu's GL
// backend refuses R32Float as a render target on desktop GL contexts). Vertices arrive in world
// coordinates, expanded three a triangle, with their face normal.

struct ViewUniforms {
    // OpenCV camera frame (x right, y down, z forward) from world.
    camera_from_world: mat4x4<f32>,
    // wgpu clip space from the OpenCV camera frame (see camera.rs).
    clip_from_camera: mat4x4<f32>,
};

@group(0) @binding(0) var<uniform> view: ViewUniforms;

struct VertexIn {
    @location(0) position_world: vec3<f32>,
    @location(1) normal_world: vec3<f32>,
    @location(2) color: vec4<f32>,
    @location(3) instance_id: u32,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) position_camera: vec3<f32>,
    @location(1) @interpolate(flat) normal_camera: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) @interpolate(flat) instance_id: u32,
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
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    var diffuse = 0.0;
    let len = length(in.normal_camera);
    if (len > 0.0) {
        var n = in.normal_camera / len;
        // Two-sided: the normal that faces the camera (the camera sits at the origin).
        if (dot(n, in.position_camera) > 0.0) {
            n = -n;
        }
        diffuse = max(dot(n, LIGHT_CAMERA), 0.0);
    }
    let shade = AMBIENT + (1.0 - AMBIENT) * diffuse;
    // The id is stored as unorm8: (id + 0.25) / 255 reads back as id whether the hardware
    // rounds to nearest or towards zero.
    let id = min((f32(in.instance_id) + 0.25) / 255.0, 1.0);
    out.rgb_id = vec4<f32>(in.color * shade, id);
    out.depth_m_bits = bitcast<u32>(in.position_camera.z);
    return out;
}
