//! Building with obvhs and flattening into [`BvhNode`]s.
//!
//! Builder choice: obvhs 0.4 offers PLOC (+ reinsertion and SAH-driven leaf
//! collapse); it has no binned-SAH builder. Spatial pre-splits are off: they put
//! one triangle into several leaves, which doubles intersection work for
//! frusta that see both copies and breaks the one-leaf-per-triangle layout.
//! The default preset (`High`) was chosen by measurement
//! (`cargo run --release --example bvh_builders ../shared/scenes/*/*.gl*`,
//! 100k shadow-like rays through the CPU reference tracer, one thread, leaf ≤ 4):
//!
//! | scene   | Fast ms / Mrays/s | Medium ms / Mrays/s | High ms / Mrays/s |
//! |---------|-------------------|---------------------|-------------------|
//! | Sponza  | 11.4 / 1.29       | 21.7 / 1.34         | 59.6 / 1.41       |
//! | Bunny   | 10.8 / 0.99       | 17.2 / 0.95         | 44.5 / 0.98       |
//! | Engine  | 26.1 / 1.05       | 39.6 / 1.02         | 113.6 / 1.23      |
//!
//! `High` traces 5–20 % faster for ≤ 0.12 s more build on these scenes; one
//! 1024² frame of 16 shadow rays per pixel is 16.7 M rays, so the build pays
//! for itself in every frame. Moving objects (refit/rebuild per frame) may
//! prefer `Fast`.

use std::time::{Duration, Instant};

use glam::{Vec3, Vec3A};
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2_from_tris, triangle::Triangle};

use super::{AlphaMasks, BuildQuality, Bvh, BvhSettings};
use crate::contract::bvh::MAX_LEAF_TRIANGLES;
use crate::contract::layout::{BvhNode, BvhTriangle};
use crate::{Error, Result};

fn params(settings: &BvhSettings) -> BvhBuildParams {
    let mut p = match settings.quality {
        BuildQuality::Fast => BvhBuildParams::fast_build(),
        BuildQuality::Medium => BvhBuildParams::medium_build(),
        BuildQuality::High => BvhBuildParams::slow_build(),
    };
    p.pre_split = false;
    p.max_prims_per_leaf = settings.max_leaf_size;
    p
}

pub(super) fn build(corners: &[[Vec3; 3]], settings: &BvhSettings) -> Result<Bvh> {
    if corners.is_empty() {
        return Err(Error::Bvh("the scene has no triangles".into()));
    }
    if !(1..=MAX_LEAF_TRIANGLES).contains(&settings.max_leaf_size) {
        return Err(Error::value(
            "BvhSettings::max_leaf_size",
            settings.max_leaf_size,
            format!("must be in 1..={MAX_LEAF_TRIANGLES}"),
        ));
    }
    if u32::try_from(corners.len()).is_err() {
        return Err(Error::Bvh(format!(
            "{} triangles is more than 2^32",
            corners.len()
        )));
    }
    // Non-finite corners would poison every box above them; the loader drops such
    // triangles, so here they can only come from a caller's own corners.
    if let Some(i) = corners.iter().position(|c| !c.iter().all(|p| p.is_finite())) {
        return Err(Error::Bvh(format!(
            "triangle {i} has a non-finite corner {:?}; drop such triangles before building",
            corners[i]
        )));
    }
    let start = Instant::now();
    let tris: Vec<Triangle> = corners
        .iter()
        .map(|c| Triangle {
            v0: Vec3A::from(c[0]),
            v1: Vec3A::from(c[1]),
            v2: Vec3A::from(c[2]),
        })
        .collect();
    let bvh2 = build_bvh2_from_tris(&tris, params(settings), &mut Duration::default());
    let (nodes, order) = flatten(&bvh2);
    let triangles = order
        .iter()
        .map(|&i| {
            let c = corners[i as usize];
            BvhTriangle {
                v0: c[0],
                scene_index: i,
                v1: c[1],
                alpha: crate::contract::alpha::OPAQUE,
                v2: c[2],
                pad2: 0,
            }
        })
        .collect();
    Ok(Bvh {
        nodes,
        triangles,
        build_time: start.elapsed(),
        alpha: AlphaMasks::default(),
    })
}

/// Depth-first copy of obvhs' tree: every inner node gets its two children as a
/// fresh adjacent pair, and leaves get their triangles appended in visit order.
/// Returns the nodes and, per leaf-order slot, the original triangle index.
fn flatten(bvh2: &obvhs::bvh2::Bvh2) -> (Vec<BvhNode>, Vec<u32>) {
    let src = &bvh2.nodes;
    let mut nodes = vec![BvhNode::default()];
    let mut order = Vec::with_capacity(bvh2.primitive_indices.len());
    let mut stack = vec![(0usize, 0usize)];
    while let Some((s, d)) = stack.pop() {
        let n = &src[s];
        let (bmin, bmax) = (Vec3::from(n.aabb().min), Vec3::from(n.aabb().max));
        if n.is_leaf() {
            let first = order.len() as u32;
            let range = n.first_index as usize..(n.first_index + n.prim_count) as usize;
            order.extend_from_slice(&bvh2.primitive_indices[range]);
            nodes[d] = BvhNode {
                bmin,
                first,
                bmax,
                count: n.prim_count,
            };
        } else {
            let pair = nodes.len();
            nodes.extend([BvhNode::default(); 2]);
            nodes[d] = BvhNode {
                bmin,
                first: pair as u32,
                bmax,
                count: 0,
            };
            let left = n.first_index as usize;
            stack.push((left + 1, pair + 1));
            stack.push((left, pair));
        }
    }
    (nodes, order)
}
