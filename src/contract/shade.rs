//! What the shade pass (`shaders/shade.wgsl`) and its twin ([`crate::reference::shade`])
//! read of the light.

use crate::contract::layout::ShadeParams;
use crate::scene::view::QuadLight;

/// Shade parameters for a light and image size.
pub fn shade_params(light: &QuadLight, width: u32, height: u32) -> ShadeParams {
    let n = light.area_normal();
    ShadeParams {
        light_center: light.center(),
        light_area: n.length(),
        light_normal: n.normalize(),
        width,
        radiance: light.color * light.intensity,
        height,
    }
}
