//! Statistics of a flattened BVH, for `penumbra info` and for choosing build parameters.

use std::collections::BTreeMap;

use super::Bvh;
use crate::contract::layout::BvhNode;

/// Shape and cost figures of a [`Bvh`].
#[derive(Clone, Debug, PartialEq)]
pub struct BvhStats {
    /// Triangles in the BVH.
    pub triangles: usize,
    /// Nodes, inner and leaf.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Leaf size → number of leaves with that many triangles.
    pub leaf_size_histogram: BTreeMap<u32, usize>,
    /// Edges on the longest root-to-leaf path (a root leaf has depth 0).
    pub max_depth: usize,
    /// Surface-area-heuristic cost with traversal cost 1 per inner node and
    /// intersection cost 1 per triangle: Σ_inner A(n)/A(root) + Σ_leaf A(l)/A(root)·count(l).
    pub sah_cost: f64,
    /// Bytes of the node and triangle buffers as uploaded.
    pub gpu_bytes: usize,
}

/// Half the surface area of a node's box (0 for an empty box).
pub(super) fn half_area(n: &BvhNode) -> f64 {
    let d = (n.bmax - n.bmin).max(glam::Vec3::ZERO).as_dvec3();
    d.x * d.y + d.y * d.z + d.z * d.x
}

pub(super) fn stats(bvh: &Bvh) -> BvhStats {
    let root_area = half_area(&bvh.nodes[0]);
    let mut s = BvhStats {
        triangles: bvh.triangles.len(),
        nodes: bvh.nodes.len(),
        leaves: 0,
        leaf_size_histogram: BTreeMap::new(),
        max_depth: 0,
        sah_cost: 0.0,
        gpu_bytes: size_of_val(bvh.nodes.as_slice()) + size_of_val(bvh.triangles.as_slice()),
    };
    let mut stack = vec![(0usize, 0usize)];
    while let Some((i, depth)) = stack.pop() {
        let n = &bvh.nodes[i];
        // A flat root (e.g. a single ground quad) has zero area: count it as 1 per node.
        let rel = if root_area > 0.0 {
            half_area(n) / root_area
        } else {
            1.0
        };
        if n.is_leaf() {
            s.leaves += 1;
            *s.leaf_size_histogram.entry(n.count).or_default() += 1;
            s.max_depth = s.max_depth.max(depth);
            s.sah_cost += rel * f64::from(n.count);
        } else {
            s.sah_cost += rel;
            stack.push((n.first as usize, depth + 1));
            stack.push((n.first as usize + 1, depth + 1));
        }
    }
    s
}
