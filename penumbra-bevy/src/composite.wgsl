// penumbra-bevy's composite: adds one quad light's diffuse light, times penumbra's filtered
// visibility, to a Bevy camera's HDR target (additive blending), after Bevy's main pass.
// Recorded by composite.rs once per light and view. Light from an unoccluded polygon is
// exact (Lambert's edge sum); visibility is the fraction of the light's samples a pixel
// sees (penumbra's 16 rays and filter), so the product is the usual ratio estimate.

struct Params {
    world_from_clip: mat4x4<f32>,
    corner: vec3<f32>,
    has_visibility: u32,
    edge_u: vec3<f32>,
    width: f32,
    edge_v: vec3<f32>,
    height: f32,
    // Light radiance x albedo / pi x the camera's exposure, linear RGB.
    scale: vec3<f32>,
    pad: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var depth_texture: texture_depth_2d;
// Bevy's normal prepass: world-space normal stored as n * 0.5 + 0.5.
@group(0) @binding(2) var normal_texture: texture_2d<f32>;
@group(0) @binding(3) var visibility_texture: texture_2d<f32>;

const PI: f32 = 3.14159265358979;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// Integral of max(0, n . w) over the quad's solid angle seen from p, for the light's
// front side only: pi x its form factor when the whole quad is above p's tangent plane.
fn projected_solid_angle(p: vec3<f32>, n: vec3<f32>) -> f32 {
    let facing = cross(params.edge_u, params.edge_v);
    if dot(facing, p - params.corner) <= 0.0 {
        return 0.0;
    }
    var c: array<vec3<f32>, 4>;
    c[0] = normalize(params.corner - p);
    c[1] = normalize(params.corner + params.edge_u - p);
    c[2] = normalize(params.corner + params.edge_u + params.edge_v - p);
    c[3] = normalize(params.corner + params.edge_v - p);
    var sum = 0.0;
    for (var i = 0u; i < 4u; i++) {
        let a = c[i];
        let b = c[(i + 1u) % 4u];
        let axis = cross(a, b);
        let len = length(axis);
        if len > 1e-7 {
            sum += atan2(len, dot(a, b)) * dot(n, axis / len);
        }
    }
    // The corners wind clockwise as seen from the front side: the edge sum is negative there.
    return max(0.0, -0.5 * sum);
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(frag.xy);
    let z = textureLoad(depth_texture, pixel, 0);
    if z == 0.0 {
        return vec4<f32>(0.0);
    }
    let ndc = vec2<f32>(2.0 * frag.x / params.width - 1.0, 1.0 - 2.0 * frag.y / params.height);
    let h = params.world_from_clip * vec4<f32>(ndc, z, 1.0);
    let p = h.xyz / h.w;
    let n = normalize(textureLoad(normal_texture, pixel, 0).xyz * 2.0 - 1.0);
    var visibility = 1.0;
    if params.has_visibility != 0u {
        visibility = textureLoad(visibility_texture, pixel, 0).x;
    }
    return vec4<f32>(params.scale * projected_solid_angle(p, n) * visibility, 0.0);
}
