//! CPU twin of the embedded pass's G-buffer kernels (`shaders/gbuffer_from_depth.wgsl`,
//! `shaders/gbuffer_from_position.wgsl`): a host's rasterized surface point and normals
//! turned into the [`GBufferTexel`] the shadow kernel reads, the way the primary pass
//! makes one from a ray hit ([`super::primary::primary_texel`]).

use glam::{Mat4, Vec3, Vec4};

use crate::contract::layout::{GBufferTexel, NORMALS_BIASED, SurfaceParams};

/// Clip-space position of pixel `(x, y)`'s centre at depth `z` (row 0 at the top,
/// wgpu's depth range 0..1): the sample point a rasterizer uses for that pixel.
pub fn pixel_clip(params: &SurfaceParams, x: u32, y: u32, z: f32) -> Vec4 {
    let sx = 2.0 * (x as f32 + 0.5) / params.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (y as f32 + 0.5) / params.height as f32;
    Vec4::new(sx, sy, z, 1.0)
}

/// World position of pixel `(x, y)` whose depth texel is `z`: the eye plus the
/// unprojected point relative to it (the kernel's arithmetic).
pub fn unproject(params: &SurfaceParams, x: u32, y: u32, z: f32) -> Vec3 {
    let relative = Mat4::from_cols_array_2d(&params.clip_to_eye) * pixel_clip(params, x, y, z);
    params.eye + relative.truncate() / relative.w
}

/// The normal a normal texture's texel `v` (its xyz) stores, as
/// [`SurfaceParams::normal_encoding`] says: `v` itself, or `2v − 1` for
/// [`NORMALS_BIASED`].
pub fn decode_normal(params: &SurfaceParams, v: Vec3) -> Vec3 {
    if params.normal_encoding == NORMALS_BIASED {
        v * 2.0 - Vec3::ONE
    } else {
        v
    }
}

/// `v` normalized, or `fallback` when `v` has no (finite) length.
fn unit_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let len2 = v.length_squared();
    if len2 > 0.0 && len2 < 3.0e38 {
        v / len2.sqrt()
    } else {
        fallback
    }
}

/// The texel of surface point `point` with the host's `shading` and `geometric`
/// normals (any length): both flipped to the camera's side, the shadow-ray origin
/// moved off the surface along the geometric normal ([`crate::pass_inputs::shadow_ray_origin`])
/// and made relative to `params.origin`, `depth` the eye distance. A zero
/// geometric normal falls back to the shading normal, a zero shading normal to the
/// direction towards the eye. Albedo is left 0: the host shades.
pub fn surface_texel(params: &SurfaceParams, point: Vec3, shading: Vec3, geometric: Vec3) -> GBufferTexel {
    let dir = point - params.eye;
    let towards_eye = unit_or(-dir, Vec3::Y);
    let mut normal = unit_or(shading, towards_eye);
    let mut geo = unit_or(geometric, normal);
    if geo.dot(dir) > 0.0 {
        geo = -geo;
    }
    if normal.dot(dir) > 0.0 {
        normal = -normal;
    }
    GBufferTexel {
        origin: crate::pass_inputs::shadow_ray_origin(point, geo, params.ray_offset) - params.origin,
        depth: dir.length(),
        normal,
        triangle: GBufferTexel::UNKNOWN_TRIANGLE,
        geo_normal: geo,
        ..Default::default()
    }
}

/// The texel of a pixel that sees no geometry.
pub fn background_texel() -> GBufferTexel {
    GBufferTexel {
        triangle: u32::MAX,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> SurfaceParams {
        let view = glam::camera::rh::view::look_at_mat4(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y);
        let proj = glam::camera::rh::proj::directx::perspective(1.0, 2.0, 0.1, 100.0);
        SurfaceParams {
            clip_to_eye: (Mat4::from_translation(-Vec3::new(0.0, 0.0, 5.0)) * (proj * view).inverse())
                .to_cols_array_2d(),
            eye: Vec3::new(0.0, 0.0, 5.0),
            ray_offset: 0.01,
            width: 8,
            height: 4,
            background_depth: 1.0,
            has_geo_normal: 1,
            ..Default::default()
        }
    }

    #[test]
    fn biased_normals_decode_to_signed_ones_and_signed_ones_pass_unchanged() {
        let mut p = params();
        let n = Vec3::new(0.6, -0.8, 0.0);
        assert_eq!(decode_normal(&p, n), n);
        p.normal_encoding = NORMALS_BIASED;
        // 0.8, 0.1, 0.5 are n · ½ + ½; the decode is exact in f32 for these values.
        assert_eq!(
            decode_normal(&p, Vec3::new(0.8, 0.1, 0.5)),
            Vec3::new(0.6, -0.8, 0.0)
        );
    }

    #[test]
    fn unprojecting_a_projected_point_gives_it_back() {
        let p = params();
        let view_proj = (Mat4::from_translation(p.eye) * Mat4::from_cols_array_2d(&p.clip_to_eye)).inverse();
        // The centre of pixel (5, 1) on the plane z = 0.
        let world = unproject(&p, 5, 1, 0.5);
        let ray = (world - p.eye).normalize();
        let on_plane = p.eye + ray * (p.eye.z / -ray.z);
        let clip = view_proj * on_plane.extend(1.0);
        let back = unproject(&p, 5, 1, clip.z / clip.w);
        assert!((back - on_plane).length() < 1e-4, "{back} vs {on_plane}");
        let ndc = clip.truncate() / clip.w;
        assert!((ndc.x - (2.0 * 5.5 / 8.0 - 1.0)).abs() < 1e-5);
        assert!((ndc.y - (1.0 - 2.0 * 1.5 / 4.0)).abs() < 1e-5);
    }

    #[test]
    fn normals_face_the_camera_and_the_origin_leaves_the_surface() {
        let p = params();
        let point = Vec3::new(0.5, 0.0, 0.0);
        // Normals given facing away from the camera (−z) and unnormalized.
        let t = surface_texel(&p, point, Vec3::new(0.0, 0.0, -3.0), Vec3::new(0.0, 0.0, -2.0));
        assert_eq!(t.normal, Vec3::Z);
        assert_eq!(t.geo_normal, Vec3::Z);
        assert_eq!(t.origin, point + Vec3::Z * 0.01);
        assert!((t.depth - (point - p.eye).length()).abs() < 1e-6);
        assert!(t.is_hit() && t.triangle == GBufferTexel::UNKNOWN_TRIANGLE);
    }

    #[test]
    fn missing_normals_fall_back_instead_of_turning_into_nan() {
        let p = params();
        let t = surface_texel(&p, Vec3::ZERO, Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO);
        assert_eq!(t.geo_normal, Vec3::Y, "no geometric normal: the shading one");
        let t = surface_texel(&p, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
        assert_eq!(t.normal, Vec3::Z, "no normal at all: towards the eye");
        assert!(!background_texel().is_hit());
    }
}
