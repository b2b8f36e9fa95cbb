// The bindings, camera rays and G-buffer texels of the primary pass, shared by its kernels.
// Imported by shaders/primary.wgsl (per-ray) and shaders/primary_mft.wgsl, so both bind alike and write alike.

@group(0) @binding(0) var<uniform> camera: CameraParams;
// Bindings 1 (BVH nodes) and 2 (BVH triangles) are declared by each kernel, which also
// gives `hit_triangle(t)`: primary.wgsl as structs, primary_mft.wgsl as words.
@group(0) @binding(3) var<storage, read> shading: array<ShadingTriangle>;
@group(0) @binding(4) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(5) var<storage, read_write> gbuffer: array<GBufferTexel>;
// 8 words (shared/counters): [0] pixels whose rays ran out of loop iterations
// (the host reports an error), [1..6] the work counters, [6] rays (per-ray) or
// vectors (multi-frusta) whose loop the driver ended (an error too).
@group(0) @binding(6) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read> textures: array<GpuTexture>;
@group(0) @binding(8) var<storage, read> texels: array<vec4<f32>>;

// Below lavapipe's 65,535 loop iterations per invocation (all loops counted; besides the
// traversal loop there is only primary_mft's 16-iteration texel loop after it). Tests lower
// it to check the overflow report, and raise it past the limit to check that a loop the
// driver ends is reported (WORD_LOOP_CUT).
override ITERATION_BUDGET: u32 = 60000u;

// The camera ray direction through the centre of pixel (x, y); twin of frame::camera_ray.
fn pixel_dir(x: u32, y: u32) -> vec3<f32> {
    let sx = 2.0 * (f32(x + camera.origin_x) + 0.5) / f32(camera.image_width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(y + camera.origin_y) + 0.5) / f32(camera.image_height);
    return camera.forward + sx * camera.right + sy * camera.up;
}

// Base colour factor times the nearest texel (coordinates wrap); twin of ShadingData::albedo.
fn albedo(material: GpuMaterial, uv: vec2<f32>) -> vec3<f32> {
    if material.texture >= arrayLength(&textures) {
        return material.base_color;
    }
    let t = textures[material.texture];
    return material.base_color * texels[t.offset + texel_index(t.width, t.height, uv)].xyz;
}

// What the camera rays' alpha test needs of an alpha-tested triangle, read once for all
// the rays of a frustum: its texture coordinates, its material's alpha factor and cutoff,
// and where the base colour texture's texels are (`textured` false: none).
struct SurfaceAlpha {
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    factor: f32,
    cutoff: f32,
    textured: bool,
    offset: u32,
    width: u32,
    height: u32,
}

// The SurfaceAlpha of triangle `ix`.
fn surface_alpha(ix: u32) -> SurfaceAlpha {
    let sh = shading[ix];
    let m = materials[sh.material];
    let textured = m.texture < arrayLength(&textures);
    let t = textures[select(0u, m.texture, textured)];
    return SurfaceAlpha(sh.uv0, sh.uv1, sh.uv2, m.alpha_factor, m.alpha_cutoff, textured,
        t.offset, max(t.width, 1u), max(t.height, 1u));
}

// Whether a camera ray passes the surface `a` at its hit `h` = (t, u, v): where texel
// alpha × factor is below the cutoff. Branch-free; without a texture it reads texel 0 and
// ignores it (every storage buffer holds 16 bytes at least: buffers::MIN_BUFFER_BYTES).
fn surface_passes(a: SurfaceAlpha, h: vec3<f32>) -> bool {
    let uv = a.uv0 * (1.0 - h.y - h.z) + a.uv1 * h.y + a.uv2 * h.z;
    let texel = texels[select(0u, a.offset + texel_index(a.width, a.height, uv), a.textured)].w;
    return a.factor * select(1.0, texel, a.textured) < a.cutoff;
}

// Whether a camera ray passes triangle `ix` (`tri`) at its hit `h` = (t, u, v): only an
// alpha-tested triangle's surface can be absent, where texel alpha × factor is below the
// cutoff. The texels and materials are the shading's; the shadow kernels' bits
// (shared/alpha) are made from the same numbers. Twin: AlphaMasks::passes.
fn passes_alpha(tri: BvhTriangle, ix: u32, h: vec3<f32>) -> bool {
    if !ALPHA_TEST || tri.alpha == ALPHA_OPAQUE {
        return false;
    }
    return surface_passes(surface_alpha(ix), h);
}

// The texel of the camera ray from the eye along `dir` whose closest hit is
// triangle `best_tri` at `best` = (t, u, v), or of a miss (best_tri = 0xffffffff).
// Twin of reference::primary::hit_texel.
fn gbuffer_texel(best_tri: u32, best: vec3<f32>, dir: vec3<f32>) -> GBufferTexel {
    var texel: GBufferTexel;
    texel.triangle = 0xffffffffu;
    if best_tri != 0xffffffffu {
        let tri = hit_triangle(best_tri);
        let sh = shading[best_tri];
        var geo = normalize(cross(tri.v1 - tri.v0, tri.v2 - tri.v0));
        let w = 1.0 - best.y - best.z;
        let interpolated = sh.n0 * w + sh.n1 * best.y + sh.n2 * best.z;
        var normal = geo;
        if dot(interpolated, interpolated) > 0.0 {
            normal = normalize(interpolated);
        }
        if dot(geo, dir) > 0.0 {
            geo = -geo;
        }
        if dot(normal, dir) > 0.0 {
            normal = -normal;
        }
        let point = camera.eye + dir * best.x;
        let uv = sh.uv0 * w + sh.uv1 * best.y + sh.uv2 * best.z;
        texel.origin = shadow_ray_origin(point, geo, camera.ray_offset);
        texel.depth = best.x * length(dir);
        texel.normal = normal;
        texel.triangle = best_tri;
        texel.geo_normal = geo;
        texel.albedo = albedo(materials[sh.material], uv);
    }
    return texel;
}
