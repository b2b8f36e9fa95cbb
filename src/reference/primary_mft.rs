//! CPU twin of the multi-frusta primary kernel (`shaders/primary_mft.wgsl`):
//! one 16-lane vector per 16×16 pixel block, lane `i` owning the frustum of
//! the 4×4 pixels `(x0 + k % 4, y0 + k / 4)`, `x0 = 16·bx + 4·(i % 4)`,
//! `y0 = 16·by + 4·(i / 4)`, closest hit per ray. The same culling, the same
//! loop of steps in the same order, the same counters; one lane at a time.
//!
//! Culling is conservative (a box or triangle is dropped only when no ray of
//! the frustum can hit it before its closest hit so far), and each ray is
//! tested with the per-ray tracer's Möller–Trumbore arithmetic and keeps the
//! first hit with a strictly smaller `t`, so every texel equals the per-ray
//! tracer's ([`super::primary::primary_gbuffer`]) — except where two triangles
//! give a ray exactly the same `t` and the two traversal orders meet them in a
//! different order. Why the culling is safe is told at the top of the kernel.

use glam::Vec3;

use super::descend::descend;
use super::primary::hit_texel;
use super::{Hit, intersect_surface};
use crate::bvh::Bvh;
use crate::contract::counters::Counters;
use crate::contract::layout::{BvhNode, BvhTriangle, CameraParams, GBufferTexel};
use crate::pass_inputs::{ShadingData, camera_ray};

pub use crate::contract::ITERATION_BUDGET;
use crate::contract::bvh::STACK_SIZE;
pub use crate::contract::primary::BLOCK;
use crate::contract::primary::{DEPTH_SLACK, T_NONE};

/// One lane's frustum of 16 camera rays and their closest hits so far.
#[derive(Clone, Copy, Debug)]
pub struct PixelFrustum {
    x0: u32,
    y0: u32,
    /// Bit `k`: pixel `k` lies in the image.
    inside: u32,
    dirs: [Vec3; 16],
    /// `(t, u, v)` of the closest hit so far.
    best: [Vec3; 16],
    /// Its triangle, `u32::MAX` for none.
    tri: [u32; 16],
    /// Its `t`: `T_NONE` before a hit, 0 for a pixel outside the image (never hits).
    t: [f32; 16],
    t_max: f32,
    /// Inward normals of the side planes through the eye.
    side: [Vec3; 4],
    /// Corner-ray directions (through the pixel-edge corners of the footprint).
    corner: [Vec3; 4],
}

/// The direction through the pixel-edge point `(ex, ey)`; twin of WGSL `edge_dir`.
fn edge_dir(cam: &CameraParams, ex: u32, ey: u32) -> Vec3 {
    let sx = 2.0 * (ex + cam.origin_x) as f32 / cam.image_width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (ey + cam.origin_y) as f32 / cam.image_height as f32;
    cam.forward + sx * cam.right + sy * cam.up
}

/// Depth of the box's nearest corner along the view direction.
fn box_depth(cam: &CameraParams, node: &BvhNode) -> f32 {
    let p = Vec3::select(cam.forward.cmpgt(Vec3::ZERO), node.bmin, node.bmax);
    cam.forward.dot(p - cam.eye)
}

/// The traversal order's key: the child with the smaller key is visited first.
fn order_key(cam: &CameraParams, node: &BvhNode, order_dir: Vec3) -> f32 {
    ((node.bmin + node.bmax) * 0.5 - cam.eye).dot(order_dir)
}

impl PixelFrustum {
    /// The frustum of the 4×4 pixels from `(x0, y0)`.
    pub fn new(cam: &CameraParams, x0: u32, y0: u32) -> PixelFrustum {
        let mut inside = 0;
        let mut t = [0.0; 16];
        for (k, t) in t.iter_mut().enumerate() {
            let (x, y) = (x0 + k as u32 % 4, y0 + k as u32 / 4);
            if x < cam.width && y < cam.height {
                inside |= 1 << k;
                *t = T_NONE;
            }
        }
        // Clipped to the image; meaningless (and never used) for a lane with no pixel.
        let (x1, y1) = ((x0 + 4).min(cam.width), (y0 + 4).min(cam.height));
        let corner = [
            edge_dir(cam, x0, y0),
            edge_dir(cam, x1, y0),
            edge_dir(cam, x1, y1),
            edge_dir(cam, x0, y1),
        ];
        let centre = corner[0] + corner[2];
        let side = std::array::from_fn(|k| {
            let n = corner[k].cross(corner[(k + 1) % 4]);
            if n.dot(centre) < 0.0 { -n } else { n }
        });
        PixelFrustum {
            x0,
            y0,
            inside,
            dirs: std::array::from_fn(|k| camera_ray(cam, x0 + k as u32 % 4, y0 + k as u32 / 4)),
            best: [Vec3::new(-1.0, 0.0, 0.0); 16],
            tri: [u32::MAX; 16],
            t,
            t_max: if inside != 0 { T_NONE } else { 0.0 },
            side,
            corner,
        }
    }

    /// Whether a ray may meet the box (whose [`box_depth`] is `depth`) before its closest hit.
    fn may_hit_box(&self, cam: &CameraParams, node: &BvhNode, depth: f32) -> bool {
        let outside = |n: Vec3| {
            let p = Vec3::select(n.cmpgt(Vec3::ZERO), node.bmax, node.bmin);
            n.dot(p - cam.eye) < 0.0
        };
        depth <= self.t_max * DEPTH_SLACK
            && !(outside(self.side[0])
                || outside(self.side[1])
                || outside(self.side[2])
                || outside(self.side[3]))
    }

    /// No ray can hit the triangle before its closest hit: depth, side planes, corner rays.
    fn culls_triangle(&self, cam: &CameraParams, tri: &BvhTriangle) -> bool {
        let a0 = tri.v0 - cam.eye;
        let a1 = tri.v1 - cam.eye;
        let a2 = tri.v2 - cam.eye;
        let f = cam.forward;
        let near = f.dot(a0).min(f.dot(a1)).min(f.dot(a2));
        if near > self.t_max * DEPTH_SLACK {
            return true;
        }
        let all_outside = |n: Vec3| n.dot(a0) < 0.0 && n.dot(a1) < 0.0 && n.dot(a2) < 0.0;
        if self.side.iter().any(|&n| all_outside(n)) {
            return true;
        }
        let m0 = a0.cross(a1);
        let m1 = a1.cross(a2);
        let m2 = a2.cross(a0);
        let d = m0.dot(a2);
        if d == 0.0 {
            // The eye lies in the triangle's plane (as far as f32 can tell): left to the ray tests.
            return false;
        }
        let edge_culls = |m: Vec3| {
            let s = self.corner.map(|c| m.dot(c));
            if d > 0.0 {
                s.iter().all(|&x| x < 0.0)
            } else {
                s.iter().all(|&x| x > 0.0)
            }
        };
        edge_culls(m0) || edge_culls(m1) || edge_culls(m2)
    }

    /// The 16 rays against triangle `ix`, each exactly as the per-ray tracer tests it.
    fn test_rays(&mut self, bvh: &Bvh, cam: &CameraParams, tri: &BvhTriangle, ix: u32) {
        for k in 0..16 {
            if let Some((t, u, v)) = intersect_surface(bvh, tri, cam.eye, self.dirs[k], self.t[k]) {
                self.t[k] = t;
                self.best[k] = Vec3::new(t, u, v);
                self.tri[k] = ix;
            }
        }
        self.t_max = self.t.iter().fold(0.0, |a: f32, &b| a.max(b));
    }

    /// Pixel `k`'s position and closest hit, when it lies in the image.
    pub fn pixel(&self, k: usize) -> Option<((u32, u32), Option<Hit>)> {
        (self.inside & (1 << k) != 0).then(|| {
            let hit = (self.tri[k] != u32::MAX).then(|| Hit {
                t: self.best[k].x,
                triangle: self.tri[k],
                u: self.best[k].y,
                v: self.best[k].z,
            });
            ((self.x0 + k as u32 % 4, self.y0 + k as u32 / 4), hit)
        })
    }
}

fn ballot(frusta: &[PixelFrustum; 16], pred: impl Fn(usize, &PixelFrustum) -> bool) -> u32 {
    frusta
        .iter()
        .enumerate()
        .filter(|(i, f)| pred(*i, f))
        .fold(0, |m, (i, _)| m | (1 << i))
}

/// What tracing one block gave.
#[derive(Clone, Debug)]
pub struct BlockResult {
    /// The 16 frusta (lane order) with their rays' closest hits.
    pub frusta: [PixelFrustum; 16],
    /// The vector ran out of its iteration budget (the hits are incomplete).
    pub overflow: bool,
    /// The loop passes it ran: with a budget of at least this many it finishes, with one
    /// fewer it runs out (a test pins the kernel's pass structure by it).
    pub passes: u32,
}

/// The leaf range `(cursor, end)` after entering `node`: its triangles for a leaf,
/// `current` (already used up) for an inner node.
fn enter(bvh: &Bvh, node: u32, current: (u32, u32)) -> (u32, u32) {
    let n = &bvh.nodes[node as usize];
    if n.is_leaf() {
        (n.first, n.first + n.count)
    } else {
        current
    }
}

/// Traces block `(bx, by)` as the kernel's vector does, adding its work to `counters`.
///
/// Each loop iteration is one pass of the kernel's loop: a leaf triangle (in a leaf),
/// then a stack pop (where the leaf is done or the last visit entered nothing), then an
/// inner node's visit (where the vector is at one), each from the state the one before
/// left. After `budget` passes the vector stops with what it has and reports an
/// overflow, as the kernel does.
pub fn trace_block(
    bvh: &Bvh,
    cam: &CameraParams,
    bx: u32,
    by: u32,
    budget: u32,
    counters: &mut Counters,
) -> BlockResult {
    let mut frusta: [PixelFrustum; 16] = std::array::from_fn(|i| {
        PixelFrustum::new(
            cam,
            bx * BLOCK + (i as u32 % 4) * 4,
            by * BLOCK + (i as u32 / 4) * 4,
        )
    });
    let order_dir = edge_dir(cam, bx * BLOCK + 8, by * BLOCK + 8);
    let (mut cursor, mut end) = (0u32, 0u32);
    let mut node = 0u32;
    // Pending subtrees: (node, frusta that want it, its box depth).
    let mut stack: Vec<(u32, u32, f32)> = Vec::with_capacity(STACK_SIZE);
    let mut popping = false;
    counters.box_tests += 1;
    let root = &bvh.nodes[0];
    let root_depth = box_depth(cam, root);
    let mut mask = ballot(&frusta, |_, f| {
        f.inside != 0 && f.may_hit_box(cam, root, root_depth)
    });
    let mut running = mask != 0;
    if root.is_leaf() {
        (cursor, end) = (root.first, root.first + root.count);
    }
    let mut iterations = 0u32;
    let mut overflow = false;
    while running {
        iterations += 1;
        if iterations > budget {
            overflow = true;
            break;
        }
        if cursor < end {
            let tri = &bvh.triangles[cursor as usize];
            let mut survivors = 0u32;
            for (i, f) in frusta.iter_mut().enumerate() {
                if mask & (1 << i) != 0 && !f.culls_triangle(cam, tri) {
                    survivors |= 1 << i;
                    f.test_rays(bvh, cam, tri, cursor);
                }
            }
            counters.triangles_accessed += 1;
            counters.triangles_after_culling += u64::from(survivors != 0);
            counters.triangle_tests += u64::from(survivors.count_ones());
            cursor += 1;
            popping = cursor == end;
        }
        if cursor >= end && popping {
            match stack.pop() {
                None => running = false,
                Some((c, m, depth)) => {
                    // Frusta whose rays have all hit nearer than the box drop it.
                    let m = m & ballot(&frusta, |_, f| depth <= f.t_max * DEPTH_SLACK);
                    if m != 0 {
                        (node, mask, popping) = (c, m, false);
                        (cursor, end) = enter(bvh, node, (cursor, end));
                    }
                }
            }
        }
        if running && cursor >= end && !popping {
            counters.nodes_visited += 1;
            counters.box_tests += 2;
            let l = bvh.nodes[node as usize].first;
            let (left, right) = (&bvh.nodes[l as usize], &bvh.nodes[l as usize + 1]);
            let (dl, dr) = (box_depth(cam, left), box_depth(cam, right));
            let ml = ballot(&frusta, |i, f| {
                mask & (1 << i) != 0 && f.may_hit_box(cam, left, dl)
            });
            let mr = ballot(&frusta, |i, f| {
                mask & (1 << i) != 0 && f.may_hit_box(cam, right, dr)
            });
            // Nearer child first; the other waits on the stack with its frusta.
            let right_first = order_key(cam, right, order_dir) < order_key(cam, left, order_dir);
            let d = descend(l, ml, mr, right_first);
            if let Some((c, m)) = d.later {
                assert!(stack.len() < STACK_SIZE, "BVH deeper than the traversal stack");
                stack.push((c, m, if c == l { dl } else { dr }));
            }
            match d.now {
                Some((c, m)) => {
                    (node, mask) = (c, m);
                    (cursor, end) = enter(bvh, node, (cursor, end));
                }
                None => popping = true,
            }
        }
    }
    BlockResult {
        frusta,
        overflow,
        passes: iterations.min(budget),
    }
}

/// What the multi-frusta primary pass produced.
#[derive(Clone, Debug)]
pub struct MftPrimary {
    /// The G-buffer (row-major, row 0 at the top).
    pub gbuffer: Vec<GBufferTexel>,
    /// The work of all vectors, counted as the kernel counts it with `COUNTERS` on.
    pub counters: Counters,
    /// Pixels of vectors that ran out of their iteration budget (the kernel's status word 0).
    pub overflow_pixels: u64,
}

/// The G-buffer of a whole image traced block by block as the multi-frusta
/// kernel does; block rows are spread over all cores.
pub fn primary_mft_gbuffer(bvh: &Bvh, shading: &ShadingData, cam: &CameraParams, budget: u32) -> MftPrimary {
    let (w, h) = (cam.width as usize, cam.height as usize);
    let (bw, bh) = (cam.width.div_ceil(BLOCK), cam.height.div_ceil(BLOCK));
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let rows_per = (bh as usize).div_ceil(threads).max(1);
    let results: Vec<(Vec<BlockResult>, Counters)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..bh)
            .step_by(rows_per)
            .map(|by0| {
                s.spawn(move || {
                    let mut counters = Counters::default();
                    let mut blocks = Vec::new();
                    for by in by0..(by0 + rows_per as u32).min(bh) {
                        for bx in 0..bw {
                            blocks.push(trace_block(bvh, cam, bx, by, budget, &mut counters));
                        }
                    }
                    (blocks, counters)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("block thread panicked"))
            .collect()
    });
    let mut out = MftPrimary {
        gbuffer: vec![GBufferTexel::default(); w * h],
        counters: Counters::default(),
        overflow_pixels: 0,
    };
    for (blocks, counters) in results {
        out.counters += counters;
        for block in blocks {
            for f in &block.frusta {
                for k in 0..16 {
                    if let Some(((x, y), hit)) = f.pixel(k) {
                        out.gbuffer[y as usize * w + x as usize] =
                            hit_texel(bvh, shading, cam, f.dirs[k], hit);
                        out.overflow_pixels += u64::from(block.overflow);
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::BvhSettings;
    use crate::pass_inputs::camera_params;
    use crate::reference::closest_hit;
    use crate::scene::view::Camera;

    /// xorshift64: deterministic inputs without a dependency.
    fn next(state: &mut u64) -> f32 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 40) as f32 / (1u64 << 24) as f32
    }

    /// `n` random triangles in the unit cube, each up to `size` across.
    fn soup(n: usize, size: f32, seed: u64) -> Vec<[Vec3; 3]> {
        let mut s = seed;
        let p = |s: &mut u64| Vec3::new(next(s), next(s), next(s));
        (0..n)
            .map(|_| {
                let c = p(&mut s);
                [c, c + (p(&mut s) - 0.5) * size, c + (p(&mut s) - 0.5) * size]
            })
            .collect()
    }

    fn camera(w: u32, h: u32) -> CameraParams {
        let cam = Camera {
            eye: Vec3::new(0.5, 0.6, 2.5),
            target: Vec3::splat(0.5),
            up: Vec3::Y,
            fov_y_degrees: 45.0,
        };
        camera_params(&cam, w, h, 1e-4)
    }

    /// Every pixel's hit equals the per-ray tracer's, ties of equal t aside.
    fn assert_hits_match(bvh: &Bvh, cam: &CameraParams) -> usize {
        let mut ties = 0;
        let mut counters = Counters::default();
        for by in 0..cam.height.div_ceil(BLOCK) {
            for bx in 0..cam.width.div_ceil(BLOCK) {
                let block = trace_block(bvh, cam, bx, by, u32::MAX, &mut counters);
                assert!(!block.overflow);
                for f in &block.frusta {
                    for k in 0..16 {
                        let Some(((x, y), hit)) = f.pixel(k) else { continue };
                        let per_ray = closest_hit(bvh, cam.eye, camera_ray(cam, x, y), f32::MAX);
                        if hit != per_ray {
                            let (a, b) = (hit.expect("both hit"), per_ray.expect("both hit"));
                            assert_eq!(a.t, b.t, "({x},{y}): frusta {a:?}, per-ray {b:?}");
                            ties += 1;
                        }
                    }
                }
            }
        }
        ties
    }

    #[test]
    fn frusta_find_the_per_ray_hits() {
        for (n, size, seed) in [(300, 0.3, 1), (2000, 0.1, 2), (50, 1.0, 3)] {
            let bvh = Bvh::build_from_corners(&soup(n, size, seed), &BvhSettings::default()).unwrap();
            for (w, h) in [(37, 23), (64, 64), (16, 1)] {
                let ties = assert_hits_match(&bvh, &camera(w, h));
                assert!(ties * 100 <= (w * h) as usize, "{ties} ties");
            }
        }
    }

    #[test]
    fn a_small_budget_reports_every_pixel_of_its_vectors() {
        let bvh = Bvh::build_from_corners(&soup(500, 0.2, 4), &BvhSettings::default()).unwrap();
        let cam = camera(37, 23);
        let shading = ShadingData {
            triangles: vec![Default::default(); bvh.triangles.len()],
            materials: vec![Default::default()],
            textures: Vec::new(),
            texels: vec![glam::Vec4::ONE],
        };
        let full = primary_mft_gbuffer(&bvh, &shading, &cam, ITERATION_BUDGET);
        assert_eq!(full.overflow_pixels, 0);
        let cut = primary_mft_gbuffer(&bvh, &shading, &cam, 3);
        // Each vector that sees the soup needs more than 3 steps; its pixels are all counted.
        let per_block: Vec<bool> = (0..2)
            .flat_map(|by| (0..3).map(move |bx| (bx, by)))
            .map(|(bx, by)| trace_block(&bvh, &cam, bx, by, 3, &mut Counters::default()).overflow)
            .collect();
        let pixels = |(bx, by): (u32, u32)| u64::from((37 - bx * 16).min(16) * (23 - by * 16).min(16));
        let expected: u64 = (0..6)
            .filter(|&i| per_block[i as usize])
            .map(|i| pixels((i % 3, i / 3)))
            .sum();
        assert!(expected > 37 * 23 / 2, "most blocks overflow: {per_block:?}");
        assert_eq!(cut.overflow_pixels, expected);
        assert!(cut.counters.nodes_visited < full.counters.nodes_visited);
    }
}
