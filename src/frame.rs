//! CPU-side preparation of what the frame's passes read: the camera, the
//! shading data in leaf order and the materials.

use glam::Vec3;

use crate::bvh::Bvh;
use crate::layout::{CameraParams, GpuMaterial, ShadingTriangle};
use crate::scene::Scene;
use crate::view::Camera;

/// Shadow-ray origins leave the surface by this fraction of the scene's
/// diagonal: large enough to clear f32 rounding of the hit point, small
/// enough not to open gaps at contacts (10⁻⁴ of 10 m is 1 mm).
pub const RAY_OFFSET_FRACTION: f32 = 1e-4;

/// The camera for a `width`×`height` image (square pixels).
pub fn camera_params(camera: &Camera, width: u32, height: u32, ray_offset: f32) -> CameraParams {
    let forward = (camera.target - camera.eye).normalize();
    let right = forward.cross(camera.up).normalize();
    let up = right.cross(forward);
    let tan = (camera.fov_y_degrees.to_radians() * 0.5).tan();
    let aspect = width as f32 / height as f32;
    CameraParams {
        eye: camera.eye,
        width,
        forward,
        height,
        right: right * (tan * aspect),
        ray_offset,
        up: up * tan,
        pad: 0,
    }
}

/// The unnormalised direction of the camera ray through pixel `(x, y)`; the
/// WGSL primary kernel computes the same expression.
pub fn camera_ray(cam: &CameraParams, x: u32, y: u32) -> Vec3 {
    let sx = 2.0 * (x as f32 + 0.5) / cam.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (y as f32 + 0.5) / cam.height as f32;
    cam.forward + sx * cam.right + sy * cam.up
}

/// Shading data of every BVH triangle, in the BVH's leaf order.
pub fn shading_triangles(scene: &Scene, bvh: &Bvh) -> Vec<ShadingTriangle> {
    bvh.triangles
        .iter()
        .map(|t| {
            let s = &scene.triangles[t.scene_index as usize];
            ShadingTriangle {
                n0: s.normals[0],
                material: s.material,
                n1: s.normals[1],
                pad1: 0,
                n2: s.normals[2],
                pad2: 0,
            }
        })
        .collect()
}

/// The scene's materials as the primary pass reads them.
pub fn gpu_materials(scene: &Scene) -> Vec<GpuMaterial> {
    scene
        .materials
        .iter()
        .map(|m| GpuMaterial {
            base_color: Vec3::new(
                m.base_color_factor[0],
                m.base_color_factor[1],
                m.base_color_factor[2],
            ),
            pad: 0,
        })
        .collect()
}
