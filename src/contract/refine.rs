//! What the refinement's selection kernel (`shaders/refine_select.wgsl`) and its twin
//! ([`crate::reference::refine`]) are given.

use crate::contract::filter::FilterParams;

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
