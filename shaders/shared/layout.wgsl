// The per-pixel structs and mask words the primary, shadow and shade passes share, and two
// per-pixel formulas they all use (the shadow-ray origin, the unshadowed irradiance).
// Mirrors `src/contract/layout.rs` (GBufferTexel, ShadowParams); a naga test checks sizes and offsets.

// Shadow mask words: bit j = ray j blocked (MASK_FULL: all 16), MASK_SKY = the pixel
// sees no geometry (src/contract/shadow.rs, checked by a naga test).
const MASK_FULL: u32 = 0xffffu;
const MASK_SKY: u32 = 0x10000u;

// One G-buffer pixel, 64 bytes.
struct GBufferTexel {
    origin: vec3<f32>,      // bytes 0..12: shadow-ray origin (hit point moved off the surface)
    depth: f32,             // bytes 12..16: eye-to-hit distance; 0 = no hit
    normal: vec3<f32>,      // bytes 16..28: unit shading normal, camera side
    triangle: u32,          // bytes 28..32: leaf-order triangle index, 0xffffffff = none
    geo_normal: vec3<f32>,  // bytes 32..44: unit geometric normal, camera side
    pad0: u32,              // bytes 44..48
    albedo: vec3<f32>,      // bytes 48..60: linear RGB
    pad1: u32,              // bytes 60..64
}

// Shadow-pass parameters, 112 bytes.
struct ShadowParams {
    light_corners: array<vec4<f32>, 4>,  // bytes 0..64: c, c+u, c+u+v, c+v
    light_normal: vec3<f32>,             // bytes 64..76: cross(u, v), the emitting side
    t_max: f32,                          // bytes 76..80: shadow rays cover t in (0, t_max)
    width: u32,                          // bytes 80..84
    height: u32,                         // bytes 84..88
    tile_origin_x: u32,                  // bytes 88..92: first 4x4 tile of the dispatch
    tile_origin_y: u32,                  // bytes 92..96
    tiles_x: u32,                        // bytes 96..100: tiles per row of the dispatch
    resume: u32,                         // bytes 100..104: 1 = resume suspended tiles
    iteration_budget: u32,               // bytes 104..108: loop iterations before suspending
    tiles_y: u32,                        // bytes 108..112: tile rows of the dispatch
}

// Shading data of one triangle (leaf order, like BvhTriangle), 80 bytes.
struct ShadingTriangle {
    n0: vec3<f32>,     // bytes 0..12: unit shading normal at corner 0
    material: u32,     // bytes 12..16: index into the materials
    n1: vec3<f32>,     // bytes 16..28
    pad1: u32,         // bytes 28..32
    n2: vec3<f32>,     // bytes 32..44
    pad2: u32,         // bytes 44..48
    uv0: vec2<f32>,    // bytes 48..56: TEXCOORD_0 at corner 0
    uv1: vec2<f32>,    // bytes 56..64
    uv2: vec2<f32>,    // bytes 64..72
    pad3: array<u32, 2>,  // bytes 72..80
}

// One material, 32 bytes.
struct GpuMaterial {
    base_color: vec3<f32>,  // bytes 0..12: linear RGB factor
    texture: u32,           // bytes 12..16: base colour texture, 0xffffffff = none
    alpha_factor: f32,      // bytes 16..20: the base colour factor's alpha
    alpha_cutoff: f32,      // bytes 20..24: alpha-tested triangles are absent where alpha is below
    pad: array<u32, 2>,     // bytes 24..32
}

// The texture coordinates of an alpha-tested triangle and its mask, 32 bytes, at
// BvhTriangle.alpha in the alpha words (shared/alpha reads them word by word).
struct AlphaTriangle {
    uv0: vec2<f32>,  // bytes 0..8: TEXCOORD_0 at corner 0
    uv1: vec2<f32>,  // bytes 8..16
    uv2: vec2<f32>,  // bytes 16..24
    mask: u32,       // bytes 24..28: word offset of its AlphaMask
    pad: u32,        // bytes 28..32
}

// One material's coverage, 16 bytes: a bit per texel, set where the surface blocks.
struct AlphaMask {
    width: u32,   // bytes 0..4
    height: u32,  // bytes 4..8
    bits: u32,    // bytes 8..12: word offset of the first bit word
    pad: u32,     // bytes 12..16
}

// BvhTriangle.alpha of a triangle that always blocks (contract::alpha::OPAQUE).
const ALPHA_OPAQUE: u32 = 0u;
// Whether the tracing kernels test alpha masks at all: false for scenes without
// alpha-tested triangles, so that the driver drops the test's code (gpu::AlphaKernels).
override ALPHA_TEST: bool = false;

// The texel nearest to `uv` (coordinates wrap), row-major; twin of contract::alpha::texel_index.
fn texel_index(width: u32, height: u32, uv: vec2<f32>) -> u32 {
    let u = uv.x - floor(uv.x);
    let v = uv.y - floor(uv.y);
    let x = min(u32(u * f32(width)), width - 1u);
    let y = min(u32(v * f32(height)), height - 1u);
    return y * width + x;
}

// Where a texture's linear RGBA texels are in the texel buffer, 16 bytes.
struct GpuTexture {
    offset: u32,  // bytes 0..4: first texel
    width: u32,   // bytes 4..8
    height: u32,  // bytes 8..12
    pad: u32,     // bytes 12..16
}

// The pinhole camera, 64 bytes: ray = eye + t * (forward + sx * right + sy * up).
struct CameraParams {
    eye: vec3<f32>,      // bytes 0..12
    width: u32,          // bytes 12..16
    forward: vec3<f32>,  // bytes 16..28
    height: u32,         // bytes 28..32
    right: vec3<f32>,    // bytes 32..44: scaled by tan(fov/2) * aspect
    ray_offset: f32,     // bytes 44..48: shadow-ray origin offset from the surface
    up: vec3<f32>,       // bytes 48..60: scaled by tan(fov/2)
    pad: u32,            // bytes 60..64
    // The whole image the projection is for; width and height above are the
    // tile's, whose top-left pixel is (origin_x, origin_y) of the image.
    image_width: u32,    // bytes 64..68
    image_height: u32,   // bytes 68..72
    origin_x: u32,       // bytes 72..76
    origin_y: u32,       // bytes 76..80
}

// The light as the shade pass sees it, 48 bytes.
struct ShadeParams {
    light_center: vec3<f32>,  // bytes 0..12
    light_area: f32,          // bytes 12..16
    light_normal: vec3<f32>,  // bytes 16..28: unit, emitting side
    width: u32,               // bytes 28..32
    radiance: vec3<f32>,      // bytes 32..44: colour * intensity
    height: u32,              // bytes 44..48
}

// Shadow-ray origins leave the surface along `normal` by the scene's `ray_offset` (a
// fraction of its size) or by this many steps of f32 at the point's largest coordinate,
// whichever is larger: far from the origin the hit point itself is only known to a step
// or two, and a fixed offset below that lets rays hit their own surface. Twin:
// contract::layout::ORIGIN_OFFSET_ULPS (a test checks they agree).
const ORIGIN_OFFSET_ULPS: f32 = 4.0;

// The shadow-ray origin of the surface point `point`; twin of pass_inputs::shadow_ray_origin.
fn shadow_ray_origin(point: vec3<f32>, normal: vec3<f32>, ray_offset: f32) -> vec3<f32> {
    let m = max(max(abs(point.x), abs(point.y)), abs(point.z));
    // The spacing of f32 values at m: 2^(m's exponent) * 2^-23.
    let ulp = bitcast<f32>(bitcast<u32>(m) & 0x7f800000u) * (1.0 / 8388608.0);
    return point + normal * max(ray_offset, ORIGIN_OFFSET_ULPS * ulp);
}

// Irradiance from the light treated as a point at its centre, with its area and both
// cosines, before shadowing; the shade pass and refine_trace multiply it by the visible
// fraction. CPU twin: reference::shade::unshadowed_irradiance.
fn unshadowed_irradiance(light: ShadeParams, texel: GBufferTexel) -> vec3<f32> {
    let w = light.light_center - texel.origin;
    let r2 = max(dot(w, w), 1e-12);
    let r = sqrt(r2);
    let cos_surface = max(dot(texel.normal, w) / r, 0.0);
    let cos_light = max(-dot(light.light_normal, w) / r, 0.0);
    return light.radiance * (light.light_area * cos_surface * cos_light / r2);
}
