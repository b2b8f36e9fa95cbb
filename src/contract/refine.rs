//! What the refinement's selection kernel (`shaders/refine_select.wgsl`) and its twin
//! ([`crate::reference::refine`]) are given.

use crate::contract::filter::FilterParams;
use crate::sampling::SAMPLES_PER_SET;

/// Visibility tolerance of the refinement's window test: one ray of 16. A neighbour on
/// the same surface whose unfiltered visibility differs by more cuts the window, so the
/// pixel is refined; the filter itself averages neighbours up to two rays apart
/// ([`FilterParams::DEFAULT_VISIBILITY_TOLERANCE`]). See the module's figures.
pub const REFINE_VISIBILITY_TOLERANCE: f32 = 1.0 / 16.0;

/// The filter's parameters with the refinement's visibility tolerance: what
/// `refine_select` gets as its `filter_params`.
pub fn selection_params(filter: &FilterParams) -> FilterParams {
    FilterParams {
        visibility_tolerance: REFINE_VISIBILITY_TOLERANCE,
        ..*filter
    }
}

/// The sample-set counts a refined pixel may trace ([`RefineParams::sets`]): powers of two,
/// so that its visibility, (rays − blocked) / rays, is exact in f32 on every device.
///
/// [`RefineParams::sets`]: crate::contract::layout::RefineParams::sets
pub const REFINE_SET_COUNTS: [u32; 5] = [1, 2, 4, 8, 16];

/// Listed pixels per 4×4 tile of the refinement's sample image when each traces `sets` of
/// the 16 sample sets: `16 / sets` (WGSL: `per_tile` in `refine_gather` and `refine_resolve`).
pub fn pixels_per_tile(sets: u32) -> u32 {
    crate::sampling::SETS as u32 / sets.clamp(1, 16)
}

/// How many pixels a ray budget of `budget` rays per pixel with geometry on average (the
/// frame's 16 included) lets the refinement trace, for `geometry` pixels with geometry and
/// `sets` sample sets (16 rays each, its own traced again when among them) per refined
/// pixel: `⌊(budget − 16) · geometry / (16 · sets)⌋`, 0 below 16.
pub fn budget_pixels(budget: f32, geometry: u32, sets: u32) -> u32 {
    let per_set = SAMPLES_PER_SET as f64;
    let extra = (f64::from(budget) - per_set).max(0.0);
    (extra * f64::from(geometry) / (per_set * f64::from(sets.max(1)))).floor() as u32
}

/// The pixels a budget of `keep` pixels refines, from the listed `(pixel, score)` pairs: the
/// `keep` highest scores (ties: the lower pixel index first), returned in pixel order. Run
/// on the host between `refine_select` and `refine_gather`, and by the CPU twin.
pub fn within_budget(listed: &[(u32, f32)], keep: u32) -> Vec<u32> {
    let mut ranked = listed.to_vec();
    ranked.sort_unstable_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    ranked.truncate(keep as usize);
    let mut kept: Vec<u32> = ranked.into_iter().map(|(p, _)| p).collect();
    kept.sort_unstable();
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_pixels_counts_the_extra_rays_in_whole_pixels() {
        assert_eq!(budget_pixels(16.0, 1000, 16), 0);
        assert_eq!(budget_pixels(8.0, 1000, 16), 0, "below 16: nothing");
        // 8 extra rays per pixel over 1000 pixels: 8000 / 256 = 31.25 pixels.
        assert_eq!(budget_pixels(24.0, 1000, 16), 31);
        // 8 sets, 128 rays per refined pixel: 62.5.
        assert_eq!(budget_pixels(24.0, 1000, 8), 62);
        assert_eq!(
            budget_pixels(272.0, 1000, 16),
            1000,
            "256 extra rays: every pixel"
        );
    }

    #[test]
    fn within_budget_keeps_the_highest_scores_in_pixel_order() {
        let listed = [(9, 0.1), (3, 0.5), (7, 0.5), (1, 0.0), (5, 0.9)];
        assert_eq!(within_budget(&listed, 0), Vec::<u32>::new());
        assert_eq!(within_budget(&listed, 1), vec![5]);
        // 3 and 7 tie: the lower index goes first.
        assert_eq!(within_budget(&listed, 2), vec![3, 5]);
        assert_eq!(within_budget(&listed, 3), vec![3, 5, 7]);
        assert_eq!(within_budget(&listed, 9), vec![1, 3, 5, 7, 9]);
    }
}
