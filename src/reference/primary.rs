//! CPU twin of the primary pass (`shaders/primary.wgsl`): one closest-hit
//! camera ray per pixel, written as a G-buffer texel.

use crate::bvh::Bvh;
use crate::frame::{ShadingData, camera_ray};
use crate::layout::{CameraParams, GBufferTexel};
use crate::reference::closest_hit;

/// The G-buffer texel of pixel `(x, y)`.
///
/// Normals are flipped to the side the camera ray comes from (a back face
/// seen by the camera is lit like a front face); the shadow-ray origin is
/// the hit point moved `ray_offset` along the flipped geometric normal.
pub fn primary_texel(bvh: &Bvh, shading: &ShadingData, cam: &CameraParams, x: u32, y: u32) -> GBufferTexel {
    let dir = camera_ray(cam, x, y);
    let Some(hit) = closest_hit(bvh, cam.eye, dir, f32::INFINITY) else {
        return GBufferTexel {
            triangle: u32::MAX,
            ..Default::default()
        };
    };
    let tri = &bvh.triangles[hit.triangle as usize];
    let sh = &shading.triangles[hit.triangle as usize];
    let mut geo = tri.e1.cross(tri.e2).normalize();
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
        origin: point + geo * cam.ray_offset,
        depth: hit.t * dir.length(),
        normal,
        triangle: hit.triangle,
        geo_normal: geo,
        pad0: 0,
        albedo: shading.albedo(sh.material, uv),
        pad1: 0,
    }
}

/// The whole G-buffer (row-major, row 0 at the top), rows spread over all cores.
pub fn primary_gbuffer(bvh: &Bvh, shading: &ShadingData, cam: &CameraParams) -> Vec<GBufferTexel> {
    let w = cam.width as usize;
    super::parallel::per_pixel(w, cam.height as usize, |p| {
        primary_texel(bvh, shading, cam, (p % w) as u32, (p / w) as u32)
    })
}
