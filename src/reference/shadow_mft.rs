//! CPU twin of the multi-frusta shadow kernel (`shaders/shadow_mft.wgsl`), and only that
//! (long because the kernel is: one file, one kernel, read side by side with it):
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

use glam::{Vec2, Vec3};

use super::descend::descend;
use super::shadow_per_ray::{initial_mask, light_corners};
use crate::bvh::{AlphaMasks, Bvh};
use crate::contract::bvh::{MAX_LEAF_TRIANGLES, STACK_SIZE};
use crate::contract::layout::{BvhNode, BvhTriangle, GBufferTexel, MASK_FULL, MASK_SKY, ShadowParams};
use crate::contract::shadow::{
    BOUNDS_PAD, SHRINK_FLAG, SHRINK_MARGIN, ST_CAND, ST_LEAF_MASK, ST_PENDING, ST_SHRUNK, STATE_WORDS,
};
use crate::contract::suspend::{
    ST_LANES, ST_STACK_MASK, ST_STACK_NODE, ST_STATUS, STACK_COUNT_SHIFT, STATUS_SUSPENDED,
};
use crate::sampling::SAMPLES_PER_SET;

/// The box around the origin and the light rectangle's corners, widened by [`BOUNDS_PAD`].
fn frustum_bounds(o: Vec3, c: &[Vec3; 4]) -> (Vec3, Vec3) {
    let lo = o.min(c[0].min(c[1])).min(c[2].min(c[3]));
    let hi = o.max(c[0].max(c[1])).max(c[2].max(c[3]));
    let pad = lo.abs().max(hi.abs()) * BOUNDS_PAD;
    (lo - pad, hi + pad)
}

/// Inward normals of the planes through `o` and each light edge.
fn side_planes(o: Vec3, c: &[Vec3; 4]) -> [Vec3; 4] {
    let centre = (c[0] + c[2]) * 0.5;
    std::array::from_fn(|k| {
        let n = (c[k] - o).cross(c[(k + 1) % 4] - o);
        if n.dot(centre - o) < 0.0 { -n } else { n }
    })
}

/// The light's corner `c0`, edges `eu = c1 − c0`, `ev = c3 − c0`, and the
/// duals `du`, `dv` that give a point's light coordinates (s, t).
struct LightFrame {
    c0: Vec3,
    eu: Vec3,
    ev: Vec3,
    du: Vec3,
    dv: Vec3,
}

impl LightFrame {
    fn new(params: &ShadowParams) -> LightFrame {
        let c = light_corners(params);
        let (eu, ev) = (c[1] - c[0], c[3] - c[0]);
        let n = eu.cross(ev);
        let inv = 1.0 / n.dot(n);
        LightFrame {
            c0: c[0],
            eu,
            ev,
            du: ev.cross(n) * inv,
            dv: n.cross(eu) * inv,
        }
    }

    /// Light coordinates of a point on the light (the kernel's `point_st`).
    fn st(&self, p: Vec3) -> Vec2 {
        let q = p - self.c0;
        Vec2::new(q.dot(self.du), q.dot(self.dv))
    }

    fn at(&self, st: Vec2) -> Vec3 {
        self.c0 + self.eu * st.x + self.ev * st.y
    }
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
    /// The frustum's bounding box ([`frustum_bounds`]).
    bmin: Vec3,
    bmax: Vec3,
    /// The same rectangle in light coordinates: its lowest and highest (s, t).
    lo: Vec2,
    hi: Vec2,
    /// With [`SHRINK_FLAG`]: the blocked-ray mask `corners` were last shrunk for.
    shrunk_for: u32,
    /// The mask before any triangle (rays below the horizon).
    initial: u32,
    /// Light coordinates (s, t) of the lane's 16 samples: ray j goes from the
    /// origin to `c0 + s·eu + t·ev`.
    st: [Vec2; SAMPLES_PER_SET],
    /// Blocked rays (bits 0..16), or [`MASK_SKY`].
    occluded: u32,
}

impl Frustum {
    /// The frustum of one pixel; `set` is its sample set.
    pub fn new(texel: &GBufferTexel, set: usize, light_points: &[Vec3], params: &ShadowParams) -> Frustum {
        let o = texel.origin;
        let c = light_corners(params);
        let frame = LightFrame::new(params);
        let (bmin, bmax) = frustum_bounds(o, &c);
        Frustum {
            origin: o,
            bmin,
            bmax,
            geo_normal: texel.geo_normal,
            side: side_planes(o, &c),
            corners: c,
            lo: Vec2::ZERO,
            hi: Vec2::ONE,
            shrunk_for: 0,
            st: std::array::from_fn(|j| frame.st(light_points[set * SAMPLES_PER_SET + j])),
            occluded: initial_mask(texel, set, light_points, params),
            initial: initial_mask(texel, set, light_points, params),
        }
    }

    /// The lane of a tile pixel outside the image: done from the start, like a sky pixel.
    pub fn outside() -> Frustum {
        Frustum {
            occluded: MASK_SKY,
            ..Default::default()
        }
    }

    /// Frustum shrinking, the paper's "CR" (§5.3): recomputes the corner rays
    /// through the corners of the light-plane rectangle (s, t ranges, widened by
    /// [`SHRINK_MARGIN`]) that holds the samples not yet blocked in `blocked`. Rays
    /// already blocked need no more tests, so culling against the smaller frustum
    /// gives the same mask with fewer triangle tests.
    pub fn shrink_to(&mut self, blocked: u32, params: &ShadowParams) {
        let frame = LightFrame::new(params);
        let (mut lo, mut hi) = (Vec2::ONE, Vec2::ZERO);
        for (j, st) in self.st.iter().enumerate() {
            if blocked & (1 << j) == 0 {
                lo = lo.min(*st);
                hi = hi.max(*st);
            }
        }
        lo = (lo - SHRINK_MARGIN).max(Vec2::ZERO);
        hi = (hi + SHRINK_MARGIN).min(Vec2::ONE);
        self.corners = [
            frame.at(lo),
            frame.at(Vec2::new(hi.x, lo.y)),
            frame.at(hi),
            frame.at(Vec2::new(lo.x, hi.y)),
        ];
        (self.lo, self.hi) = (lo, hi);
        self.side = side_planes(self.origin, &self.corners);
        (self.bmin, self.bmax) = frustum_bounds(self.origin, &self.corners);
        self.shrunk_for = blocked | SHRINK_FLAG;
    }

    /// Shrinks after a leaf if a ray was blocked since the last time (or since the start).
    fn shrink_after_leaf(&mut self, params: &ShadowParams) {
        let last = if self.shrunk_for & SHRINK_FLAG != 0 {
            self.shrunk_for & MASK_FULL
        } else {
            self.initial
        };
        if !self.is_done() && self.occluded != last {
            self.shrink_to(self.occluded, params);
        }
    }

    /// No ray left to decide (all blocked, or a sky pixel).
    pub fn is_done(&self) -> bool {
        self.occluded & MASK_SKY != 0 || self.occluded & MASK_FULL == MASK_FULL
    }
}

/// Whether any ray of the frustum may hit the box: false only when the box
/// misses the frustum's bounding box or lies wholly outside one of its six
/// planes (p-vertex test).
pub fn frustum_may_hit_box(f: &Frustum, node: &BvhNode, params: &ShadowParams) -> bool {
    if node.bmin.cmpgt(f.bmax).any() || node.bmax.cmplt(f.bmin).any() {
        return false;
    }
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
/// tetrahedron origin–triangle): the ray to light point `p` passes through the
/// triangle when the `m_e·(p − origin)` all have the sign of `D` (edges
/// inclusive: a shared edge, whose corners the two triangles store as the
/// same bits, gives them exactly negated normals and edge functions, so a ray
/// on it hits both and none slips between them — tested on a closed room in
/// `tests/cpu/shadow_mft.rs`), and it reaches the triangle's plane at `t = D / Σ m_e·(p −
/// origin)`, so it hits when `|D| < t_max·|Σ m_e·(p − origin)|`. With `p = c0 +
/// s·eu + t·ev` each `m_e·(p − origin)` is an edge function `a + b·s + c·t` of
/// the sample's light coordinates: three dot products per edge and triangle,
/// then two multiply-adds per edge and ray.
///
/// The hit bits of an alpha-tested triangle leave out the rays its mask lets pass
/// ([`AlphaMasks::passes`] at `EdgeFunctions::weights`).
pub fn frustum_test_triangle(
    f: &Frustum,
    tri: &BvhTriangle,
    params: &ShadowParams,
    alpha: &AlphaMasks,
) -> TriangleOutcome {
    let o = f.origin;
    let (v0, v1, v2) = (tri.v0, tri.v1, tri.v2);
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
    let e = EdgeFunctions::new([m0, m1, m2], d, o, params);
    // Corner rays: if the frustum's whole light rectangle lies outside one
    // edge plane, so does every ray (the paper's corner-ray culling, shared
    // origin). Edge functions are monotonic in s and t, also as rounded, so a
    // sample inside the rectangle cannot be inside the plane then.
    let corners = [
        e.at(f.lo),
        e.at(Vec2::new(f.hi.x, f.lo.y)),
        e.at(f.hi),
        e.at(Vec2::new(f.lo.x, f.hi.y)),
    ];
    let highest = corners[0].max(corners[1]).max(corners[2].max(corners[3]));
    if highest.cmplt(Vec3::ZERO).any() {
        return TriangleOutcome::Culled;
    }
    let hits =
        f.st.iter()
            .enumerate()
            .filter(|(_, st)| e.hit(**st, params.t_max) && !alpha.passes(tri, e.weights(**st)))
            .fold(0u32, |m, (j, _)| m | 1 << j);
    TriangleOutcome::Tested(hits)
}

/// A triangle's three edge functions over the light seen from one origin,
/// one per component: `E(s, t) = a + b·s + c·t` (the kernel's `EdgeFunctions`),
/// negated when `D < 0` so that inside means all three ≥ 0.
struct EdgeFunctions {
    a: Vec3,
    b: Vec3,
    c: Vec3,
    /// `|D|`.
    limit: f32,
}

impl EdgeFunctions {
    fn new(m: [Vec3; 3], d: f32, o: Vec3, params: &ShadowParams) -> EdgeFunctions {
        let c = light_corners(params);
        let q = c[0] - o;
        let (eu, ev) = (c[1] - c[0], c[3] - c[0]);
        let sg = if d > 0.0 { 1.0 } else { -1.0 };
        let dots = |v: Vec3| Vec3::new(m[0].dot(v), m[1].dot(v), m[2].dot(v)) * sg;
        EdgeFunctions {
            a: dots(q),
            b: dots(eu),
            c: dots(ev),
            limit: d.abs(),
        }
    }

    fn at(&self, st: Vec2) -> Vec3 {
        self.a + self.b * st.x + self.c * st.y
    }

    /// The barycentric weights (corners 0, 1, 2) where the ray to light coordinates `st`
    /// meets the triangle's plane: edge function `k` is opposite corner `k + 2`.
    fn weights(&self, st: Vec2) -> [f32; 3] {
        let v = self.at(st);
        let inv = 1.0 / (v.x + v.y + v.z);
        [v.y * inv, v.z * inv, v.x * inv]
    }

    /// The ray to light coordinates `st` hits the triangle before `t_max`.
    fn hit(&self, st: Vec2, t_max: f32) -> bool {
        let v = self.at(st);
        v.cmpge(Vec3::ZERO).all() && self.limit < t_max * (v.x + v.y + v.z)
    }
}

pub use super::counters::Counters;

/// The traversal state of one vector: what the GPU kernel saves when it
/// suspends and reloads when it resumes.
///
/// Traversal and leaves are two stages with one leaf between them: the
/// traversal walks on to the next leaf (`pending`) while the leaf stage tests
/// the current one (`cursor..end` for `leaf_mask`), so that a kernel step can
/// do both (see `shaders/shadow_mft.wgsl`).
#[derive(Clone, Debug, Default)]
struct VectorState {
    /// First child of the inner node to visit next (when not popping): the kernel's
    /// `t_children`, set only when the traversal enters an inner node.
    children: u32,
    /// Frusta that entered that node (or the last leaf found).
    mask: u32,
    /// Next triangle of the current leaf.
    cursor: u32,
    /// End of the current leaf's triangles.
    end: u32,
    /// Frusta that entered the current leaf.
    leaf_mask: u32,
    /// The leaf the traversal found next, waiting for the leaf stage: first
    /// triangle, end, frusta.
    pending: Option<(u32, u32, u32)>,
    /// Frusta not yet done.
    alive: u32,
    /// Pending subtrees as the kernel's stack words: the node's `first`, and the frusta
    /// that wanted it with its `count << STACK_COUNT_SHIFT`.
    stack: Vec<(u32, u32)>,
    /// The next traversal step pops the stack.
    popping: bool,
    /// The stack ran empty: the traversal has found every leaf.
    traversal_done: bool,
}

fn ballot(frusta: &[Frustum; 16], pred: impl Fn(usize, &Frustum) -> bool) -> u32 {
    frusta
        .iter()
        .enumerate()
        .filter(|(i, f)| pred(*i, f))
        .fold(0, |m, (i, _)| m | (1 << i))
}

impl VectorState {
    /// Moves to node `c` with frustum mask `m`; a leaf waits in `pending` and the
    /// traversal goes on from the stack.
    fn enter(&mut self, bvh: &Bvh, c: u32, m: u32) {
        let n = &bvh.nodes[c as usize];
        self.enter_at(n.first, n.count, m);
    }

    /// As [`Self::enter`], for the node whose `first` and `count` are given (a stack entry).
    fn enter_at(&mut self, first: u32, count: u32, m: u32) {
        self.mask = m;
        if count > 0 {
            self.pending = Some((first, first + count, m));
            self.popping = true;
        } else {
            self.children = first;
        }
    }

    /// The leaf stage takes the pending leaf when it has none.
    fn take_pending(&mut self, cand: u32) {
        if cand == 0 && self.cursor >= self.end {
            if let Some((first, end, m)) = self.pending.take() {
                self.cursor = first;
                self.end = end;
                self.leaf_mask = m;
            }
        }
    }
}

/// How the twin runs a tile, as the kernel was compiled and dispatched.
#[derive(Clone, Copy, Debug)]
pub struct TileOptions {
    /// Loop steps per dispatch (the kernel's `iteration_budget`): when they run
    /// out, the state is kept and traversal resumes, exactly as the GPU resumes
    /// a suspended tile in its next dispatch.
    pub budget: u32,
    /// Frustum shrinking ([`Frustum::shrink_to`]) after every leaf (`SHRINK`).
    pub shrink: bool,
    /// Transposed leaves (`LEAF_TRANSPOSED`): one triangle per step, then one
    /// more step per frustum left after culling; otherwise up to two triangles
    /// per step. The masks are the same either way; the steps (and so the
    /// suspensions) are not.
    pub transposed: bool,
}

impl TileOptions {
    /// Per-lane leaves without shrinking, `budget` steps per dispatch.
    pub fn with_budget(budget: u32) -> TileOptions {
        TileOptions {
            budget,
            shrink: false,
            transposed: false,
        }
    }
}

/// The next triangle of the current leaf against every frustum that entered
/// it and is not done; returns the frusta that were left after culling and the
/// rays of each that hit it (per-lane leaves OR them in at once; transposed
/// leaves one candidate frustum per kernel step).
fn leaf_triangle(
    bvh: &Bvh,
    st: &mut VectorState,
    frusta: &[Frustum; 16],
    params: &ShadowParams,
    counters: &mut Counters,
) -> (u32, [u32; 16]) {
    let tri = &bvh.triangles[st.cursor as usize];
    st.cursor += 1;
    counters.triangles_accessed += 1;
    let mut survived = 0u32;
    let mut hits = [0u32; 16];
    for (i, f) in frusta.iter().enumerate() {
        if st.leaf_mask & (1 << i) != 0 && !f.is_done() {
            if let TriangleOutcome::Tested(h) = frustum_test_triangle(f, tri, params, &bvh.alpha) {
                survived |= 1 << i;
                hits[i] = h;
            }
        }
    }
    counters.triangle_tests += u64::from(survived.count_ones());
    counters.triangles_after_culling += u64::from(survived != 0);
    (survived, hits)
}

/// Per-lane leaves: [`leaf_triangle`] with every survivor's hits OR-ed in.
fn per_lane_triangle(
    bvh: &Bvh,
    st: &mut VectorState,
    frusta: &mut [Frustum; 16],
    params: &ShadowParams,
    counters: &mut Counters,
) {
    let (_, hits) = leaf_triangle(bvh, st, frusta, params, counters);
    for (f, h) in frusta.iter_mut().zip(hits) {
        f.occluded |= h;
    }
}

/// One step of the traversal stage, unless a found leaf waits or it is done: pop
/// the stack if it must, then visit the inner node it is at (both child boxes
/// against every frustum that entered it), into the child [`right_first`] picks.
fn traversal_step(
    bvh: &Bvh,
    st: &mut VectorState,
    frusta: &[Frustum; 16],
    params: &ShadowParams,
    counters: &mut Counters,
) {
    if !st.traversal_done && st.pending.is_none() && st.popping {
        match st.stack.pop() {
            None => st.traversal_done = true,
            Some((first, word)) if word & st.alive != 0 => {
                st.popping = false;
                st.enter_at(first, word >> STACK_COUNT_SHIFT, word & st.alive);
            }
            Some(_) => {}
        }
    }
    if !st.traversal_done && st.pending.is_none() && !st.popping {
        let l = st.children;
        counters.nodes_visited += 1;
        counters.box_tests += 2;
        let mask = st.mask;
        let wants = |c: u32| {
            ballot(frusta, |i, f| {
                mask & (1 << i) != 0 && !f.is_done() && frustum_may_hit_box(f, &bvh.nodes[c as usize], params)
            })
        };
        let (ml, mr) = (wants(l), wants(l + 1));
        let d = descend(l, ml, mr, right_first(bvh, l, params));
        if let Some((c, m)) = d.later {
            assert!(st.stack.len() < STACK_SIZE, "BVH deeper than the traversal stack");
            let n = &bvh.nodes[c as usize];
            assert!(
                n.count <= MAX_LEAF_TRIANGLES,
                "a leaf larger than the stack word holds"
            );
            st.stack.push((n.first, m | n.count << STACK_COUNT_SHIFT));
        }
        match d.now {
            Some((c, m)) => st.enter(bvh, c, m),
            None => st.popping = true,
        }
    }
}

/// The area of a box's shadow along the light's normal: the area it covers
/// seen from the light, which a shadow ray is the likelier to cross the larger it is.
fn shadow_area(n: &BvhNode, params: &ShadowParams) -> f32 {
    let e = n.bmax - n.bmin;
    let a = params.light_normal.abs();
    a.x * e.y * e.z + a.y * e.x * e.z + a.z * e.x * e.y
}

/// The traversal's order: whether child `l + 1` comes first, the child with
/// the larger [`shadow_area`] (on a tie, the one whose centre is nearer the
/// light's plane). Blockers found early stop rays and shrink the frusta
/// sooner (see `shaders/shadow_mft.wgsl`).
fn right_first(bvh: &Bvh, l: u32, params: &ShadowParams) -> bool {
    let (left, right) = (&bvh.nodes[l as usize], &bvh.nodes[l as usize + 1]);
    let (al, ar) = (shadow_area(left, params), shadow_area(right, params));
    if ar != al {
        return ar > al;
    }
    let key = |n: &BvhNode| params.light_normal.dot((n.bmin + n.bmax) * 0.5);
    key(right) < key(left)
}

/// Traces one 4×4 tile's 16 frusta under `options` and returns the 16 occlusion masks
/// (lane order): dispatch after dispatch ([`dispatch_tile`]), each
/// suspended one resumed from the state it saved, as the GPU pass resumes its tiles.
///
/// Each loop iteration is one step of the kernel, which may do, in this
/// order: two traversal steps (each a stack pop and an inner node), one or two
/// triangles of the current leaf, and the end of a leaf (see
/// `shaders/shadow_mft.wgsl` for why).
pub fn trace_tile(
    bvh: &Bvh,
    frusta: [Frustum; 16],
    params: &ShadowParams,
    options: &TileOptions,
    counters: &mut Counters,
) -> [u32; 16] {
    let mut run = dispatch_tile(bvh, &frusta, None, params, options, counters);
    loop {
        match run {
            TileRun::Finished(masks) => return masks,
            TileRun::Suspended(saved) => {
                counters.suspensions += 1;
                run = dispatch_tile(bvh, &frusta, Some(&saved), params, options, counters);
            }
        }
    }
}

/// What one dispatch of the kernel leaves of a tile.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TileRun {
    /// The tile finished: its 16 occlusion masks (lane order).
    Finished([u32; 16]),
    /// The budget ran out: the state the kernel saves, word for word.
    Suspended(Box<[u32; STATE_WORDS]>),
}

/// The state words the kernel saves when it suspends.
fn save(st: &VectorState, frusta: &[Frustum; 16], cand: u32) -> Box<[u32; STATE_WORDS]> {
    let mut w = Box::new([0u32; STATE_WORDS]);
    w[ST_STATUS] = STATUS_SUSPENDED;
    w[1] = st.children;
    w[2] = st.mask;
    w[3] = st.cursor;
    w[4] = st.end;
    w[5] = st.alive;
    w[6] = st.stack.len() as u32;
    w[7] = u32::from(st.popping) | u32::from(st.traversal_done) << 1;
    for (i, f) in frusta.iter().enumerate() {
        w[ST_LANES + i] = f.occluded;
        w[ST_SHRUNK + i] = f.shrunk_for;
    }
    for (i, &(first, word)) in st.stack.iter().enumerate() {
        w[ST_STACK_NODE + i] = first;
        w[ST_STACK_MASK + i] = word;
    }
    w[ST_CAND] = cand;
    w[ST_LEAF_MASK] = st.leaf_mask;
    let (first, end, mask) = st.pending.unwrap_or((0, 0, 0));
    w[ST_PENDING..ST_PENDING + 3].copy_from_slice(&[first, end, mask]);
    w
}

/// The state a resumed dispatch starts from: the saved words read back the way the
/// kernel reads them, into the tile's fresh frusta (each lane's mask restored and, if
/// it had shrunk, shrunk again to the same rectangle). Returns the state, the frusta
/// and the transposed leaf's candidates.
fn resume(
    saved: &[u32; STATE_WORDS],
    fresh: &[Frustum; 16],
    params: &ShadowParams,
    shrink: bool,
) -> (VectorState, [Frustum; 16], u32) {
    let depth = saved[6] as usize;
    let st = VectorState {
        children: saved[1],
        mask: saved[2],
        cursor: saved[3],
        end: saved[4],
        alive: saved[5],
        popping: saved[7] & 1 != 0,
        traversal_done: saved[7] & 2 != 0,
        leaf_mask: saved[ST_LEAF_MASK],
        pending: (saved[ST_PENDING + 1] != 0)
            .then(|| (saved[ST_PENDING], saved[ST_PENDING + 1], saved[ST_PENDING + 2])),
        stack: (0..depth)
            .map(|i| (saved[ST_STACK_NODE + i], saved[ST_STACK_MASK + i]))
            .collect(),
    };
    let mut frusta = *fresh;
    for (i, f) in frusta.iter_mut().enumerate() {
        f.occluded = saved[ST_LANES + i];
        let shrunk_for = saved[ST_SHRUNK + i];
        if shrink && shrunk_for & SHRINK_FLAG != 0 {
            f.shrink_to(shrunk_for & MASK_FULL, params);
        }
    }
    (st, frusta, saved[ST_CAND])
}

/// One dispatch of the kernel over one tile: from `fresh` (the tile's frusta as
/// [`Frustum::new`] builds them), or resumed from `saved`; runs until the tile
/// finishes or `options.budget` steps are spent.
pub fn dispatch_tile(
    bvh: &Bvh,
    fresh: &[Frustum; 16],
    saved: Option<&[u32; STATE_WORDS]>,
    params: &ShadowParams,
    options: &TileOptions,
    counters: &mut Counters,
) -> TileRun {
    // Transposed leaves: the frusta still to be tested (one step each) against
    // triangle cursor − 1, and their rays that hit it, OR-ed in one frustum per step as
    // the kernel's ballots do.
    let mut cand_hits = [0u32; 16];
    let (mut st, mut frusta, mut cand, mut running) = match saved {
        Some(words) => {
            let (st, frusta, cand) = resume(words, fresh, params, options.shrink);
            if cand != 0 {
                // The kernel reloads the triangle and tests the candidates left.
                let tri = &bvh.triangles[st.cursor as usize - 1];
                for (i, f) in frusta.iter().enumerate().filter(|(i, _)| cand & (1 << i) != 0) {
                    if let TriangleOutcome::Tested(h) = frustum_test_triangle(f, tri, params, &bvh.alpha) {
                        cand_hits[i] = h;
                    }
                }
            }
            (st, frusta, cand, true)
        }
        None => {
            let mut frusta = *fresh;
            if options.shrink {
                // Start from the rectangle of the samples themselves (rays below the
                // horizon left out): 1–7 % fewer steps on the shared scenes.
                for f in frusta.iter_mut().filter(|f| !f.is_done()) {
                    f.shrink_to(f.occluded, params);
                }
            }
            let mut st = VectorState {
                alive: ballot(&frusta, |_, f| !f.is_done()),
                stack: Vec::with_capacity(STACK_SIZE),
                ..Default::default()
            };
            let root_mask = ballot(&frusta, |_, f| {
                !f.is_done() && frustum_may_hit_box(f, &bvh.nodes[0], params)
            });
            counters.box_tests += 1;
            st.enter(bvh, 0, root_mask);
            (st, frusta, 0, root_mask != 0)
        }
    };
    let mut iterations = 0u32;
    while running {
        if iterations >= options.budget {
            return TileRun::Suspended(save(&st, &frusta, cand));
        }
        iterations += 1;
        counters.traversal_steps += 1;
        st.take_pending(cand);
        // The traversal stage, twice: it takes about as many steps as the leaves.
        traversal_step(bvh, &mut st, &frusta, params, counters);
        traversal_step(bvh, &mut st, &frusta, params, counters);
        // The leaf stage: up to two triangles (transposed: one, then its candidates).
        st.take_pending(cand);
        let in_leaf = cand != 0 || st.cursor < st.end;
        if options.transposed && cand == 0 && st.cursor < st.end {
            (cand, cand_hits) = leaf_triangle(bvh, &mut st, &frusta, params, counters);
        }
        if !options.transposed && st.cursor < st.end {
            per_lane_triangle(bvh, &mut st, &mut frusta, params, counters);
        }
        if !options.transposed && st.cursor < st.end {
            per_lane_triangle(bvh, &mut st, &mut frusta, params, counters);
        }
        if options.transposed {
            // The kernel's inner loop: a step per candidate, lowest first, and one that
            // ends it.
            loop {
                iterations += 1;
                counters.traversal_steps += 1;
                if cand == 0 || iterations >= options.budget {
                    break;
                }
                let f = cand.trailing_zeros() as usize;
                frusta[f].occluded |= cand_hits[f];
                cand &= cand - 1;
            }
        }
        if in_leaf && cand == 0 && st.cursor == st.end {
            if options.shrink {
                for f in frusta.iter_mut() {
                    f.shrink_after_leaf(params);
                }
            }
            st.alive = ballot(&frusta, |_, f| !f.is_done());
            running = st.alive != 0;
        }
        if st.traversal_done && st.pending.is_none() && cand == 0 && st.cursor >= st.end {
            running = false;
        }
    }
    TileRun::Finished(frusta.map(|f| f.occluded))
}

/// Occlusion masks of a whole G-buffer (row-major) with multi-frusta tracing as the
/// kernel runs under `options`, tile by tile; tiles are spread over all cores. The masks
/// do not depend on the leaf mode; the counters do (transposed leaves take more steps per
/// leaf, so the traversal stage runs ahead of them by other nodes).
pub fn mft_masks(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    light_points: &[Vec3],
    params: &ShadowParams,
    options: &TileOptions,
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
                                    Frustum::outside()
                                }
                            });
                            out.push((
                                ty * tw + tx,
                                trace_tile(bvh, frusta, params, options, &mut counters),
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
