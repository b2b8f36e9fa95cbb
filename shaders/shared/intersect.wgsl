// Ray-box and ray-triangle tests, the WGSL twins of src/reference/intersect.rs.
// Imported by the per-ray kernels (primary pass).

// 1 + 2*gamma(3): makes the f32 slab test conservative (Ize 2013).
const BOX_EXIT_SCALE: f32 = 1.0000003576278687;

fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = 1e-30;
    let fixed = select(d, select(vec3<f32>(tiny), vec3<f32>(-tiny), d < vec3<f32>(0.0)), abs(d) < vec3<f32>(tiny));
    return vec3<f32>(1.0) / fixed;
}

// Entry distance into the box within [0, t_max], or -1 for a miss.
fn intersect_box(origin: vec3<f32>, inv_dir: vec3<f32>, node: BvhNode, t_max: f32) -> f32 {
    let t0 = (node.bmin - origin) * inv_dir;
    let t1 = (node.bmax - origin) * inv_dir;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    let t_near = max(max(max(lo.x, lo.y), lo.z), 0.0);
    let t_far = min(min(min(hi.x, hi.y), hi.z), t_max) * BOX_EXIT_SCALE;
    return select(-1.0, t_near, t_near <= t_far);
}

// Moller-Trumbore: (t, u, v) of a hit with 0 < t < t_max, or t = -1. Not watertight:
// a ray through a shared edge can miss both triangles (see reference::intersect).
fn intersect_triangle(tri: BvhTriangle, origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> vec3<f32> {
    let miss = vec3<f32>(-1.0, 0.0, 0.0);
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let p = cross(dir, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return miss;
    }
    let inv_det = 1.0 / det;
    let s = origin - tri.v0;
    let u = dot(s, p) * inv_det;
    if u < 0.0 || u > 1.0 {
        return miss;
    }
    let q = cross(s, e1);
    let v = dot(dir, q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return miss;
    }
    let t = dot(e2, q) * inv_det;
    if t > 0.0 && t < t_max {
        return vec3<f32>(t, u, v);
    }
    return miss;
}

// The barycentric weights (corners 0, 1, 2) of a Moller-Trumbore hit (t, u, v).
fn hit_weights(h: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(1.0 - h.y - h.z, h.y, h.z);
}
