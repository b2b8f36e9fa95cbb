//! CPU twin of the per-ray primary kernel (`shaders/primary.wgsl`): one
//! closest-hit camera ray per pixel, written as a G-buffer texel.

use glam::Vec3;

use super::traverse::closest_hit_counted;
use crate::bvh::Bvh;
use crate::contract::counters::Counters;
use crate::contract::layout::{CameraParams, GBufferTexel};
use crate::pass_inputs::{ShadingData, camera_ray};
use crate::reference::Hit;

/// The G-buffer texel of the camera ray from `cam.eye` along `dir` whose
/// closest hit is `hit` (`None`: a miss); twin of WGSL `gbuffer_texel`.
///
/// Normals are flipped to the side the camera ray comes from (a back face
/// seen by the camera is lit like a front face); the shadow-ray origin is
/// the hit point moved off the surface along the flipped geometric normal
/// ([`crate::pass_inputs::shadow_ray_origin`]).
pub fn hit_texel(
    bvh: &Bvh,
    shading: &ShadingData,
    cam: &CameraParams,
    dir: Vec3,
    hit: Option<Hit>,
) -> GBufferTexel {
    let Some(hit) = hit else {
        return GBufferTexel {
            triangle: u32::MAX,
            ..Default::default()
        };
    };
    let tri = &bvh.triangles[hit.triangle as usize];
    let sh = &shading.triangles[hit.triangle as usize];
    let mut geo = (tri.v1 - tri.v0).cross(tri.v2 - tri.v0).normalize();
    let w = 1.0 - hit.u - hit.v;
    let mut normal = (sh.n0 * w + sh.n1 * hit.u + sh.n2 * hit.v).normalize_or(geo);
    if geo.dot(dir) > 0.0 {
        geo = -geo;
    }
    if normal.dot(dir) > 0.0 {
        normal = -normal;
    }
    let point = cam.eye + dir * hit.t;
    let uv = sh.uv0 * w + sh.uv1 * hit.u + sh.uv2 * hit.v;
    GBufferTexel {
        origin: crate::pass_inputs::shadow_ray_origin(point, geo, cam.ray_offset),
        depth: hit.t * dir.length(),
        normal,
        triangle: hit.triangle,
        geo_normal: geo,
        pad0: 0,
        albedo: shading.albedo(sh.material, uv),
        pad1: 0,
    }
}

/// The G-buffer texel of pixel `(x, y)`, and the work its ray did.
pub fn primary_texel_counted(
    bvh: &Bvh,
    shading: &ShadingData,
    cam: &CameraParams,
    x: u32,
    y: u32,
) -> (GBufferTexel, Counters) {
    let dir = camera_ray(cam, x, y);
    let mut counters = Counters::default();
    // f32::MAX like the kernel's initial t_best (no hit can reach it anyway).
    let hit = closest_hit_counted(bvh, cam.eye, dir, f32::MAX, &mut counters);
    (hit_texel(bvh, shading, cam, dir, hit), counters)
}

/// The G-buffer texel of pixel `(x, y)`.
pub fn primary_texel(bvh: &Bvh, shading: &ShadingData, cam: &CameraParams, x: u32, y: u32) -> GBufferTexel {
    primary_texel_counted(bvh, shading, cam, x, y).0
}

/// The whole G-buffer (row-major, row 0 at the top), rows spread over all cores.
pub fn primary_gbuffer(bvh: &Bvh, shading: &ShadingData, cam: &CameraParams) -> Vec<GBufferTexel> {
    primary_gbuffer_counted(bvh, shading, cam).0
}

/// [`primary_gbuffer`] and the work of all its rays, counted as the per-ray
/// kernel counts it with `COUNTERS` on (see [`crate::contract::counters`]).
pub fn primary_gbuffer_counted(
    bvh: &Bvh,
    shading: &ShadingData,
    cam: &CameraParams,
) -> (Vec<GBufferTexel>, Counters) {
    let w = cam.width as usize;
    let per_pixel = super::parallel::per_pixel(w, cam.height as usize, |p| {
        primary_texel_counted(bvh, shading, cam, (p % w) as u32, (p / w) as u32)
    });
    let mut total = Counters::default();
    let texels = per_pixel
        .into_iter()
        .map(|(texel, c)| {
            total += c;
            texel
        })
        .collect();
    (texels, total)
}
