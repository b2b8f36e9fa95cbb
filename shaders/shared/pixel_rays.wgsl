// Which shadow ray an invocation of a one-ray-per-invocation tracer (per-ray, ray-query) traces,
// and how its answer reaches the pixel's mask word; imported by shadow_per_ray and shadow_ray_query.
// It reads the importing kernel's `params`, `gbuffer`, `light_points` and `masks` bindings.
// CPU twin of its rules: src/reference/shadow_per_ray.rs (initial_mask, per_ray_masks).

#import shared/layout

// 16: the pixel's ray j goes to point j of its interleaved set (x mod 4 + 4 (y mod 4)),
// and bit j of its mask is set when it is blocked. Otherwise ("reference"): ray j goes
// to point j of one set of RAYS_PER_PIXEL points shared by every pixel, and the
// pixel's word counts its blocked rays (below MASK_SKY: at most 65,535 rays).
override RAYS_PER_PIXEL: u32 = 16u;

// Ray j of pixel `pixel`: from the G-buffer texel's origin to its light point (t in 0..1).
struct PixelRay {
    pixel: u32,
    j: u32,
    origin: vec3<f32>,
    dir: vec3<f32>,
    // False: nothing to trace (past the image's last pixel, or a sky pixel, whose
    // MASK_SKY this call has set).
    live: bool,
    // Blocked without tracing: the texel lies behind the light, or the light behind the
    // texel's own surface (same rules as reference::shadow_per_ray::initial_mask).
    blocked: bool,
}

// The ray of invocation `index` of a dispatch over the chunk `params` describes, lanes of
// one pixel next to each other; marks sky pixels.
fn start_pixel_ray(index: u32) -> PixelRay {
    var ray: PixelRay;
    let slot = index / RAYS_PER_PIXEL;
    ray.j = index % RAYS_PER_PIXEL;
    if slot >= params.tiles_x * params.tiles_y {
        return ray;
    }
    let x = params.tile_origin_x + slot % params.tiles_x;
    let y = params.tile_origin_y + slot / params.tiles_x;
    ray.pixel = y * params.width + x;
    let texel = gbuffer[ray.pixel];
    if texel.depth <= 0.0 {
        if ray.j == 0u {
            atomicOr(&masks[ray.pixel], MASK_SKY);
        }
        return ray;
    }
    let point = select(ray.j, ((x & 3u) + 4u * (y & 3u)) * 16u + ray.j, RAYS_PER_PIXEL == 16u);
    ray.origin = texel.origin;
    ray.dir = light_points[point].xyz - texel.origin;
    ray.live = true;
    ray.blocked = dot(params.light_normal, texel.origin - params.light_corners[0].xyz) <= 0.0
        || dot(texel.geo_normal, ray.dir) <= 0.0;
    return ray;
}

// Records that `ray` is blocked: its bit of the pixel's mask, or one more in its count.
fn record_blocked(ray: PixelRay) {
    if RAYS_PER_PIXEL == 16u {
        atomicOr(&masks[ray.pixel], 1u << ray.j);
    } else {
        atomicAdd(&masks[ray.pixel], 1u);
    }
}
