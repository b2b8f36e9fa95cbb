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

/// Whether a shadow ray from `origin` to `end` passes within `tol` of some
/// triangle edge, or has an endpoint within `tol` of some triangle: the only
/// places where two correct tracers may disagree because of rounding.
pub fn near_an_edge_or_endpoint(corners: &[[Vec3; 3]], origin: Vec3, end: Vec3, tol: f32) -> bool {
    corners.iter().any(|c| {
        (0..3).any(|e| segment_segment_distance(origin, end, c[e], c[(e + 1) % 3]) <= tol)
            || point_triangle_distance(origin, c[0], c[1], c[2]) <= tol
            || point_triangle_distance(end, c[0], c[1], c[2]) <= tol
    })
}

#[allow(clippy::too_many_arguments)]
/// Compares two sets of occlusion masks ray by ray: returns (differing
/// rays, total rays, differing rays NOT explained by an edge or endpoint).
pub fn compare_masks(
    a: &[u32],
    b: &[u32],
    gbuffer: &[penumbra::layout::GBufferTexel],
    width: u32,
    light_points: &[Vec3],
    params: &penumbra::layout::ShadowParams,
    corners: &[[Vec3; 3]],
    tol: f32,
) -> (usize, usize, Vec<String>) {
    let mut differing = 0;
    let mut total = 0;
    let mut unexplained = Vec::new();
    for (p, (&ma, &mb)) in a.iter().zip(b).enumerate() {
        if (ma | mb) & penumbra::reference::shadow::MASK_SKY != 0 {
            if ma != mb {
                unexplained.push(format!("pixel {p}: sky flag differs ({ma:#x} vs {mb:#x})"));
            }
            continue;
        }
        total += 16;
        let diff = (ma ^ mb) & 0xffff;
        differing += diff.count_ones() as usize;
        let (x, y) = (p as u32 % width, p as u32 / width);
        let set = penumbra::sampling::pixel_set(x, y);
        for j in 0..16 {
            if diff & (1 << j) != 0 {
                let o = gbuffer[p].origin;
                let end = o + (light_points[set * 16 + j] - o) * params.t_max;
                if !near_an_edge_or_endpoint(corners, o, end, tol) {
                    unexplained.push(format!(
                        "pixel ({x},{y}) ray {j}: {} vs {}",
                        ma >> j & 1,
                        mb >> j & 1
                    ));
                }
            }
        }
    }
    (differing, total, unexplained)
}

/// The shadow-mask acceptance check of the renderer issue: `masks` against the
/// per-ray oracle computed from the same `gbuffer`; at most 0.1 % of rays may
/// differ, each within 1e-4 of the scene's diagonal from a triangle edge or
/// from one of its endpoints. Returns (differing rays, rays, oracle masks).
#[allow(clippy::too_many_arguments)]
pub fn assert_masks_match_oracle(
    label: &str,
    scene: &Scene,
    bvh: &penumbra::bvh::Bvh,
    view: &penumbra::view::View,
    gbuffer: &[penumbra::layout::GBufferTexel],
    masks: &[u32],
    width: u32,
    height: u32,
) -> (usize, usize, Vec<u32>) {
    use penumbra::reference::shadow::{per_ray_masks, shadow_params};
    let params = shadow_params(&view.light, width, height);
    let points = penumbra::sampling::light_points(&view.light);
    let oracle = per_ray_masks(bvh, gbuffer, &points, &params);
    let corners: Vec<_> = scene.triangles.iter().map(|t| t.positions).collect();
    let tol = 1e-4 * scene.bounds().diagonal();
    let (differing, total, unexplained) =
        compare_masks(&oracle, masks, gbuffer, width, &points, &params, &corners, tol);
    assert!(
        unexplained.is_empty(),
        "{label}: {:?}",
        &unexplained[..unexplained.len().min(10)]
    );
    assert!(
        differing * 1000 <= total,
        "{label}: {differing} of {total} rays differ"
    );
    (differing, total, oracle)
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
