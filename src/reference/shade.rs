//! CPU twin of the shade pass (`shaders/shade.wgsl`): the light's irradiance
//! toward its centre times the visible fraction (the paper's separation of
//! shading and visibility). The filter smooths this irradiance; the diffuse
//! BRDF (albedo / π) multiplies it afterwards, so textures stay sharp.

use glam::{Vec3, Vec4};

use super::visibility::visibility;
use crate::contract::layout::MASK_SKY;
use crate::contract::layout::{GBufferTexel, ShadeParams};

pub use crate::contract::shade::shade_params;

/// `(irradiance rgb, visibility)` of one pixel: the light treated as a point
/// at its centre with its area and cosine falloff for the unshadowed term,
/// times the mask's visible fraction. Sky pixels: black with visibility 1.
pub fn shade_pixel(params: &ShadeParams, texel: &GBufferTexel, mask: u32) -> Vec4 {
    if mask & MASK_SKY != 0 {
        return Vec4::new(0.0, 0.0, 0.0, 1.0);
    }
    let v = visibility(mask);
    let shadowed: Vec3 = unshadowed_irradiance(params, texel) * v;
    shadowed.extend(v)
}

/// Irradiance from the light treated as a point at its centre, with its area and
/// both cosines, before shadowing (WGSL `unshadowed_irradiance` in `shared/layout`).
pub fn unshadowed_irradiance(params: &ShadeParams, texel: &GBufferTexel) -> Vec3 {
    let w = params.light_center - texel.origin;
    let r2 = w.dot(w).max(1e-12);
    let r = r2.sqrt();
    let cos_surface = (texel.normal.dot(w) / r).max(0.0);
    let cos_light = (-params.light_normal.dot(w) / r).max(0.0);
    params.radiance * (params.light_area * cos_surface * cos_light / r2)
}
