// Primary visibility: one closest-hit camera ray per pixel, written as a G-buffer texel.
// Dispatched by the renderer (src/gpu/render.rs); CPU twin: src/reference/primary.rs.

#import shared/bvh
#import shared/frame
#import shared/intersect

// Pushes both children of a node: the stack holds at most depth + 1 entries.
const STACK_SIZE: u32 = 64u;
// Below lavapipe's 65,535 loop iterations per invocation (all loops counted).
const ITERATION_LIMIT: u32 = 60000u;

@group(0) @binding(0) var<uniform> camera: CameraParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> triangles: array<BvhTriangle>;
@group(0) @binding(3) var<storage, read> shading: array<ShadingTriangle>;
@group(0) @binding(4) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(5) var<storage, read_write> gbuffer: array<GBufferTexel>;
// [0]: pixels whose ray ran out of iterations (the host reports an error).
@group(0) @binding(6) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read> textures: array<GpuTexture>;
@group(0) @binding(8) var<storage, read> texels: array<vec4<f32>>;

// Base colour factor times the nearest texel (coordinates wrap); twin of ShadingData::albedo.
fn albedo(material: GpuMaterial, uv: vec2<f32>) -> vec3<f32> {
    if material.texture >= arrayLength(&textures) {
        return material.base_color;
    }
    let t = textures[material.texture];
    let u = uv.x - floor(uv.x);
    let v = uv.y - floor(uv.y);
    let x = min(u32(u * f32(t.width)), t.width - 1u);
    let y = min(u32(v * f32(t.height)), t.height - 1u);
    return material.base_color * texels[t.offset + y * t.width + x].xyz;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= camera.width || gid.y >= camera.height {
        return;
    }
    let sx = 2.0 * (f32(gid.x) + 0.5) / f32(camera.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(gid.y) + 0.5) / f32(camera.height);
    let dir = camera.forward + sx * camera.right + sy * camera.up;
    let origin = camera.eye;
    let inv_dir = safe_inverse(dir);

    var best = vec3<f32>(-1.0, 0.0, 0.0);
    var best_tri = 0xffffffffu;
    var t_best = 3.4028234663852886e38;
    var stack: array<u32, 64>;
    var depth = 0u;
    var cursor = 0u;  // next triangle of the current leaf
    var end = 0u;     // end of the current leaf's triangles
    if intersect_box(origin, inv_dir, nodes[0], t_best) >= 0.0 {
        stack[0] = 0u;
        depth = 1u;
    }
    // One loop, one step per iteration (a leaf triangle or a node): lavapipe
    // counts iterations of every loop an iteration reaches, nested ones too,
    // so a nested leaf loop would let its limit strike before ours.
    var iterations = 0u;
    loop {
        if cursor >= end && depth == 0u {
            break;
        }
        iterations += 1u;
        if iterations > ITERATION_LIMIT {
            atomicAdd(&status[0], 1u);
            break;
        }
        if cursor < end {
            let h = intersect_triangle(triangles[cursor], origin, dir, t_best);
            if h.x >= 0.0 {
                t_best = h.x;
                best = h;
                best_tri = cursor;
            }
            cursor += 1u;
            continue;
        }
        depth -= 1u;
        let node = nodes[stack[depth]];
        if node.count > 0u {
            cursor = node.first;
            end = node.first + node.count;
            continue;
        }
        let l = node.first;
        let tl = intersect_box(origin, inv_dir, nodes[l], t_best);
        let tr = intersect_box(origin, inv_dir, nodes[l + 1u], t_best);
        if tl >= 0.0 && tr >= 0.0 {
            // Farther child below, nearer on top.
            let near_left = tl <= tr;
            stack[min(depth, STACK_SIZE - 1u)] = select(l, l + 1u, near_left);
            stack[min(depth + 1u, STACK_SIZE - 1u)] = select(l + 1u, l, near_left);
            depth += 2u;
        } else if tl >= 0.0 {
            stack[min(depth, STACK_SIZE - 1u)] = l;
            depth += 1u;
        } else if tr >= 0.0 {
            stack[min(depth, STACK_SIZE - 1u)] = l + 1u;
            depth += 1u;
        }
    }

    var texel: GBufferTexel;
    texel.triangle = 0xffffffffu;
    if best_tri != 0xffffffffu {
        let tri = triangles[best_tri];
        let sh = shading[best_tri];
        var geo = normalize(cross(tri.e1, tri.e2));
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
        let point = origin + dir * best.x;
        let uv = sh.uv0 * w + sh.uv1 * best.y + sh.uv2 * best.z;
        texel.origin = point + geo * camera.ray_offset;
        texel.depth = best.x * length(dir);
        texel.normal = normal;
        texel.triangle = best_tri;
        texel.geo_normal = geo;
        texel.albedo = albedo(materials[sh.material], uv);
    }
    gbuffer[gid.y * camera.width + gid.x] = texel;
}
