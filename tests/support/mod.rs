//! Helpers shared by the integration tests: a deterministic random generator,
//! random triangle soups and scenes built in code.
#![allow(dead_code)] // each test binary uses a different subset

use std::path::PathBuf;

use glam::{Mat4, Vec2, Vec3};
use penumbra::scene::{Instance, LoadWarnings, Material, Scene, SceneTriangle};

pub mod bvh;
pub mod gpu;

/// PCG32 (O'Neill): small, deterministic, good enough for test inputs.
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        let mut r = Rng(seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407));
        r.next_u32();
        r
    }

    /// Next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// Uniform in the box [lo, hi).
    pub fn in_box(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }

    /// Uniform direction on the unit sphere.
    pub fn direction(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// `n` random triangles with corners in the unit cube, each at most `size` across.
pub fn random_soup(rng: &mut Rng, n: usize, size: f32) -> Vec<[Vec3; 3]> {
    (0..n)
        .map(|_| {
            let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
            [c, c + rng.direction() * size, c + rng.direction() * size]
        })
        .collect()
}

/// A flat `n`×`n` grid of quads (2 triangles each) in the y = 0 plane over [0, 1]².
pub fn flat_grid(n: usize) -> Vec<[Vec3; 3]> {
    let mut out = Vec::new();
    let s = 1.0 / n as f32;
    for i in 0..n {
        for j in 0..n {
            let p = |a: usize, b: usize| Vec3::new(a as f32 * s, 0.0, b as f32 * s);
            out.push([p(i, j), p(i, j + 1), p(i + 1, j)]);
            out.push([p(i + 1, j), p(i, j + 1), p(i + 1, j + 1)]);
        }
    }
    out
}

/// Distance between segments `p1q1` and `p2q2` (Ericson, Real-Time Collision Detection, 5.1.9).
pub fn segment_segment_distance(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> f32 {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let (s, t);
    if a <= f32::EPSILON && e <= f32::EPSILON {
        return r.length();
    }
    if a <= f32::EPSILON {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(r);
        if e <= f32::EPSILON {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let s0 = if denom != 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            } else {
                t = t0;
                s = s0;
            }
        }
    }
    ((p1 + d1 * s) - (p2 + d2 * t)).length()
}

/// Distance from `p` to triangle `abc` (Ericson 5.1.5).
pub fn point_triangle_distance(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (p - a).length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (p - b).length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).length();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (p - c).length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (p - (a + ab * v + ac * w)).length()
}

/// Why a differing ray was excused by [`compare_masks`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Excuse {
    /// The ray passes within the tolerance of an edge of a triangle other than its
    /// origin's own.
    Edge,
    /// The ray's origin lies within the tolerance of a triangle other than its own
    /// (a concave corner, a contact).
    Origin,
    /// The ray's end lies within the tolerance of a triangle.
    End,
}

/// Why a shadow ray from `origin` to `end` may be decided differently by two correct
/// tracers: it passes within `tol` of an edge of some triangle, or one of its endpoints
/// lies within `tol` of a triangle — in each case a triangle other than `own` (the
/// scene index of the triangle the origin was offset from, when known). The origin sits
/// a whole ray offset above its own triangle and moves away from its plane, so its own
/// triangle (and any coplanar neighbour) cannot excuse a ray at a tolerance far below
/// the offset; `None`: no reason, the tracers disagree.
pub fn excuse(
    corners: &[[Vec3; 3]],
    own: Option<usize>,
    origin: Vec3,
    end: Vec3,
    tol: f32,
) -> Option<Excuse> {
    let others = || {
        corners
            .iter()
            .enumerate()
            .filter(|(i, _)| Some(*i) != own)
            .map(|(_, c)| c)
    };
    if others().any(|c| (0..3).any(|e| segment_segment_distance(origin, end, c[e], c[(e + 1) % 3]) <= tol)) {
        return Some(Excuse::Edge);
    }
    if others().any(|c| point_triangle_distance(origin, c[0], c[1], c[2]) <= tol) {
        return Some(Excuse::Origin);
    }
    if others().any(|c| point_triangle_distance(end, c[0], c[1], c[2]) <= tol) {
        return Some(Excuse::End);
    }
    None
}

/// The tolerance within which two correct tracers may decide a ray differently: 2⁻²⁰
/// (≈ 1e-6) of the scene's size `scale` (its diagonal, or its largest coordinate when
/// that is larger). f32 stores a coordinate of that size to 2⁻²⁴ of it; the ray–triangle
/// tests (Möller–Trumbore, the frusta's edge functions) round a few times more, so rays
/// that two of them decide differently pass within a few such steps (≤ 16) of an edge or
/// start or end that close to a triangle. It is 1/100 of the ray offset
/// ([`penumbra::pass_inputs::RAY_OFFSET_FRACTION`] = 1e-4 of the diagonal), so no ray is excused
/// merely for starting on its own surface.
pub fn edge_tolerance(scene: &Scene) -> f32 {
    let b = scene.bounds();
    let largest = b.min.abs().max(b.max.abs()).max_element();
    b.diagonal().max(largest) / (1u32 << 20) as f32
}

/// The outcome of [`compare_masks`].
#[derive(Clone, Debug, Default)]
pub struct MaskComparison {
    /// Rays decided differently.
    pub differing: usize,
    /// Rays compared (16 per pixel that sees geometry).
    pub total: usize,
    /// Differing rays excused because they graze an edge ([`Excuse::Edge`]).
    pub near_edge: usize,
    /// … because their origin lies on another triangle ([`Excuse::Origin`]).
    pub near_origin: usize,
    /// … because their end lies on a triangle ([`Excuse::End`]).
    pub near_end: usize,
    /// The differing rays no excuse explains, described.
    pub unexplained: Vec<String>,
}

impl std::fmt::Display for MaskComparison {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} of {} rays differ: excused {} near an edge, {} starting and {} ending on another \
             triangle; {} unexplained",
            self.differing,
            self.total,
            self.near_edge,
            self.near_origin,
            self.near_end,
            self.unexplained.len()
        )
    }
}

#[allow(clippy::too_many_arguments)]
/// Compares two sets of occlusion masks ray by ray, excusing a differing ray only as
/// [`excuse`] says (`corners` in scene order; `scene_index(texel.triangle)` names the
/// origin's own triangle, `None` where the G-buffer does not know it).
pub fn compare_masks(
    a: &[u32],
    b: &[u32],
    gbuffer: &[penumbra::contract::layout::GBufferTexel],
    width: u32,
    light_points: &[Vec3],
    params: &penumbra::contract::layout::ShadowParams,
    corners: &[[Vec3; 3]],
    scene_index: &dyn Fn(u32) -> Option<usize>,
    tol: f32,
) -> MaskComparison {
    let mut out = MaskComparison::default();
    for (p, (&ma, &mb)) in a.iter().zip(b).enumerate() {
        if (ma | mb) & penumbra::contract::layout::MASK_SKY != 0 {
            if ma != mb {
                out.unexplained
                    .push(format!("pixel {p}: sky flag differs ({ma:#x} vs {mb:#x})"));
            }
            continue;
        }
        out.total += 16;
        let diff = (ma ^ mb) & 0xffff;
        out.differing += diff.count_ones() as usize;
        let (x, y) = (p as u32 % width, p as u32 / width);
        let set = penumbra::sampling::pixel_set(x, y);
        let own = scene_index(gbuffer[p].triangle);
        for j in 0..16 {
            if diff & (1 << j) != 0 {
                let o = gbuffer[p].origin;
                let end = o + (light_points[set * 16 + j] - o) * params.t_max;
                match excuse(corners, own, o, end, tol) {
                    Some(Excuse::Edge) => out.near_edge += 1,
                    Some(Excuse::Origin) => out.near_origin += 1,
                    Some(Excuse::End) => out.near_end += 1,
                    None => out.unexplained.push(format!(
                        "pixel ({x},{y}) ray {j}: {} vs {}",
                        ma >> j & 1,
                        mb >> j & 1
                    )),
                }
            }
        }
    }
    out
}

/// The scene index of a G-buffer texel's triangle (leaf order in `bvh`), `None` for
/// texels that name none (misses, and host G-buffers that do not know it).
pub fn own_triangle(bvh: &penumbra::bvh::Bvh) -> impl Fn(u32) -> Option<usize> + '_ {
    |t| bvh.triangles.get(t as usize).map(|t| t.scene_index as usize)
}

/// [`compare_masks`] of two tracings of `view`'s 16 interleaved rays per pixel over
/// `gbuffer` (`width` wide) in `scene` (BVH `bvh`), at [`edge_tolerance`].
#[allow(clippy::too_many_arguments)]
pub fn compare_view_masks(
    a: &[u32],
    b: &[u32],
    scene: &Scene,
    bvh: &penumbra::bvh::Bvh,
    view: &penumbra::scene::view::View,
    gbuffer: &[penumbra::contract::layout::GBufferTexel],
    width: u32,
) -> MaskComparison {
    let height = a.len() as u32 / width;
    let params = penumbra::reference::shadow_per_ray::shadow_params(&view.light, width, height);
    let points = penumbra::sampling::light_points(&view.light);
    let corners: Vec<_> = scene.triangles.iter().map(|t| t.positions).collect();
    compare_masks(
        a,
        b,
        gbuffer,
        width,
        &points,
        &params,
        &corners,
        &own_triangle(bvh),
        edge_tolerance(scene),
    )
}

/// The shadow-mask acceptance check of the renderer issue: `masks` against the
/// per-ray oracle computed from the same `gbuffer`; at most 0.1 % of rays may
/// differ, each excused by [`excuse`] at [`edge_tolerance`]. Prints the counts.
/// Returns (differing rays, rays, oracle masks).
#[allow(clippy::too_many_arguments)]
pub fn assert_masks_match_oracle(
    label: &str,
    scene: &Scene,
    bvh: &penumbra::bvh::Bvh,
    view: &penumbra::scene::view::View,
    gbuffer: &[penumbra::contract::layout::GBufferTexel],
    masks: &[u32],
    width: u32,
    height: u32,
) -> (usize, usize, Vec<u32>) {
    use penumbra::reference::shadow_per_ray::{per_ray_masks, shadow_params};
    let params = shadow_params(&view.light, width, height);
    let points = penumbra::sampling::light_points(&view.light);
    let oracle = per_ray_masks(bvh, gbuffer, &points, &params);
    let c = compare_view_masks(&oracle, masks, scene, bvh, view, gbuffer, width);
    eprintln!("{label}: against the per-ray oracle: {c}");
    assert!(
        c.unexplained.is_empty(),
        "{label}: {c}: {:?}",
        &c.unexplained[..c.unexplained.len().min(10)]
    );
    assert!(c.differing * 1000 <= c.total, "{label}: {c}");
    (c.differing, c.total, oracle)
}

/// A scene built in code: one triangle list, each triangle with its material
/// index, flat normals and one white-ish material per entry of `colors`.
pub fn scene_from_triangles(triangles: &[([Vec3; 3], u32)], colors: &[[f32; 3]]) -> Scene {
    Scene {
        source: PathBuf::from("generated-in-test"),
        triangles: triangles
            .iter()
            .map(|&(positions, material)| {
                let [a, b, c] = positions;
                let n = (b - a).cross(c - a).normalize_or(Vec3::Y);
                SceneTriangle {
                    positions,
                    normals: [n; 3],
                    uvs: [Vec2::ZERO; 3],
                    material,
                    instance: 0,
                }
            })
            .collect(),
        materials: colors
            .iter()
            .map(|&[r, g, b]| Material {
                base_color_factor: [r, g, b, 1.0],
                ..Material::default()
            })
            .collect(),
        images: Vec::new(),
        instances: vec![Instance {
            node: 0,
            name: None,
            world_from_object: Mat4::IDENTITY,
        }],
        camera: None,
        warnings: LoadWarnings::default(),
    }
}

/// A closed box room seen from inside: each of its six faces an `n`×`n` grid of quads
/// (12·n² triangles), facing inward, turned about a skew axis so that no coordinate is
/// round, half-size `half` around `centre`. Every grid point is computed once from its
/// integer lattice coordinates, so the copies of a vertex that several triangles share
/// (along the box's edges too) are the same f32 values.
pub fn closed_room(n: usize, half: f32, centre: Vec3) -> Vec<([Vec3; 3], u32)> {
    let rotation = glam::Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let point = |l: [usize; 3]| {
        let unit = Vec3::new(l[0] as f32, l[1] as f32, l[2] as f32) / n as f32 * 2.0 - Vec3::ONE;
        centre + rotation * (unit * half)
    };
    let mut tris = Vec::with_capacity(12 * n * n);
    for axis in 0..3 {
        for side in [0, n] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let lattice = |i: usize, j: usize| {
                let mut l = [0; 3];
                l[axis] = side;
                l[u] = i;
                l[v] = j;
                point(l)
            };
            for i in 0..n {
                for j in 0..n {
                    let (a, b, c, d) = (
                        lattice(i, j),
                        lattice(i + 1, j),
                        lattice(i + 1, j + 1),
                        lattice(i, j + 1),
                    );
                    // Inward: the winding flips with the side (normals are flipped to the
                    // camera anyway; this keeps the mesh consistently oriented).
                    if side == 0 {
                        tris.push(([a, b, c], 0));
                        tris.push(([a, c, d], 0));
                    } else {
                        tris.push(([a, c, b], 0));
                        tris.push(([a, d, c], 0));
                    }
                }
            }
        }
    }
    tris
}

/// `n` horizontal triangles stacked over y ∈ [1, 9] whose boxes all hold the vertical
/// line x = z = 0 while each one's long edge passes 0.036 beside it, and a square
/// blocker of half-size 0.05 at height `blocker_y`, over a ground square: shadow rays
/// from the ground near the origin to a small light straight above at y = 10 enter
/// every box of the stack, touch none of its triangles and are all blocked by the
/// blocker. A traversal that is ended early, before it reaches the blocker, leaves
/// them unblocked.
pub fn near_miss_column(n: usize, blocker_y: f32) -> Vec<([Vec3; 3], u32)> {
    let square = |y: f32, half: f32, material: u32| {
        let p = |x: f32, z: f32| Vec3::new(x, y, z);
        let (a, b, c, d) = (p(-half, -half), p(-half, half), p(half, half), p(half, -half));
        [([a, b, c], material), ([a, c, d], material)]
    };
    let mut tris: Vec<([Vec3; 3], u32)> = square(0.0, 2.0, 0).to_vec();
    tris.extend(square(blocker_y, 0.05, 1));
    tris.extend(near_miss_stack(n));
    tris
}

/// `n` horizontal triangles (material 1) stacked over y ∈ [1, 9] whose boxes all hold
/// the vertical line x = z = 0 while each one's long edge passes 0.036 beside it: a ray
/// near that line enters every box and touches no triangle.
pub fn near_miss_stack(n: usize) -> Vec<([Vec3; 3], u32)> {
    (0..n)
        .map(|i| {
            let y = 1.0 + 8.0 * (i as f32 + 0.5) / n as f32;
            (
                [
                    Vec3::new(-1.0, y, 1.0),
                    Vec3::new(1.0, y, 1.0),
                    Vec3::new(1.0, y, -0.9),
                ],
                1,
            )
        })
        .collect()
}

/// `scene` and `view` scaled by `scale` about the origin, then moved by `offset`
/// ([`Scene::translate`], [`penumbra::scene::view::View::translated`]).
pub fn scaled_and_moved(
    scene: &Scene,
    view: &penumbra::scene::view::View,
    scale: f32,
    offset: Vec3,
) -> (Scene, penumbra::scene::view::View) {
    let mut scene = scene.clone();
    for t in &mut scene.triangles {
        for p in &mut t.positions {
            *p *= scale;
        }
    }
    scene.translate(offset);
    let mut view = *view;
    view.camera.eye *= scale;
    view.camera.target *= scale;
    view.light.corner *= scale;
    view.light.edge_u *= scale;
    view.light.edge_v *= scale;
    view.ground_y = view.ground_y.map(|y| y * scale);
    (scene, view.translated(offset))
}

/// Two triangles sharing the edge a–b (stored a→b in one and b→a in the other, as a
/// consistently wound mesh has them), with corners whose differences f32 rounds (so
/// `a + (b − a) ≠ b`), and a 64×64 G-buffer whose pixel p sends its first shadow ray
/// through a point on that edge towards the light behind the pair. A watertight test
/// blocks every one of those rays; rebuilding a corner as `v0 + e1` moves the two
/// triangles' copies of the edge apart by an f32 step and lets some through.
pub fn rays_through_a_shared_edge() -> (
    Scene,
    penumbra::scene::view::View,
    Vec<penumbra::contract::layout::GBufferTexel>,
    u32,
    u32,
) {
    // Found by a search for f32 corners whose rebuilt copies (a + (b − a), b + (a − b))
    // leave the line a–b farthest: 3.4e-7 between them.
    let a = Vec3::new(1.219_627_1, 0.602_710_3, 1.809_138_7);
    let b = Vec3::new(-1.895_260_7, 0.686_024_4, -1.299_458_5);
    let m = (a + b) * 0.5;
    let c = m + Vec3::new(1.0, 0.05, -1.0);
    let d = m + Vec3::new(-1.0, 0.05, 1.0);
    assert!(
        a + (b - a) != b || b + (a - b) != a,
        "the corners must not survive v0 + (v1 - v0)"
    );
    let scene = scene_from_triangles(&[([a, b, c], 0), ([b, a, d], 0)], &[[0.8; 3]]);
    // Facing down (x × z = −y), towards the pair.
    let light = penumbra::scene::view::QuadLight::from_center(
        m + Vec3::new(0.0, 3.5, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
    );
    let view = penumbra::scene::view::View {
        camera: penumbra::scene::view::Camera {
            eye: m - Vec3::new(0.0, 3.0, 0.0),
            target: m,
            up: Vec3::Z,
            fov_y_degrees: 30.0,
        },
        light,
        ground_y: None,
    };
    let points = penumbra::sampling::light_points(&light);
    let (w, h) = (64u32, 64u32);
    let mut rng = Rng::new(7);
    let texels = (0..w * h)
        .map(|p| {
            let set = penumbra::sampling::pixel_set(p % w, p / w);
            let l = points[set * 16];
            let e = a + (b - a) * rng.range(0.02, 0.98);
            let origin = e - (l - e) * 0.4;
            penumbra::contract::layout::GBufferTexel {
                origin,
                depth: 1.0,
                normal: (l - origin).normalize(),
                triangle: u32::MAX - 1,
                geo_normal: (l - origin).normalize(),
                ..Default::default()
            }
        })
        .collect();
    (scene, view, texels, w, h)
}

/// Asserts that the image `sum` of two lights is `a + b`, the images of each alone, per
/// channel: `brdf·(e1 + e2)` against `brdf·e1 + brdf·e2` is three roundings to nearest
/// against three, each within 2^-24 of its result, so they differ by less than
/// 3 · 2^-24 · (|brdf·e1| + |brdf·e2|) < 2 ε (|a| + |b|). Returns how many pixels `b` lights.
pub fn assert_image_is_sum(sum: &[[f32; 3]], a: &[[f32; 3]], b: &[[f32; 3]], label: &str) -> usize {
    assert!(
        sum.len() == a.len() && a.len() == b.len(),
        "{label}: image sizes differ"
    );
    let mut lit_by_b = 0;
    for ((s, a), b) in sum.iter().zip(a).zip(b) {
        for c in 0..3 {
            let bound = 2.0 * f32::EPSILON * (a[c].abs() + b[c].abs());
            assert!(
                (s[c] - (a[c] + b[c])).abs() <= bound,
                "{label}: {} against {} + {}",
                s[c],
                a[c],
                b[c]
            );
        }
        lit_by_b += usize::from(b[0] > 0.0);
    }
    lit_by_b
}
