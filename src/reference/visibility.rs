//! CPU twin of `shaders/visibility_values.wgsl` (masks → the filter's input values, for the
//! embedded pass) and of `shaders/visibility_to_texture.wgsl` (which copies channel a of
//! such values into the host's texture).

use crate::contract::layout::{MASK_FULL, MASK_SKY};
use crate::sampling::SAMPLES_PER_SET;

/// Fraction of a mask's 16 rays that reach the light (1 for sky pixels).
pub fn visibility(mask: u32) -> f32 {
    if mask & MASK_SKY != 0 {
        1.0
    } else {
        (SAMPLES_PER_SET as u32 - (mask & MASK_FULL).count_ones()) as f32 / SAMPLES_PER_SET as f32
    }
}

/// The filter's input values of the embedded pass, per pixel: `(0, 0, 0, visibility)`.
pub fn visibility_values(masks: &[u32]) -> Vec<[f32; 4]> {
    masks.iter().map(|&m| [0.0, 0.0, 0.0, visibility(m)]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn visibility_counts_the_unblocked_rays_and_sky_is_visible() {
        assert_eq!(visibility(0), 1.0);
        assert_eq!(visibility(MASK_FULL), 0.0);
        assert_eq!(visibility(0b1011), 13.0 / 16.0);
        assert_eq!(visibility(MASK_SKY | MASK_FULL), 1.0);
        assert_eq!(visibility_values(&[0b1]), vec![[0.0, 0.0, 0.0, 15.0 / 16.0]]);
    }
}
