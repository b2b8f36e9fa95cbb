//! Exact visibility of a quad light from a shade point, by beam splitting as
//! the soft-shadow beam tracer of Overbeck, Ramamoorthi & Mark (2007) does:
//! the ground truth that sampled shadows are measured against.
//!
//! # Semantics
//!
//! The same as the ray-traced masks of [`super::shadow_per_ray`], with infinitely
//! many rays: light point `p(s, t) = corner + s·edge_u + t·edge_v`,
//! `(s, t) ∈ [0, 1]²`, is visible from `origin` unless
//! - `dot(geo_normal, p − origin) ≤ 0` (below the surface's horizon), or
//! - a triangle meets the segment `origin + τ·(p − origin)`, `0 < τ < SHADOW_T_MAX`;
//!
//! and nothing is visible from behind the light. The result is the visible
//! area of the `(s, t)` square, which is the visible fraction of the light's
//! area: exactly what the 16-ray masks estimate.
//!
//! # Method
//!
//! Work in the light's `(s, t)` plane. Start from the unit square cut by the
//! horizon line. For every triangle in the shadow frustum (found through the
//! BVH with a conservative plane-versus-box test), cut off the part at
//! `τ ≥ SHADOW_T_MAX`, where `τ(x)` is the ray parameter at which a ray to the
//! light reaches `x` (affine in `x`), and take the cone from `origin` over
//! the rest: the positive combinations of its corners' directions, which are
//! exactly the directions of rays that meet it at `t > 0`. Its trace on the
//! light plane is convex: the intersection of one half-plane per polygon
//! edge, each the trace of the plane through `origin` and that edge, computed
//! from cross products. Nothing is projected (no division by `τ`), so a
//! triangle crossing the plane through the origin parallel to the light
//! needs no clipping there and no special case. Every visible convex polygon
//! is then split by the occluder's lines; the parts outside are kept, the
//! part inside dropped (Overbeck's beam–triangle split, in `polygon.rs`).
//! The shadows are gathered first and subtracted largest first.
//!
//! # Cost
//!
//! Proportional to the triangles in the pixel's shadow frustum and to how
//! finely they cut the light. Measured at 64×64 on a busy 2-core machine
//! (both cores): about 0.005 ms per pixel on the playground scene and
//! 0.07–0.09 ms per pixel on Sponza's atrium view, so 512×512 of Sponza takes
//! about 20 s. [`exact_visibility_image_with`] takes a time budget and reports
//! progress per row for callers that must bound it.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use glam::{DVec2, DVec3, Vec3};

use super::parallel::per_pixel;
use super::polygon::{Bounds, Fuzz, Line, Polygon, Split, area, intersect_convex, split, subtract_convex};
use super::shadow_per_ray::SHADOW_T_MAX;
use crate::bvh::Bvh;
use crate::contract::layout::{BvhNode, BvhTriangle, GBufferTexel};
use crate::scene::view::QuadLight;
use crate::{Error, Result};

/// Tolerances in `(s, t)` units (the light is the unit square). A vertex
/// within 1e-9 of a line is on it; pieces thinner than 1e-7 are dropped:
/// they come from the f32 rounding of shared vertices (`v0 + e1` is not
/// exactly the neighbour's corner), which leaves hair-thin gaps between
/// neighbouring triangles; each costs at most its area (≪ 1e-6).
const FUZZ: Fuzz = Fuzz {
    on_line: 1e-9,
    min_width: 1e-7,
};

/// The half-space `n·x + d ≥ 0`.
#[derive(Clone, Copy, Debug)]
struct Plane {
    n: DVec3,
    d: f64,
}

impl Plane {
    fn eval(&self, x: DVec3) -> f64 {
        self.n.dot(x) + self.d
    }

    /// The box lies wholly on the negative side (p-vertex test).
    fn excludes_box(&self, node: &BvhNode) -> bool {
        let (lo, hi) = (node.bmin.as_dvec3(), node.bmax.as_dvec3());
        let p = DVec3::select(self.n.cmpgt(DVec3::ZERO), hi, lo);
        self.eval(p) < 0.0
    }
}

/// One shade point's view of the light.
struct Beam {
    origin: DVec3,
    /// `corner − origin`.
    to_corner: DVec3,
    edge_u: DVec3,
    edge_v: DVec3,
    /// `τ(x) = k·(x − origin)`: the ray parameter at which rays to the light
    /// cross the plane through `x` parallel to the light (0 at the origin, 1 at the light).
    k: DVec3,
    /// The frustum: four sides through the origin and the light's edges, the
    /// horizon, `τ > 0` and `τ < SHADOW_T_MAX`.
    planes: [Plane; 7],
}

impl Beam {
    fn new(texel: &GBufferTexel, light: &QuadLight) -> Beam {
        let o = texel.origin.as_dvec3();
        let c = light.corner.as_dvec3();
        let (u, v) = (light.edge_u.as_dvec3(), light.edge_v.as_dvec3());
        let corners = [c, c + u, c + u + v, c + v];
        let centre = c + 0.5 * (u + v);
        let through_origin = |n: DVec3| Plane { n, d: -n.dot(o) };
        let side = |i: usize| {
            let n = (corners[i] - o).cross(corners[(i + 1) % 4] - o);
            through_origin(if n.dot(centre - o) < 0.0 { -n } else { n })
        };
        let normal = u.cross(v);
        // Negative: the caller has checked that the origin faces the light.
        let k = normal / normal.dot(c - o);
        Beam {
            origin: o,
            to_corner: c - o,
            edge_u: u,
            edge_v: v,
            k,
            planes: [
                side(0),
                side(1),
                side(2),
                side(3),
                through_origin(texel.geo_normal.as_dvec3()),
                through_origin(k),
                Plane {
                    n: -k,
                    d: SHADOW_T_MAX as f64 + k.dot(o),
                },
            ],
        }
    }

    /// The trace on the light's `(s, t)` plane of the plane through the origin
    /// with normal `m`: `m·(p(s, t) − origin)` as `a + b·s + c·t`.
    fn trace(&self, m: DVec3) -> (f64, f64, f64) {
        (m.dot(self.to_corner), m.dot(self.edge_u), m.dot(self.edge_v))
    }

    fn tau(&self, x: DVec3) -> f64 {
        self.k.dot(x - self.origin)
    }

    /// The light's `(s, t)` square above the horizon, or `None` when none of it is.
    fn lit_square(&self, geo_normal: Vec3) -> Option<Polygon> {
        let square = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        let (a, b, c) = self.trace(geo_normal.as_dvec3());
        let Some(horizon) = Line::from_coefficients(a, b, c) else {
            // The tangent plane is parallel to the light: all above or all below.
            return (a > 0.0).then_some(square);
        };
        match split(&square, &horizon, &FUZZ) {
            Split::Positive => Some(square),
            Split::Negative => None,
            Split::Both { positive, .. } => Some(positive),
        }
    }

    /// The convex region of `(s, t)` that the triangle hides, as half-planes
    /// (positive inside); `None` when it hides nothing (outside the frustum,
    /// outside the slab, or seen edge-on).
    fn shadow_of(&self, tri: &BvhTriangle) -> Option<Vec<Line>> {
        // The stored corners, exactly.
        let verts = [tri.v0.as_dvec3(), tri.v1.as_dvec3(), tri.v2.as_dvec3()];
        if self.planes.iter().any(|p| verts.iter().all(|&x| p.eval(x) < 0.0)) {
            return None;
        }
        // Only hits before τ = T count: cut the triangle there.
        let poly = clip_far(&verts, |x| SHADOW_T_MAX as f64 - self.tau(x));
        if poly.len() < 3 {
            return None;
        }
        // A positive combination of the corners: inside every edge's half-space.
        let inside = poly.iter().sum::<DVec3>() / poly.len() as f64 - self.origin;
        let mut lines = Vec::with_capacity(poly.len());
        for i in 0..poly.len() {
            let m = (poly[i] - self.origin).cross(poly[(i + 1) % poly.len()] - self.origin);
            let side = m.dot(inside);
            if side.abs() <= 1e-12 * m.length() * inside.length() {
                // The polygon is seen edge-on (or the edge has zero length): it hides no area.
                return None;
            }
            let m = if side < 0.0 { -m } else { m };
            let (a, b, c) = self.trace(m);
            match Line::from_coefficients(a, b, c) {
                Some(line) => lines.push(line),
                // Parallel to the light: all inside (no constraint) or all outside.
                None if a > 0.0 => {}
                None => return None,
            }
        }
        Some(lines)
    }
}

/// The part of the triangle where `g ≥ 0` (`g` affine), Sutherland–Hodgman.
fn clip_far(verts: &[DVec3; 3], g: impl Fn(DVec3) -> f64) -> Vec<DVec3> {
    let vals = verts.map(&g);
    if vals.iter().all(|&v| v > 0.0) {
        return verts.to_vec();
    }
    let mut out = Vec::with_capacity(4);
    for i in 0..3 {
        let j = (i + 1) % 3;
        let (gi, gj) = (vals[i], vals[j]);
        if gi > 0.0 {
            out.push(verts[i]);
        }
        if (gi > 0.0) != (gj > 0.0) {
            out.push(verts[i] + (verts[j] - verts[i]) * (gi / (gi - gj)));
        }
    }
    out
}

/// Visible fraction (0..=1) of `light` from the texel's shadow-ray origin,
/// exactly (see the [module docs](self)); `None` for a sky pixel. Every triangle is a
/// whole polygon here: alpha masks are not applied (the image functions refuse a BVH
/// that has alpha-tested triangles).
pub fn exact_visibility(bvh: &Bvh, texel: &GBufferTexel, light: &QuadLight) -> Option<f32> {
    if !texel.is_hit() {
        return None;
    }
    // The same f32 test as `shadow::faces_light`, so the two agree on the boundary.
    if light.area_normal().dot(texel.origin - light.corner) <= 0.0 {
        return Some(0.0);
    }
    let beam = Beam::new(texel, light);
    let Some(square) = beam.lit_square(texel.geo_normal) else {
        return Some(0.0);
    };
    // Gather every triangle's shadow on the lit part first, so the largest
    // can be subtracted first: an umbra point is then done after one, and
    // small occluders do not cut the light into pieces that a large one
    // would have removed whole.
    let lit_area = area(&square);
    let mut occluders = Vec::new();
    let mut stack = Vec::with_capacity(64);
    if !beam.planes.iter().any(|p| p.excludes_box(&bvh.nodes[0])) {
        stack.push(0u32);
    }
    while let Some(i) = stack.pop() {
        let node = &bvh.nodes[i as usize];
        if node.is_leaf() {
            for tri in &bvh.triangles[node.first as usize..(node.first + node.count) as usize] {
                let Some(lines) = beam.shadow_of(tri) else {
                    continue;
                };
                let Some(piece) = intersect_convex(&square, &lines, &FUZZ) else {
                    continue;
                };
                let a = area(&piece);
                if a >= lit_area * (1.0 - 1e-12) {
                    return Some(0.0);
                }
                occluders.push(Occluder {
                    lines,
                    bounds: Bounds::of(&piece),
                    area: a,
                });
            }
            continue;
        }
        for c in [node.first, node.first + 1] {
            if !beam.planes.iter().any(|p| p.excludes_box(&bvh.nodes[c as usize])) {
                stack.push(c);
            }
        }
    }
    occluders.sort_by(|a, b| b.area.total_cmp(&a.area));
    let mut visible = vec![(Bounds::of(&square), square)];
    let mut next = Vec::new();
    let mut pieces = Vec::new();
    for occ in &occluders {
        next.clear();
        for (bounds, poly) in visible.drain(..) {
            if !bounds.overlaps(&occ.bounds) {
                next.push((bounds, poly));
                continue;
            }
            pieces.clear();
            subtract_convex(poly, &occ.lines, &FUZZ, &mut pieces);
            next.extend(pieces.drain(..).map(|p| (Bounds::of(&p), p)));
        }
        std::mem::swap(&mut visible, &mut next);
        if visible.is_empty() {
            return Some(0.0);
        }
    }
    let total: f64 = visible.iter().map(|(_, p)| area(p)).sum();
    Some(total.clamp(0.0, 1.0) as f32)
}

/// One triangle's shadow on the light.
struct Occluder {
    /// The region it hides (positive sides).
    lines: Vec<Line>,
    /// Bounds of the part of the lit square it hides.
    bounds: Bounds,
    /// Area of that part.
    area: f64,
}

/// Limits and progress reporting for [`exact_visibility_image_with`].
#[derive(Clone, Copy, Default)]
pub struct ExactImageOptions<'a> {
    /// Give up when this much time has passed (checked before every pixel):
    /// the result is then [`Error::TimeBudget`]. `None`: no limit.
    pub budget: Option<Duration>,
    /// Called after each finished row with the number of rows finished so
    /// far (from the worker threads, so rows finish out of order).
    pub on_row: Option<&'a (dyn Fn(usize) + Sync)>,
}

/// Exact visibility of every pixel of a row-major G-buffer, rows spread over
/// all cores; sky pixels get 1 (as [`super::visibility::visibility`] gives them).
///
/// # Panics
///
/// When the BVH has alpha-tested triangles ([`exact_visibility_image_with`] returns
/// that as an error).
pub fn exact_visibility_image(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    width: u32,
    height: u32,
    light: &QuadLight,
) -> Vec<f32> {
    exact_visibility_image_with(bvh, gbuffer, width, height, light, &ExactImageOptions::default())
        .expect("no budget, so no time-out (and a BVH with alpha-tested triangles is a caller's bug)")
}

/// [`exact_visibility_image`] with a time budget and a progress callback.
///
/// # Errors
///
/// [`Error::TimeBudget`] when `options.budget` runs out first; [`Error::InvalidInput`]
/// when the BVH has alpha-tested triangles, whose holes polygons do not describe.
///
/// # Panics
///
/// When `gbuffer` does not hold `width · height` texels.
pub fn exact_visibility_image_with(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    width: u32,
    height: u32,
    light: &QuadLight,
    options: &ExactImageOptions,
) -> Result<Vec<f32>> {
    let (width, height) = (width as usize, height as usize);
    assert_eq!(
        gbuffer.len(),
        width * height,
        "G-buffer size does not match the image size"
    );
    if bvh.alpha.triangles > 0 {
        return Err(Error::invalid(
            "exact visibility",
            format!(
                "the scene has {} alpha-tested triangles, whose masks it cannot clip; \
                 use the 256-ray reference tracer",
                bvh.alpha.triangles
            ),
        ));
    }
    let start = Instant::now();
    let deadline = options.budget.map(|b| start + b);
    let out_of_time = AtomicBool::new(false);
    let done = AtomicUsize::new(0);
    let rows_done = AtomicUsize::new(0);
    let image = per_pixel(width, height, |p| {
        if out_of_time.load(Ordering::Relaxed) || deadline.is_some_and(|d| Instant::now() >= d) {
            out_of_time.store(true, Ordering::Relaxed);
            return f32::NAN;
        }
        let v = exact_visibility(bvh, &gbuffer[p], light).unwrap_or(1.0);
        done.fetch_add(1, Ordering::Relaxed);
        if p % width == width - 1 {
            let rows = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
            if let Some(f) = options.on_row {
                f(rows);
            }
        }
        v
    });
    if out_of_time.into_inner() {
        return Err(Error::TimeBudget {
            what: "exact visibility".into(),
            budget_s: options.budget.unwrap_or_default().as_secs_f64(),
            done: done.into_inner(),
            total: width * height,
        });
    }
    Ok(image)
}
