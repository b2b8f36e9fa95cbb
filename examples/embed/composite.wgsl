// The example host's lighting pass: diffuse shading from the quad light's centre, times
// penumbra's filtered visibility, plus a little ambient light; linear radiance out.

struct Lighting {
    clip_to_world: mat4x4<f32>,
    eye: vec3<f32>,
    light_area: f32,
    light_center: vec3<f32>,
    ambient: f32,
    light_normal: vec3<f32>,  // unit, the emitting side
    width: f32,
    radiance: vec3<f32>,
    height: f32,
}

@group(0) @binding(0) var<uniform> lighting: Lighting;
@group(0) @binding(1) var depth_texture: texture_depth_2d;
@group(0) @binding(2) var normal_texture: texture_2d<f32>;
@group(0) @binding(3) var albedo_texture: texture_2d<f32>;
@group(0) @binding(4) var visibility_texture: texture_2d<f32>;

const PI: f32 = 3.14159265358979;
const SKY: vec3<f32> = vec3<f32>(0.05, 0.06, 0.08);

// One triangle that covers the screen.
@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(frag.xy);
    let z = textureLoad(depth_texture, pixel, 0);
    if z >= 1.0 {
        return vec4<f32>(SKY, 1.0);
    }
    let ndc = vec2<f32>(2.0 * frag.x / lighting.width - 1.0, 1.0 - 2.0 * frag.y / lighting.height);
    let world = lighting.clip_to_world * vec4<f32>(ndc, z, 1.0);
    let point = world.xyz / world.w;
    var n = normalize(textureLoad(normal_texture, pixel, 0).xyz);
    if dot(n, lighting.eye - point) < 0.0 {
        n = -n;
    }
    let albedo = textureLoad(albedo_texture, pixel, 0).rgb;
    let visibility = textureLoad(visibility_texture, pixel, 0).r;
    let w = lighting.light_center - point;
    let r2 = max(dot(w, w), 1e-12);
    let r = sqrt(r2);
    let cos_surface = max(dot(n, w) / r, 0.0);
    let cos_light = max(-dot(lighting.light_normal, w) / r, 0.0);
    let irradiance = lighting.radiance * (lighting.light_area * cos_surface * cos_light / r2);
    let radiance = albedo / PI * (irradiance * visibility + vec3<f32>(lighting.ambient));
    return vec4<f32>(radiance, 1.0);
}
