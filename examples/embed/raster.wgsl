// The example host's G-buffer pass: rasterizes the scene's world-space triangles into
// depth, shading normal, face normal and albedo (fs_gbuffer), or world position (fs_position).

struct Camera {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;

struct Vertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) face_normal: vec3<f32>,
    @location(3) albedo: vec3<f32>,
}

struct Varyings {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    // Flat: one face normal per triangle (every vertex of a triangle carries the same one).
    @location(2) @interpolate(flat) face_normal: vec3<f32>,
    @location(3) @interpolate(flat) albedo: vec3<f32>,
}

@vertex
fn vs_main(v: Vertex) -> Varyings {
    var out: Varyings;
    out.clip = camera.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.face_normal = v.face_normal;
    out.albedo = v.albedo;
    return out;
}

struct GBuffer {
    @location(0) normal: vec4<f32>,
    @location(1) face_normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
}

@fragment
fn fs_gbuffer(in: Varyings) -> GBuffer {
    var out: GBuffer;
    out.normal = vec4<f32>(in.normal, 0.0);
    out.face_normal = vec4<f32>(in.face_normal, 0.0);
    out.albedo = vec4<f32>(in.albedo, 1.0);
    return out;
}

// World position, w = 1 (the clear value's w = 0 marks pixels that see no geometry).
@fragment
fn fs_position(in: Varyings) -> @location(0) vec4<f32> {
    return vec4<f32>(in.world, 1.0);
}
