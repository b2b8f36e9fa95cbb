//! The BVH: built on the CPU with obvhs, flattened to 32-byte [`BvhNode`]s with
//! sibling children adjacent and triangles reordered into leaf order, so the
//! GPU reads leaves contiguously with no index indirection.

mod alpha;
mod build;
mod refit;
mod stats;

use std::time::Duration;

pub use alpha::AlphaMasks;
pub use refit::{MERGE_GAP_BYTES, Refit, ranges};
pub use stats::BvhStats;

use crate::Result;
use crate::contract::layout::{BvhNode, BvhTriangle};
use crate::scene::Scene;

/// How much time the builder spends on tree quality (obvhs presets, no spatial splits).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BuildQuality {
    /// PLOC with a small search radius and a little reinsertion (obvhs `fast_build`).
    Fast,
    /// PLOC with a medium search radius and more reinsertion (obvhs `medium_build`).
    Medium,
    /// PLOC with a large search radius and much reinsertion (obvhs `slow_build`
    /// without pre-splits); the default, see `build.rs` for the measurements.
    #[default]
    High,
}

/// Parameters of the BVH build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhSettings {
    /// Largest number of triangles in one leaf (1..=255). Multi-frusta tracing
    /// wants shallower trees than per-ray tracing (the MFT paper, §5): larger
    /// leaves mean fewer box tests per frustum but more triangle tests. The
    /// default, 8, is the faster of 4 and 8 for the MFT shadow pass on Sponza's
    /// atrium view at 1024×1024 (3.59 s against 4.00 s median, `penumbra bench
    /// --leaf-sizes 4,8`); the packet tracer prefers 4.
    pub max_leaf_size: u32,
    /// Build time versus tree quality.
    pub quality: BuildQuality,
}

impl Default for BvhSettings {
    fn default() -> Self {
        BvhSettings {
            max_leaf_size: 8,
            quality: BuildQuality::default(),
        }
    }
}

/// A flattened BVH over a scene's triangles.
#[derive(Clone, Debug)]
pub struct Bvh {
    /// Nodes; the root is node 0. Children of an inner node are adjacent.
    pub nodes: Vec<BvhNode>,
    /// Triangles in leaf order (leaf `first .. first + count`).
    pub triangles: Vec<BvhTriangle>,
    /// Time spent building (obvhs build plus flattening).
    pub build_time: Duration,
    /// The masks of alpha-tested triangles, which [`BvhTriangle::alpha`] points into
    /// (empty for [`Bvh::build_from_corners`]).
    pub alpha: AlphaMasks,
}

impl Bvh {
    /// Builds a BVH over all triangles of `scene`, with the masks of its alpha-tested
    /// materials ([`AlphaMasks::build`]: their textures are decoded here).
    pub fn build(scene: &Scene, settings: &BvhSettings) -> Result<Bvh> {
        let corners: Vec<[glam::Vec3; 3]> = scene.triangles.iter().map(|t| t.positions).collect();
        let mut bvh = build::build(&corners, settings)?;
        bvh.alpha = AlphaMasks::build(scene, &mut bvh.triangles)?;
        Ok(bvh)
    }

    /// The same BVH with every triangle opaque: what the scene would be if its masks were
    /// ignored (`bench` compares the two).
    pub fn without_alpha(&self) -> Bvh {
        let mut bvh = self.clone();
        for t in &mut bvh.triangles {
            t.alpha = crate::contract::alpha::OPAQUE;
        }
        bvh.alpha = AlphaMasks::default();
        bvh
    }

    /// Builds a BVH over triangles given by their corners (index = scene index).
    pub fn build_from_corners(corners: &[[glam::Vec3; 3]], settings: &BvhSettings) -> Result<Bvh> {
        build::build(corners, settings)
    }

    /// Node count, leaf sizes, depth and SAH cost.
    pub fn stats(&self) -> BvhStats {
        stats::stats(self)
    }
}
