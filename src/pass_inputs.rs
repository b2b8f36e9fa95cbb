//! CPU-side preparation of what the frame's passes read: the camera, the
//! shading data in leaf order, the materials and their textures.

use glam::{Vec2, Vec3, Vec4};

use crate::bvh::Bvh;
use crate::contract::alpha::{BLEND_ALPHA_CUTOFF, texel_index};
use crate::contract::layout::{CameraParams, GpuMaterial, GpuTexture, ORIGIN_OFFSET_ULPS, ShadingTriangle};
use crate::scene::view::Camera;
use crate::scene::{AlphaMode, ImageSource, Material, Scene};
use crate::{Error, Result};

/// Shadow-ray origins leave the surface by this fraction of the scene's
/// diagonal: near the origin large enough to clear f32 rounding of the hit
/// point, small enough not to open gaps at contacts (10⁻⁴ of 10 m is 1 mm);
/// far from the origin [`ORIGIN_OFFSET_ULPS`] takes over ([`shadow_ray_origin`]).
pub const RAY_OFFSET_FRACTION: f32 = 1e-4;

/// The shadow-ray origin of surface point `point` with unit `normal` (on the side the
/// rays leave to): the point moved along the normal by `ray_offset` or by
/// [`ORIGIN_OFFSET_ULPS`] steps of f32 at its largest coordinate, whichever is larger.
/// A fixed offset alone fails far from the origin (a scene at 1e5 m has f32 steps of
/// 7.8 mm): rays would start inside their own surface. The kernels compute the same
/// expression (`shadow_ray_origin` in `shaders/shared/layout.wgsl`).
pub fn shadow_ray_origin(point: Vec3, normal: Vec3, ray_offset: f32) -> Vec3 {
    let m = point.abs().max_element();
    // The spacing of f32 values at m: 2^(m's exponent) · 2⁻²³.
    let ulp = f32::from_bits(m.to_bits() & 0x7f80_0000) * (1.0 / 8_388_608.0);
    point + normal * ray_offset.max(ORIGIN_OFFSET_ULPS * ulp)
}

/// The camera for a `width`×`height` image (square pixels).
///
/// The frame is [`Camera::basis`]; a camera without one (which
/// [`crate::scene::view::View::validate`] refuses) gives NaN rays, which hit nothing.
pub fn camera_params(camera: &Camera, width: u32, height: u32, ray_offset: f32) -> CameraParams {
    let (forward, right, up) = camera.basis().unwrap_or((Vec3::NAN, Vec3::NAN, Vec3::NAN));
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
        image_width: width,
        image_height: height,
        origin_x: 0,
        origin_y: 0,
    }
}

/// The camera of the `width`×`height` tile whose top-left pixel is `(x0, y0)` of the
/// image `whole` projects: the same rays, written to a tile-sized G-buffer.
pub fn tile_camera(whole: &CameraParams, x0: u32, y0: u32, width: u32, height: u32) -> CameraParams {
    CameraParams {
        width,
        height,
        origin_x: whole.origin_x + x0,
        origin_y: whole.origin_y + y0,
        ..*whole
    }
}

/// The unnormalised direction of the camera ray through pixel `(x, y)`; the
/// WGSL primary kernel computes the same expression.
pub fn camera_ray(cam: &CameraParams, x: u32, y: u32) -> Vec3 {
    let sx = 2.0 * ((x + cam.origin_x) as f32 + 0.5) / cam.image_width as f32 - 1.0;
    let sy = 1.0 - 2.0 * ((y + cam.origin_y) as f32 + 0.5) / cam.image_height as f32;
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
                uv0: s.uvs[0],
                uv1: s.uvs[1],
                uv2: s.uvs[2],
                pad3: [0; 2],
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
            texture: m.base_color_texture.unwrap_or(u32::MAX),
            alpha_factor: m.base_color_factor[3],
            alpha_cutoff: alpha_cutoff(m),
            pad: [0; 2],
        })
        .collect()
}

/// The cutoff below which rays pass `m`'s surface: its `alphaCutoff` for `MASK`,
/// [`BLEND_ALPHA_CUTOFF`] for `BLEND`, and 0 (never passes) for `OPAQUE`.
pub fn alpha_cutoff(m: &Material) -> f32 {
    match m.alpha_mode {
        AlphaMode::Opaque => 0.0,
        AlphaMode::Mask => m.alpha_cutoff,
        AlphaMode::Blend => BLEND_ALPHA_CUTOFF,
    }
}

/// Scene image `i` decoded to 8-bit RGBA; errors as for [`ShadingData::new`].
pub(crate) fn decode_rgba8(scene: &Scene, i: usize) -> Result<image::RgbaImage> {
    let (bytes, what) = image_bytes(scene, i)?;
    Ok(image::load_from_memory(&bytes)
        .map_err(|e| Error::scene(&scene.source, format!("{what}: cannot decode the texture: {e}")))?
        .to_rgba8())
}

/// A texel's alpha as the kernels see it (linear, unlike its colour).
pub(crate) fn texel_alpha(a: u8) -> f32 {
    a as f32 / 255.0
}

/// Everything the primary pass needs besides the BVH: per-triangle shading
/// data, materials, and the base colour textures decoded to linear RGBA.
#[derive(Clone, Debug)]
pub struct ShadingData {
    /// Shading data in leaf order.
    pub triangles: Vec<ShadingTriangle>,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// One entry per scene image: where its texels are.
    pub textures: Vec<GpuTexture>,
    /// All textures' texels, linear RGBA.
    pub texels: Vec<Vec4>,
}

impl ShadingData {
    /// Gathers and decodes; an image that cannot be read or decoded is an
    /// error naming the scene and the image file (a missing texture is an
    /// error, not a silently untextured material: the albedo would be wrong).
    pub fn new(scene: &Scene, bvh: &Bvh) -> Result<ShadingData> {
        let mut textures = Vec::with_capacity(scene.images.len());
        let mut texels = Vec::new();
        for i in 0..scene.images.len() {
            let image = decode_rgba8(scene, i)?;
            textures.push(GpuTexture {
                offset: texels.len() as u32,
                width: image.width(),
                height: image.height(),
                pad: 0,
            });
            // Base colour textures are sRGB-encoded (glTF 2.0 §3.9.2); shading wants linear.
            texels.extend(image.pixels().map(|p| {
                Vec4::new(
                    srgb_to_linear(p[0]),
                    srgb_to_linear(p[1]),
                    srgb_to_linear(p[2]),
                    texel_alpha(p[3]),
                )
            }));
        }
        if texels.is_empty() {
            // A bindable buffer needs at least one element.
            texels.push(Vec4::ONE);
        }
        Ok(ShadingData {
            triangles: shading_triangles(scene, bvh),
            materials: gpu_materials(scene),
            textures,
            texels,
        })
    }

    /// Albedo of `material` at texture coordinate `uv`: the base colour factor
    /// times the nearest texel (coordinates wrap), as the primary kernel computes it.
    pub fn albedo(&self, material: u32, uv: Vec2) -> Vec3 {
        let m = &self.materials[material as usize];
        match self.textures.get(m.texture as usize) {
            None => m.base_color,
            Some(t) => {
                m.base_color
                    * self.texels[(t.offset + texel_index(t.width, t.height, uv)) as usize].truncate()
            }
        }
    }
}

/// Largest texture file read: a bound against a hostile scene naming a huge file.
const MAX_TEXTURE_FILE_BYTES: u64 = 1 << 30;

/// The encoded bytes of scene image `i` and how to name it in errors
/// (`image 3 'textures/wood.png'` or `embedded image 3`).
fn image_bytes(scene: &Scene, i: usize) -> Result<(std::borrow::Cow<'_, [u8]>, String)> {
    match &scene.images[i] {
        ImageSource::File(path) => {
            let what = format!("image {i} '{}'", path.display());
            let bytes = crate::scene::read_file_prefix(path, MAX_TEXTURE_FILE_BYTES)
                .map_err(|e| Error::scene(&scene.source, format!("{what}: cannot read the texture: {e}")))?;
            Ok((bytes.into(), what))
        }
        ImageSource::Embedded { bytes, .. } => Ok((bytes.as_slice().into(), format!("embedded image {i}"))),
    }
}

/// Width and height of scene image `i`, from its header only (nothing is
/// decoded); errors as for [`ShadingData::new`].
pub fn texture_dimensions(scene: &Scene, i: usize) -> Result<(u32, u32)> {
    let (bytes, what) = image_bytes(scene, i)?;
    image::ImageReader::new(std::io::Cursor::new(&bytes[..]))
        .with_guessed_format()
        .map_err(|e| Error::scene(&scene.source, format!("{what}: {e}")))?
        .into_dimensions()
        .map_err(|e| Error::scene(&scene.source, format!("{what}: cannot decode the texture: {e}")))
}

fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shadow_ray_origins_clear_the_f32_steps_of_far_points() {
        let n = Vec3::Y;
        // Near the origin the scene's offset rules.
        assert_eq!(
            shadow_ray_origin(Vec3::new(3.0, 1.0, -2.0), n, 1e-3),
            Vec3::new(3.0, 1.001, -2.0)
        );
        // At 1e5 f32 steps are 2^16 · 2^-23 = 1/128: ORIGIN_OFFSET_ULPS of them, not the 1e-3 offset.
        let far = Vec3::new(1e5, 0.5, 1e5);
        let o = shadow_ray_origin(far, n, 1e-3);
        assert_eq!(o.y, 0.5 + ORIGIN_OFFSET_ULPS / 128.0);
        assert_eq!((o.x, o.z), (far.x, far.z));
        // Zero point: no NaN, the fixed offset.
        assert_eq!(shadow_ray_origin(Vec3::ZERO, n, 1e-3), Vec3::new(0.0, 1e-3, 0.0));
    }

    #[test]
    fn albedo_is_factor_times_nearest_texel_with_wrapping() {
        let data = ShadingData {
            triangles: Vec::new(),
            materials: vec![
                GpuMaterial {
                    base_color: Vec3::new(0.5, 1.0, 1.0),
                    texture: 0,
                    ..Default::default()
                },
                GpuMaterial {
                    base_color: Vec3::splat(0.25),
                    texture: u32::MAX,
                    ..Default::default()
                },
            ],
            textures: vec![GpuTexture {
                offset: 0,
                width: 2,
                height: 2,
                pad: 0,
            }],
            texels: vec![
                Vec4::splat(1.0),
                Vec4::splat(2.0),
                Vec4::splat(3.0),
                Vec4::splat(4.0),
            ],
        };
        assert_eq!(data.albedo(0, Vec2::new(0.25, 0.25)), Vec3::new(0.5, 1.0, 1.0));
        assert_eq!(data.albedo(0, Vec2::new(0.75, 0.25)), Vec3::new(1.0, 2.0, 2.0));
        assert_eq!(data.albedo(0, Vec2::new(0.25, 0.75)), Vec3::new(1.5, 3.0, 3.0));
        assert_eq!(
            data.albedo(0, Vec2::new(-0.25, 1.75)),
            Vec3::new(2.0, 4.0, 4.0),
            "wraps"
        );
        assert_eq!(
            data.albedo(1, Vec2::new(0.5, 0.5)),
            Vec3::splat(0.25),
            "no texture"
        );
        assert!((srgb_to_linear(255) - 1.0).abs() < 1e-6 && srgb_to_linear(0) == 0.0);
    }
}
