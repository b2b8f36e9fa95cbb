//! What the ray–box test of every traversal (`shaders/shared/intersect.wgsl` and the CPU
//! twins' [`crate::reference::intersect_box`]) agrees on.

/// `1 + 2γ₃` with `γₙ = n·ε / (1 − n·ε)`, ε = 2⁻²⁴: scaling the slab test's exit
/// distance by it makes the f32 box test conservative (Ize, "Robust BVH Ray
/// Traversal", JCGT 2013), so rounding never culls a box that the exact
/// test would enter.
pub const BOX_EXIT_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);
