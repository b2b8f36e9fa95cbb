// Soft shadows through the driver's ray queries: every invocation traces one shadow ray with rayQueryProceed against the scene's TLAS, ending at the first hit.
// Dispatched by the shadow tracer (src/gpu/shadow_tracer.rs, Tracer::RayQuery) on devices with ray queries;
// CPU twin: none (the traversal is the driver's; tests/gpu/peers.rs holds its masks to the per-ray oracle's, like Embree's).
enable wgpu_ray_query;

#import shared/alpha
#import shared/bvh
#import shared/groups
#import shared/layout
#import shared/pixel_rays

@group(0) @binding(0) var<uniform> params: ShadowParams;
// One instance of the scene's triangles in leaf order, the identity transform (src/gpu/ray_query.rs).
@group(0) @binding(1) var scene_tlas: acceleration_structure;
@group(0) @binding(2) var<storage, read> gbuffer: array<GBufferTexel>;
@group(0) @binding(3) var<storage, read> light_points: array<vec4<f32>>;
// Cleared by the host before the dispatch; rays OR their bit into their pixel's word.
@group(0) @binding(4) var<storage, read_write> masks: array<atomic<u32>>;
// The triangles in leaf order (a candidate's primitive index) and the alpha words that
// shared/alpha reads: only for scenes with alpha-tested triangles are there candidates.
@group(0) @binding(5) var<storage, read> triangles: array<BvhTriangle>;
@group(0) @binding(6) var<storage, read> alpha: array<u32>;

@compute @workgroup_size(LINE_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let ray = start_pixel_ray(gid.x + gid.y * groups.x * LINE_GROUP);
    if !ray.live {
        return;
    }
    var blocked = ray.blocked;
    if !blocked {
        // In a scene without alpha-tested triangles the BLAS geometry is opaque, so the
        // first rayQueryProceed runs the whole traversal and commits the first hit it
        // finds, if any. With them it is not (src/gpu/ray_query.rs): each hit comes back as
        // a candidate, committed unless its triangle's mask lets the ray pass there
        // (barycentrics weigh corners 1 and 2). No culling: both faces block, as in the
        // per-ray oracle.
        var query: ray_query;
        rayQueryInitialize(
            &query,
            scene_tlas,
            RayDesc(RAY_FLAG_TERMINATE_ON_FIRST_HIT, 0xffu, 0.0, params.t_max, ray.origin, ray.dir)
        );
        while rayQueryProceed(&query) {
            let c = rayQueryGetCandidateIntersection(&query);
            let b = c.barycentrics;
            if !alpha_passes(triangles[c.primitive_index].alpha, vec3<f32>(1.0 - b.x - b.y, b.x, b.y)) {
                rayQueryConfirmIntersection(&query);
            }
        }
        blocked = rayQueryGetCommittedIntersection(&query).kind != RAY_QUERY_INTERSECTION_NONE;
    }
    if blocked {
        record_blocked(ray);
    }
}
