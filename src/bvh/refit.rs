//! Refitting: after triangles move, every box of the flattened tree is recomputed
//! bottom-up, keeping the tree's shape, and the changed nodes and triangles are
//! reported as index ranges for a partial upload.
//!
//! The nodes are in depth-first order with each child pair stored after its parent
//! (`build.rs`, `flatten`), so one sweep from the last node to the first sees every child
//! before its parent. The sweep touches every node (O(nodes), no parent links needed) but
//! recomputes only the boxes above moved triangles.
//!
//! A refitted tree stays correct however far triangles move, but its boxes grow and
//! overlap, so tracing slows down; [`Bvh::sah_cost`] measures that, and the caller
//! rebuilds when the cost has grown too much (see `crate::gpu::GpuScene::set_transforms`).

use std::ops::Range;

use glam::Vec3;

use super::Bvh;
use crate::contract::layout::BvhNode;

/// Ranges closer than this many bytes are merged into one upload: a few bytes of
/// unchanged data cost less than another `write_buffer` call.
pub const MERGE_GAP_BYTES: usize = 256;

/// What a refit changed: index ranges of [`Bvh::nodes`] and [`Bvh::triangles`], sorted,
/// disjoint, merged across gaps below [`MERGE_GAP_BYTES`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Refit {
    /// Nodes whose box changed (or lies in a merged gap).
    pub nodes: Vec<Range<usize>>,
    /// Leaf-order triangle slots that moved (or lie in a merged gap).
    pub triangles: Vec<Range<usize>>,
}

impl Bvh {
    /// Moves the triangles at leaf-order `slots` to their corners in `corners` (indexed by
    /// [`crate::contract::layout::BvhTriangle::scene_index`], i.e. by scene triangle) and refits:
    /// each leaf above a moved triangle gets the exact bounds of its triangles' corners,
    /// each inner node above it the union of its children's boxes.
    ///
    /// Panics if a slot or scene index is out of range (a bug in the caller).
    pub fn refit(&mut self, corners: &[[Vec3; 3]], slots: &[u32]) -> Refit {
        let mut moved = vec![false; self.triangles.len()];
        for &slot in slots {
            let t = &mut self.triangles[slot as usize];
            let [a, b, c] = corners[t.scene_index as usize];
            t.v0 = a;
            t.v1 = b;
            t.v2 = c;
            moved[slot as usize] = true;
        }
        let mut dirty = vec![false; self.nodes.len()];
        for i in (0..self.nodes.len()).rev() {
            let n = self.nodes[i];
            let (bmin, bmax) = if n.is_leaf() {
                let range = n.first as usize..(n.first + n.count) as usize;
                if !moved[range.clone()].iter().any(|&m| m) {
                    continue;
                }
                let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                for t in &self.triangles[range] {
                    for p in corners[t.scene_index as usize] {
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                }
                (lo, hi)
            } else {
                let l = n.first as usize;
                if !dirty[l] && !dirty[l + 1] {
                    continue;
                }
                let (a, b) = (self.nodes[l], self.nodes[l + 1]);
                (a.bmin.min(b.bmin), a.bmax.max(b.bmax))
            };
            if (bmin, bmax) != (n.bmin, n.bmax) {
                self.nodes[i].bmin = bmin;
                self.nodes[i].bmax = bmax;
                dirty[i] = true;
            }
        }
        Refit {
            nodes: ranges(&dirty, MERGE_GAP_BYTES / size_of::<BvhNode>()),
            triangles: ranges(
                &moved,
                MERGE_GAP_BYTES / size_of::<crate::contract::layout::BvhTriangle>(),
            ),
        }
    }

    /// Surface-area-heuristic cost, as in [`super::BvhStats::sah_cost`] (traversal cost 1
    /// per inner node, 1 per triangle, areas relative to the root's), in one pass.
    pub fn sah_cost(&self) -> f64 {
        let root = super::stats::half_area(&self.nodes[0]);
        let sum: f64 = self
            .nodes
            .iter()
            .map(|n| super::stats::half_area(n) * f64::from(n.count.max(1)))
            .sum();
        // A flat root (a single ground quad) has zero area: count 1 per node, as stats do.
        if root > 0.0 {
            sum / root
        } else {
            self.nodes.iter().map(|n| f64::from(n.count.max(1))).sum()
        }
    }
}

/// The runs of `true` in `flags`, runs separated by at most `gap` `false`s merged.
pub fn ranges(flags: &[bool], gap: usize) -> Vec<Range<usize>> {
    let mut out: Vec<Range<usize>> = Vec::new();
    for (i, &f) in flags.iter().enumerate() {
        if !f {
            continue;
        }
        match out.last_mut() {
            Some(r) if i - r.end <= gap => r.end = i + 1,
            _ => out.push(i..i + 1),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_merge_small_gaps_only() {
        let f = |s: &str| s.chars().map(|c| c == '#').collect::<Vec<_>>();
        assert_eq!(ranges(&f("##..#....#"), 2), vec![0..5, 9..10]);
        assert_eq!(ranges(&f("...."), 2), vec![]);
        assert_eq!(ranges(&f("#.#"), 0), vec![0..1, 2..3]);
    }
}
