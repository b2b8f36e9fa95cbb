// A host's rasterized surface turned into a G-buffer texel, for the embedded shadow pass.
// Mirrors `src/contract/layout.rs` (SurfaceParams, ImageSize); a naga test checks sizes and offsets.

#import shared/layout

// How the host's G-buffer textures map to world space, 112 bytes.
struct SurfaceParams {
    clip_to_eye: mat4x4<f32>,    // bytes 0..64: inverse of the host's projection × view, moved by -eye
    eye: vec3<f32>,              // bytes 64..76: camera position, world space
    ray_offset: f32,             // bytes 76..80: shadow-ray origin offset along the normal
    width: u32,                  // bytes 80..84
    height: u32,                 // bytes 84..88
    background_depth: f32,       // bytes 88..92: depth texels equal to this see no geometry
    has_geo_normal: u32,         // bytes 92..96: 1 = the geometric-normal texture is the host's own
    origin: vec3<f32>,           // bytes 96..108: GpuScene::origin, which ray origins are relative to
    normal_encoding: u32,        // bytes 108..112: NORMALS_BIASED = stored as n * 0.5 + 0.5
}

// SurfaceParams::normal_encoding of textures that hold n * 0.5 + 0.5 (else: n itself).
const NORMALS_BIASED: u32 = 1u;

// An image size for the per-pixel kernels, 16 bytes.
struct ImageSize {
    width: u32,   // bytes 0..4
    height: u32,  // bytes 4..8
    pad0: u32,    // bytes 8..12
    pad1: u32,    // bytes 12..16
}

// Marks a texel hit by the host's rasterizer: no triangle index is known (GBufferTexel::UNKNOWN_TRIANGLE).
const UNKNOWN_TRIANGLE: u32 = 0xfffffffeu;

// Clip-space position of pixel (x, y)'s centre at depth `z` (row 0 at the top, wgpu's z in 0..1).
fn pixel_clip(params: SurfaceParams, pixel: vec2<u32>, z: f32) -> vec4<f32> {
    let sx = 2.0 * (f32(pixel.x) + 0.5) / f32(params.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(pixel.y) + 0.5) / f32(params.height);
    return vec4<f32>(sx, sy, z, 1.0);
}

// The normal a normal texture's texel `v` stores (twin: gbuffer_from_surface::decode_normal).
fn decode_normal(params: SurfaceParams, v: vec3<f32>) -> vec3<f32> {
    if params.normal_encoding == NORMALS_BIASED {
        return v * 2.0 - 1.0;
    }
    return v;
}

// `v` normalized, or `fallback` when `v` has no length (a host that wrote no normal).
fn unit_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let len2 = dot(v, v);
    if len2 > 0.0 && len2 < 3.0e38 {
        return v * inverseSqrt(len2);
    }
    return fallback;
}

// The texel of a surface point seen from the eye, as the primary pass would write it:
// normals flipped to the camera's side, the origin moved off the surface along the
// geometric normal (twin of reference::primary::primary_texel; albedo is the host's business).
fn surface_texel(params: SurfaceParams, point: vec3<f32>, shading: vec3<f32>, geometric: vec3<f32>) -> GBufferTexel {
    let dir = point - params.eye;
    let towards_eye = unit_or(-dir, vec3<f32>(0.0, 1.0, 0.0));
    var normal = unit_or(shading, towards_eye);
    var geo = unit_or(geometric, normal);
    if dot(geo, dir) > 0.0 {
        geo = -geo;
    }
    if dot(normal, dir) > 0.0 {
        normal = -normal;
    }
    var texel: GBufferTexel;
    // Offset at the world point (the host's rounding is the world's), then moved.
    texel.origin = shadow_ray_origin(point, geo, params.ray_offset) - params.origin;
    texel.depth = length(dir);
    texel.normal = normal;
    texel.triangle = UNKNOWN_TRIANGLE;
    texel.geo_normal = geo;
    return texel;
}

// The texel of a pixel that sees no geometry.
fn background_texel() -> GBufferTexel {
    var texel: GBufferTexel;
    texel.triangle = 0xffffffffu;
    return texel;
}
