//! CPU twin of the multi-frusta shadow kernel (`shaders/shadow_mft.wgsl`):
//! the same 16-lane vector per 4×4 tile, the same culling, the same per-ray
//! arithmetic and the same traversal order, one lane at a time. It is the
//! kernel's test oracle (bit-exact where the GPU does not fuse multiply-adds)
//! and the place to count work the way the paper's Table 1 does.
//!
//! Lane `i` owns pixel `i` of the tile (`x mod 4 + 4·(y mod 4)`), whose set of
//! light samples is set `i`. Its frustum is the pyramid from its shadow-ray
//! origin to the light's four corners, cut by the surface's tangent plane and
//! the light's plane. Every ray of the pixel lies strictly inside it (samples
//! sit at least ½⁄256 of an edge inside the light), so the culling below is
//! conservative.

use glam::Vec3;

use super::descend::descend;
use super::shadow::{MASK_FULL, MASK_SKY, initial_mask, light_corners};
use crate::bvh::Bvh;
use crate::layout::{BvhNode, BvhTriangle, GBufferTexel, ShadowParams};
use crate::sampling::SAMPLES_PER_SET;

/// Depth of the traversal stack; a BVH deeper than this cannot be traced.
pub const STACK_SIZE: usize = 64;
/// Widening of a shrunk frustum's light rectangle, in light-edge units: samples
/// lie at odd multiples of 1/512, so this keeps every active sample 1/1024 of an
/// edge inside, far above the rounding of the (s, t) arithmetic.
pub const SHRINK_MARGIN: f32 = 1.0 / 1024.0;
/// Marks a frustum's `shrunk_for` as set.
pub const SHRINK_FLAG: u32 = 1 << 31;

/// Inward normals of the planes through `o` and each light edge.
fn side_planes(o: Vec3, c: &[Vec3; 4]) -> [Vec3; 4] {
    let centre = (c[0] + c[2]) * 0.5;
    std::array::from_fn(|k| {
        let n = (c[k] - o).cross(c[(k + 1) % 4] - o);
        if n.dot(centre - o) < 0.0 { -n } else { n }
    })
}

/// One lane's frustum and its rays.
#[derive(Clone, Copy, Debug, Default)]
pub struct Frustum {
    origin: Vec3,
    geo_normal: Vec3,
    /// Inward normals of the four side planes through `origin`.
    side: [Vec3; 4],
    /// The light rectangle the frustum bounds: the light's corners, or after
    /// shrinking those of the part that holds the still-active samples.
    corners: [Vec3; 4],
    /// With [`SHRINK_FLAG`]: the blocked-ray mask `corners` were last shrunk for.
    shrunk_for: u32,
    /// The lane's sample set.
    set: usize,
    /// The mask before any triangle (rays below the horizon).
    initial: u32,
    /// Ray directions `light point − origin` of the lane's 16 samples.
    dirs: [Vec3; SAMPLES_PER_SET],
    /// Blocked rays (bits 0..16), or [`MASK_SKY`].
    occluded: u32,
}

impl Frustum {
    /// The frustum of one pixel; `set` is its sample set.
    pub fn new(texel: &GBufferTexel, set: usize, light_points: &[Vec3], params: &ShadowParams) -> Frustum {
        let o = texel.origin;
        let c = light_corners(params);
        Frustum {
            origin: o,
            geo_normal: texel.geo_normal,
            side: side_planes(o, &c),
            corners: c,
            shrunk_for: 0,
            set,
            dirs: std::array::from_fn(|j| light_points[set * SAMPLES_PER_SET + j] - o),
            occluded: initial_mask(texel, set, light_points, params),
            initial: initial_mask(texel, set, light_points, params),
        }
    }

    /// Frustum shrinking, the paper's "CR" (§5.3): recomputes the corner rays
    /// through the corners of the light-plane rectangle (s, t ranges, widened by
    /// [`SHRINK_MARGIN`]) that holds the samples not yet blocked in `blocked`. Rays
    /// already blocked need no more tests, so culling against the smaller frustum
    /// gives the same mask with fewer triangle tests.
    pub fn shrink_to(&mut self, blocked: u32, light_points: &[Vec3], params: &ShadowParams) {
        let c = light_corners(params);
        let (eu, ev) = (c[1] - c[0], c[3] - c[0]);
        let n = eu.cross(ev);
        let inv = 1.0 / n.dot(n);
        let du = ev.cross(n) * inv;
        let dv = n.cross(eu) * inv;
        let (mut lo, mut hi) = (glam::Vec2::ONE, glam::Vec2::ZERO);
        for j in 0..SAMPLES_PER_SET {
            if blocked & (1 << j) == 0 {
                let q = light_points[self.set * SAMPLES_PER_SET + j] - c[0];
                let st = glam::Vec2::new(q.dot(du), q.dot(dv));
                lo = lo.min(st);
                hi = hi.max(st);
            }
        }
        lo = (lo - SHRINK_MARGIN).max(glam::Vec2::ZERO);
        hi = (hi + SHRINK_MARGIN).min(glam::Vec2::ONE);
        let at = |s: f32, t: f32| c[0] + eu * s + ev * t;
        self.corners = [at(lo.x, lo.y), at(hi.x, lo.y), at(hi.x, hi.y), at(lo.x, hi.y)];
        self.side = side_planes(self.origin, &self.corners);
        self.shrunk_for = blocked | SHRINK_FLAG;
    }

    /// Shrinks after a leaf if a ray was blocked since the last time (or since the start).
    fn shrink_after_leaf(&mut self, light_points: &[Vec3], params: &ShadowParams) {
        let last = if self.shrunk_for & SHRINK_FLAG != 0 {
            self.shrunk_for & MASK_FULL
        } else {
            self.initial
        };
        if !self.is_done() && self.occluded != last {
            self.shrink_to(self.occluded, light_points, params);
        }
    }

    /// No ray left to decide (all blocked, or a sky pixel).
    pub fn is_done(&self) -> bool {
        self.occluded & MASK_SKY != 0 || self.occluded & MASK_FULL == MASK_FULL
    }
}

/// Whether any ray of the frustum may hit the box: false only when the box
/// lies wholly outside one of the six planes (p-vertex test).
pub fn frustum_may_hit_box(f: &Frustum, node: &BvhNode, params: &ShadowParams) -> bool {
    let outside = |n: Vec3, p0: Vec3| {
        let p = Vec3::select(n.cmpgt(Vec3::ZERO), node.bmax, node.bmin);
        n.dot(p - p0) < 0.0
    };
    let c0 = light_corners(params)[0];
    !(outside(f.side[0], f.origin)
        || outside(f.side[1], f.origin)
        || outside(f.side[2], f.origin)
        || outside(f.side[3], f.origin)
        || outside(f.geo_normal, f.origin)
        || outside(params.light_normal, c0))
}

/// What happened when a frustum met a triangle (for the counters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TriangleOutcome {
    /// Culled before any ray was tested.
    Culled,
    /// The 16 rays were tested; the bits of those that hit.
    Tested(u32),
}

/// Culls the triangle against the frustum, else tests the frustum's 16 rays.
///
/// With `a_i = v_i − origin`, the edge normals `m0 = a0×a1`, `m1 = a1×a2`,
/// `m2 = a2×a0` and `D = m0·a2` (six times the signed volume of the
/// tetrahedron origin–triangle): ray `d` passes through the triangle when
/// `m_e·d` all have the sign of `D` (edges inclusive: a shared edge gives
/// exactly negated normals to its two triangles), and it reaches the
/// triangle's plane at `t = D / (m0+m1+m2)·d`, so it hits when `|D| <
/// t_max·|Σ m_e·d|`. No division, and all four dot products share `d`.
pub fn frustum_test_triangle(f: &Frustum, tri: &BvhTriangle, params: &ShadowParams) -> TriangleOutcome {
    let o = f.origin;
    let (v0, v1, v2) = (tri.v0, tri.v0 + tri.e1, tri.v0 + tri.e2);
    let (a0, a1, a2) = (v0 - o, v1 - o, v2 - o);
    // Wholly outside one plane of the frustum.
    let all_outside =
        |n: Vec3, b0: Vec3, b1: Vec3, b2: Vec3| n.dot(b0) < 0.0 && n.dot(b1) < 0.0 && n.dot(b2) < 0.0;
    let c = light_corners(params);
    let ln = params.light_normal;
    if all_outside(f.side[0], a0, a1, a2)
        || all_outside(f.side[1], a0, a1, a2)
        || all_outside(f.side[2], a0, a1, a2)
        || all_outside(f.side[3], a0, a1, a2)
        || all_outside(f.geo_normal, a0, a1, a2)
        || all_outside(ln, v0 - c[0], v1 - c[0], v2 - c[0])
    {
        return TriangleOutcome::Culled;
    }
    let m0 = a0.cross(a1);
    let m1 = a1.cross(a2);
    let m2 = a2.cross(a0);
    let d = m0.dot(a2);
    if d == 0.0 {
        // The origin lies in the triangle's plane: no ray crosses it.
        return TriangleOutcome::Culled;
    }
    // Corner rays: if all four light corners lie strictly outside one edge
    // plane, so does every ray (the paper's corner-ray culling, shared origin).
    let k = f.corners;
    let (k0, k1, k2, k3) = (k[0] - o, k[1] - o, k[2] - o, k[3] - o);
    let edge_culls = |m: Vec3| {
        let s = [m.dot(k0), m.dot(k1), m.dot(k2), m.dot(k3)];
        if d > 0.0 {
            s.iter().all(|&x| x < 0.0)
        } else {
            s.iter().all(|&x| x > 0.0)
        }
    };
    if edge_culls(m0) || edge_culls(m1) || edge_culls(m2) {
        return TriangleOutcome::Culled;
    }
    let limit = d.abs();
    let mut hits = 0u32;
    for (j, dir) in f.dirs.iter().enumerate() {
        let s0 = m0.dot(*dir);
        let s1 = m1.dot(*dir);
        let s2 = m2.dot(*dir);
        let inside = if d > 0.0 {
            s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0
        } else {
            s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0
        };
        if inside && limit < params.t_max * (s0 + s1 + s2).abs() {
            hits |= 1 << j;
        }
    }
    TriangleOutcome::Tested(hits)
}

pub use super::counters::Counters;

/// The traversal state of one vector: what the GPU kernel saves when it
/// suspends and reloads when it resumes.
#[derive(Clone, Debug, Default)]
struct VectorState {
    /// Inner node to visit next (when not in a leaf).
    node: u32,
    /// Frusta that entered `node`.
    mask: u32,
    /// Next triangle of the current leaf.
    cursor: u32,
    /// End of the current leaf's triangles.
    end: u32,
    /// Frusta not yet done.
    alive: u32,
    /// Pending subtrees with the frusta that wanted them.
    stack: Vec<(u32, u32)>,
    /// The next step pops the stack.
    popping: bool,
}

fn ballot(frusta: &[Frustum; 16], pred: impl Fn(usize, &Frustum) -> bool) -> u32 {
    frusta
        .iter()
        .enumerate()
        .filter(|(i, f)| pred(*i, f))
        .fold(0, |m, (i, _)| m | (1 << i))
}

impl VectorState {
    /// Moves to node `c` with frustum mask `m`, opening its triangle range if it is a leaf.
    fn enter(&mut self, bvh: &Bvh, c: u32, m: u32) {
        self.node = c;
        self.mask = m;
        let n = &bvh.nodes[c as usize];
        if n.is_leaf() {
            self.cursor = n.first;
            self.end = n.first + n.count;
        }
    }
}

/// Traces one 4×4 tile's 16 frusta; returns the 16 occlusion masks (lane order).
///
/// Each loop iteration is one step, as in the kernel: one leaf triangle, one
/// stack pop, or one inner node. `budget` mimics the kernel's per-dispatch
/// iteration budget: when it runs out, the state is kept and traversal
/// resumes, exactly as the GPU resumes a suspended tile in its next dispatch.
pub fn trace_tile(
    bvh: &Bvh,
    frusta: [Frustum; 16],
    params: &ShadowParams,
    budget: u32,
    counters: &mut Counters,
) -> [u32; 16] {
    trace_tile_with(bvh, frusta, params, budget, None, counters)
}

/// [`trace_tile`], with frustum shrinking ([`Frustum::shrink_to`]) after every leaf
/// when `shrink` gives the light points.
pub fn trace_tile_with(
    bvh: &Bvh,
    mut frusta: [Frustum; 16],
    params: &ShadowParams,
    budget: u32,
    shrink: Option<&[Vec3]>,
    counters: &mut Counters,
) -> [u32; 16] {
    let mut st = VectorState {
        alive: ballot(&frusta, |_, f| !f.is_done()),
        stack: Vec::with_capacity(STACK_SIZE),
        ..Default::default()
    };
    let root_mask = ballot(&frusta, |_, f| {
        !f.is_done() && frustum_may_hit_box(f, &bvh.nodes[0], params)
    });
    counters.box_tests += 1;
    let mut running = root_mask != 0;
    st.enter(bvh, 0, root_mask);
    let mut iterations = 0u32;
    while running {
        if iterations == budget {
            // Suspend: on the GPU the state goes to memory and the next dispatch resumes it.
            counters.suspensions += 1;
            iterations = 0;
        }
        iterations += 1;
        counters.traversal_steps += 1;
        if st.cursor < st.end {
            let tri = &bvh.triangles[st.cursor as usize];
            st.cursor += 1;
            counters.triangles_accessed += 1;
            let mut survived = 0;
            for (i, f) in frusta.iter_mut().enumerate() {
                if st.mask & (1 << i) != 0 && !f.is_done() {
                    if let TriangleOutcome::Tested(hits) = frustum_test_triangle(f, tri, params) {
                        survived += 1;
                        f.occluded |= hits;
                    }
                }
            }
            counters.triangle_tests += survived;
            counters.triangles_after_culling += u64::from(survived > 0);
            if st.cursor == st.end {
                if let Some(points) = shrink {
                    for f in frusta.iter_mut() {
                        f.shrink_after_leaf(points, params);
                    }
                }
                st.alive = ballot(&frusta, |_, f| !f.is_done());
                running = st.alive != 0;
                st.popping = true;
            }
        } else if st.popping {
            match st.stack.pop() {
                None => running = false,
                Some((c, m)) if m & st.alive != 0 => {
                    st.popping = false;
                    st.enter(bvh, c, m & st.alive);
                }
                Some(_) => {}
            }
        } else {
            let l = bvh.nodes[st.node as usize].first;
            counters.nodes_visited += 1;
            counters.box_tests += 2;
            let mask = st.mask;
            let wants = |c: u32| {
                ballot(&frusta, |i, f| {
                    mask & (1 << i) != 0
                        && !f.is_done()
                        && frustum_may_hit_box(f, &bvh.nodes[c as usize], params)
                })
            };
            let (ml, mr) = (wants(l), wants(l + 1));
            // Into the child more frusta want first.
            let d = descend(l, ml, mr, mr.count_ones() > ml.count_ones());
            if let Some(later) = d.later {
                assert!(st.stack.len() < STACK_SIZE, "BVH deeper than the traversal stack");
                st.stack.push(later);
            }
            match d.now {
                Some((c, m)) => st.enter(bvh, c, m),
                None => st.popping = true,
            }
        }
    }
    frusta.map(|f| f.occluded)
}

/// Occlusion masks of a whole G-buffer (row-major) with multi-frusta tracing,
/// tile by tile; tiles are spread over all cores.
pub fn mft_masks(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    light_points: &[Vec3],
    params: &ShadowParams,
    budget: u32,
) -> (Vec<u32>, Counters) {
    mft_masks_with(bvh, gbuffer, light_points, params, budget, false)
}

/// [`mft_masks`], with frustum shrinking when `shrink` is set.
pub fn mft_masks_with(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    light_points: &[Vec3],
    params: &ShadowParams,
    budget: u32,
    shrink: bool,
) -> (Vec<u32>, Counters) {
    let (w, h) = (params.width as usize, params.height as usize);
    assert_eq!(
        gbuffer.len(),
        w * h,
        "G-buffer size does not match the parameters"
    );
    let (tw, th) = (w.div_ceil(4), h.div_ceil(4));
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let rows_per = th.div_ceil(threads).max(1);
    /// One thread's result: (tile index, lane masks) per tile, and its counters.
    type TileRows = (Vec<(usize, [u32; 16])>, Counters);
    let results: Vec<TileRows> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..th)
            .step_by(rows_per)
            .map(|ty0| {
                s.spawn(move || {
                    let mut counters = Counters::default();
                    let mut out = Vec::new();
                    for ty in ty0..(ty0 + rows_per).min(th) {
                        for tx in 0..tw {
                            let frusta = std::array::from_fn(|i| {
                                let (x, y) = (tx * 4 + i % 4, ty * 4 + i / 4);
                                if x < w && y < h {
                                    Frustum::new(&gbuffer[y * w + x], i, light_points, params)
                                } else {
                                    // Outside the image: a done lane, like a sky pixel.
                                    Frustum {
                                        occluded: MASK_SKY,
                                        ..Default::default()
                                    }
                                }
                            });
                            out.push((
                                ty * tw + tx,
                                trace_tile_with(
                                    bvh,
                                    frusta,
                                    params,
                                    budget,
                                    shrink.then_some(light_points),
                                    &mut counters,
                                ),
                            ));
                        }
                    }
                    (out, counters)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("tile thread panicked"))
            .collect()
    });
    let mut masks = vec![0u32; w * h];
    let mut counters = Counters::default();
    for (tiles, c) in results {
        counters += c;
        for (t, lane_masks) in tiles {
            let (tx, ty) = (t % tw, t / tw);
            for (i, m) in lane_masks.iter().enumerate() {
                let (x, y) = (tx * 4 + i % 4, ty * 4 + i / 4);
                if x < w && y < h {
                    masks[y * w + x] = *m;
                }
            }
        }
    }
    (masks, counters)
}
