//! Exact visibility by beam splitting against closed forms (a square occluder
//! parallel to a square light, a wall crossing the point's plane, the
//! horizon) and against a 16,384-sample Monte Carlo estimate at 1,000 points
//! of the default scene, traced with the per-ray oracle's rules.

use crate::support;

use std::path::Path;

use glam::Vec3;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::layout::GBufferTexel;
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::any_hit;
use penumbra::reference::exact::{ExactImageOptions, exact_visibility, exact_visibility_image_with};
use penumbra::reference::primary::primary_gbuffer;
use penumbra::reference::shadow_per_ray::{SHADOW_T_MAX, per_ray_mask, shadow_params};
use penumbra::scene::view::QuadLight;
use penumbra::{Error, assets, sampling, scene::Scene};
use support::Rng;

/// Light side, height of the light plane.
const L: f32 = 2.0;
const H: f32 = 4.0;

/// A `L`×`L` light centred over the origin at height `H`, facing down.
fn light() -> QuadLight {
    QuadLight::from_center(
        Vec3::new(0.0, H, 0.0),
        Vec3::new(L, 0.0, 0.0),
        Vec3::new(0.0, 0.0, L),
    )
}

/// A shade point on the ground (normal +y).
fn texel(origin: Vec3, geo_normal: Vec3) -> GBufferTexel {
    GBufferTexel {
        origin,
        depth: 1.0,
        geo_normal,
        normal: geo_normal,
        ..Default::default()
    }
}

/// The axis-aligned rectangle `[x0, x1] × [z0, z1]` at height `y` as two triangles.
fn rect(x0: f32, x1: f32, z0: f32, z1: f32, y: f32) -> [[Vec3; 3]; 2] {
    let p = |x, z| Vec3::new(x, y, z);
    [
        [p(x0, z0), p(x1, z0), p(x1, z1)],
        [p(x0, z0), p(x1, z1), p(x0, z1)],
    ]
}

fn bvh(corners: &[[Vec3; 3]]) -> Bvh {
    Bvh::build_from_corners(corners, &BvhSettings::default()).unwrap()
}

/// Length of the overlap of `[a0, a1]` and `[b0, b1]`.
fn overlap(a0: f32, a1: f32, b0: f32, b1: f32) -> f32 {
    (a1.min(b1) - a0.max(b0)).max(0.0)
}

#[test]
fn square_occluder_parallel_to_square_light() {
    // A 1×0.8 occluder at height h; seen from o = (px, 0, pz) it hides the
    // rectangle scaled by H/h about o on the light plane.
    let (x0, x1, z0, z1, h) = (-0.5, 0.5, -0.3, 0.5, 1.5);
    let mut corners = rect(x0, x1, z0, z1, h).to_vec();
    // The ground the points lie on: below every shade point, so never in a frustum.
    corners.extend(rect(-20.0, 20.0, -20.0, 20.0, -1e-3));
    let bvh = bvh(&corners);
    let k = H / h;
    let mut partial = 0;
    for (px, pz) in [
        (0.0, 0.0),
        (0.3, 0.1),
        (0.55, -0.2),
        (0.9, 0.4),
        (-1.1, 0.7),
        (1.3, -1.0),
        (2.5, 0.0),
        (0.0, 3.0),
    ] {
        let project = |a: f32, p: f32| p + (a - p) * k;
        let hidden = overlap(project(x0, px), project(x1, px), -L / 2.0, L / 2.0)
            * overlap(project(z0, pz), project(z1, pz), -L / 2.0, L / 2.0);
        let expected = 1.0 - hidden / (L * L);
        let got = exact_visibility(&bvh, &texel(Vec3::new(px, 0.0, pz), Vec3::Y), &light()).unwrap();
        assert!(
            (got - expected).abs() < 1e-5,
            "point ({px}, {pz}): exact {got}, closed form {expected}"
        );
        if expected > 0.01 && expected < 0.99 {
            partial += 1;
        }
    }
    assert!(partial >= 4, "the offsets must include partial overlaps");
}

#[test]
fn fully_lit_and_umbra_points() {
    let mut corners = rect(-1.0, 1.0, -1.0, 1.0, 3.0).to_vec();
    corners.extend(rect(-20.0, 20.0, -20.0, 20.0, -1e-3));
    let bvh = bvh(&corners);
    // Far to the side: the occluder hides x ∈ [−4, −4/3] of the light plane, beside the light.
    let lit = exact_visibility(&bvh, &texel(Vec3::new(8.0, 0.0, 0.0), Vec3::Y), &light()).unwrap();
    assert_eq!(lit, 1.0);
    // The light's own quad (a luminaire's mesh) and a triangle above the light do not block.
    let mut with_luminaire = corners.clone();
    with_luminaire.extend(rect(-1.0, 1.0, -1.0, 1.0, H));
    with_luminaire.push([
        Vec3::new(-9.0, H + 1.0, -9.0),
        Vec3::new(9.0, H + 1.0, 0.0),
        Vec3::new(0.0, H + 1.0, 9.0),
    ]);
    let lit = exact_visibility(
        &self::bvh(&with_luminaire),
        &texel(Vec3::new(8.0, 0.0, 0.0), Vec3::Y),
        &light(),
    );
    assert_eq!(lit, Some(1.0));
    // Under the centre: the 2×2 occluder at 3/4 of the way hides an 8/3 × 8/3 square, more than the light.
    let umbra = exact_visibility(&bvh, &texel(Vec3::ZERO, Vec3::Y), &light()).unwrap();
    assert_eq!(umbra, 0.0);
}

#[test]
fn wall_crossing_the_points_plane() {
    // A wall x = 0.5 from far below the ground (y = −30) up to y = 10, seen from the origin:
    // the ray to p crosses it at τ = 0.5 / p.x, so p is hidden where
    // p.x > 0.5 / T. The wall's triangles cross the plane through the point
    // parallel to the light, and their centroids lie behind it.
    let xw = 0.5;
    let wall = |z0: f32, z1: f32| {
        let p = |y, z| Vec3::new(xw, y, z);
        [
            [p(-30.0, z0), p(10.0, z0), p(10.0, z1)],
            [p(-30.0, z0), p(10.0, z1), p(-30.0, z1)],
        ]
    };
    let mut corners = wall(-20.0, 20.0).to_vec();
    corners.extend(rect(-20.0, 20.0, -20.0, 20.0, -1e-3));
    let bvh = bvh(&corners);
    let got = exact_visibility(&bvh, &texel(Vec3::ZERO, Vec3::Y), &light()).unwrap();
    let edge = xw / SHADOW_T_MAX;
    let expected = (edge + L / 2.0) / L;
    assert!(
        (got - expected).abs() < 1e-6,
        "exact {got}, closed form {expected}"
    );
    // Split into many strips sharing edges: the same answer (no cracks).
    let mut strips: Vec<[Vec3; 3]> = (0..40)
        .flat_map(|i| wall(-2.0 + 0.1 * i as f32, -1.9 + 0.1 * i as f32))
        .collect();
    strips.extend(rect(-20.0, 20.0, -20.0, 20.0, -1e-3));
    let got_strips = exact_visibility(&self::bvh(&strips), &texel(Vec3::ZERO, Vec3::Y), &light()).unwrap();
    assert!(
        (got_strips - expected).abs() < 1e-5,
        "strips: exact {got_strips}, closed form {expected}"
    );
}

#[test]
fn horizon_back_of_light_and_sky() {
    let corners = rect(-20.0, 20.0, -20.0, 20.0, -1e-3);
    let bvh = bvh(&corners);
    // A surface facing +x under the light's centre sees the half with x > 0.
    let half = exact_visibility(&bvh, &texel(Vec3::ZERO, Vec3::X), &light()).unwrap();
    assert!((half - 0.5).abs() < 1e-6, "{half}");
    // Tilted 45° toward +x: the horizon y = −x meets the light plane at x = −H, outside the light.
    let tilted = exact_visibility(
        &bvh,
        &texel(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0).normalize()),
        &light(),
    );
    assert_eq!(tilted, Some(1.0));
    // Above the light: its back.
    let back = exact_visibility(&bvh, &texel(Vec3::new(0.0, H + 1.0, 0.0), Vec3::Y), &light());
    assert_eq!(back, Some(0.0));
    let sky = GBufferTexel::default();
    assert_eq!(exact_visibility(&bvh, &sky, &light()), None);
}

#[test]
fn property_in_unit_range_and_one_without_occluders() {
    let mut rng = Rng::new(6);
    for case in 0..200 {
        let soup = support::random_soup(&mut rng, 60, 0.4);
        let bvh = bvh(&soup);
        let centre = rng.in_box(Vec3::splat(-0.5), Vec3::splat(1.5));
        let light = QuadLight::from_center(
            centre,
            rng.direction() * rng.range(0.05, 1.0),
            rng.direction() * rng.range(0.05, 1.0),
        );
        let origin = rng.in_box(Vec3::ZERO, Vec3::ONE);
        let t = texel(origin, rng.direction());
        if let Some(v) = exact_visibility(&bvh, &t, &light) {
            assert!((0.0..=1.0).contains(&v), "case {case}: {v}");
        }
        // Nothing between: the only triangle is behind the point, and the
        // surface faces the light's plane, so the whole light is visible.
        let n = light.area_normal().normalize();
        let p = if n.dot(origin - light.corner) > 0.0 {
            origin
        } else {
            2.0 * light.corner - origin
        };
        let behind = p + n * 0.5;
        let lone = self::bvh(&[[behind, behind + light.edge_u, behind + light.edge_v]]);
        let v = exact_visibility(&lone, &texel(p, -n), &light).unwrap();
        assert!((v - 1.0).abs() < 1e-9, "case {case}: {v}");
    }
}

/// `n`×`n` stratified Monte Carlo estimate with the per-ray oracle's rules.
fn monte_carlo(bvh: &Bvh, t: &GBufferTexel, light: &QuadLight, n: usize, rng: &mut Rng) -> f32 {
    if light.area_normal().dot(t.origin - light.corner) <= 0.0 {
        return 0.0;
    }
    let mut visible = 0usize;
    for i in 0..n {
        for j in 0..n {
            let s = (i as f32 + rng.f32()) / n as f32;
            let u = (j as f32 + rng.f32()) / n as f32;
            let d = light.corner + s * light.edge_u + u * light.edge_v - t.origin;
            if t.geo_normal.dot(d) > 0.0 && !any_hit(bvh, t.origin, d, SHADOW_T_MAX) {
                visible += 1;
            }
        }
    }
    visible as f32 / (n * n) as f32
}

/// |exact − MC| bound for an `n`×`n` estimate: 4σ + 1e-3 with σ = sqrt(v(1 − v)/n²),
/// the standard deviation of n² independent uniform samples at the exact v.
/// Stratified jittered sampling has no larger variance, so 4σ fails by chance
/// with probability below 1e-4 per point; 1e-3 absorbs rays whose f32 hit
/// test rounds differently at an edge.
fn mc_bound(exact: f32, n: usize) -> f32 {
    4.0 * (exact * (1.0 - exact) / (n * n) as f32).sqrt() + 1e-3
}

#[test]
fn matches_monte_carlo_in_random_soups_around_the_point() {
    // Points inside the soup: many triangles cross the plane through the
    // point parallel to the light, or reach past the light.
    let mut rng = Rng::new(2009);
    const N: usize = 64;
    let mut penumbra = 0;
    for case in 0..150 {
        let soup = support::random_soup(&mut rng, 30, 0.5);
        let bvh = bvh(&soup);
        let light = QuadLight::from_center(
            Vec3::new(rng.range(0.2, 0.8), rng.range(0.9, 1.3), rng.range(0.2, 0.8)),
            Vec3::new(rng.range(0.1, 0.6), 0.0, rng.range(-0.1, 0.1)),
            Vec3::new(rng.range(-0.1, 0.1), 0.0, rng.range(0.1, 0.6)),
        );
        let light = if light.area_normal().y > 0.0 {
            QuadLight {
                corner: light.corner + light.edge_u,
                edge_u: -light.edge_u,
                ..light
            }
        } else {
            light
        };
        let t = texel(rng.in_box(Vec3::splat(0.2), Vec3::splat(0.8)), rng.direction());
        let exact = exact_visibility(&bvh, &t, &light).unwrap();
        let mc = monte_carlo(&bvh, &t, &light, N, &mut rng);
        assert!(
            (exact - mc).abs() <= mc_bound(exact, N),
            "case {case}: exact {exact}, Monte Carlo {mc}"
        );
        if exact > 0.0 && exact < 1.0 {
            penumbra += 1;
        }
    }
    assert!(penumbra >= 50, "only {penumbra} cases in penumbra");
}

#[test]
fn matches_monte_carlo_at_1000_points_of_the_default_scene() {
    let s = assets::default_scene();
    let scene = Scene::from_bytes(s.glb, Path::new(s.file_name)).unwrap();
    let view = s.view();
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let (w, h) = (160u32, 120u32);
    let cam = camera_params(
        &view.camera,
        w,
        h,
        scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
    );
    let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(&scene, &bvh).unwrap(), &cam);
    // Half the points anywhere on the geometry, half where the 16-ray mask is
    // mixed (the penumbrae, where an exact tracer can be wrong).
    let params = shadow_params(&view.light, w, h);
    let points = sampling::light_points(&view.light);
    let hits: Vec<usize> = (0..gbuffer.len()).filter(|&p| gbuffer[p].is_hit()).collect();
    let mixed: Vec<usize> = hits
        .iter()
        .copied()
        .filter(|&p| {
            let set = sampling::pixel_set(p as u32 % w, p as u32 / w);
            let m = per_ray_mask(&bvh, &gbuffer[p], set, &points, &params) & 0xffff;
            m != 0 && m != 0xffff
        })
        .collect();
    let mut rng = Rng::new(2007);
    let chosen: Vec<usize> = (0..1000)
        .map(|i| {
            let from = if i % 2 == 0 { &hits } else { &mixed };
            from[rng.next_u32() as usize % from.len()]
        })
        .collect();
    // 128² = 16,384 samples per point, points spread over two threads.
    const N: usize = 128;
    let results: Vec<(usize, f32, f32)> = std::thread::scope(|sc| {
        let handles: Vec<_> = chosen
            .chunks(chosen.len().div_ceil(2))
            .enumerate()
            .map(|(k, chunk)| {
                let (bvh, gbuffer, light) = (&bvh, &gbuffer, &view.light);
                sc.spawn(move || {
                    let mut rng = Rng::new(k as u64 + 1);
                    chunk
                        .iter()
                        .map(|&p| {
                            let t = &gbuffer[p];
                            let exact = exact_visibility(bvh, t, light).unwrap();
                            (p, exact, monte_carlo(bvh, t, light, N, &mut rng))
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    // Bound: see `mc_bound` (4σ + 1e-3).
    let mut worst = 0.0f32;
    let mut penumbra = 0;
    for &(p, exact, mc) in &results {
        let (diff, bound) = ((exact - mc).abs(), mc_bound(exact, N));
        assert!(
            diff <= bound,
            "pixel ({}, {}): exact {exact}, Monte Carlo {mc}, |diff| {diff} > 4σ + 1e-3 = {bound}",
            p as u32 % w,
            p as u32 / w,
        );
        worst = worst.max(diff / bound);
        if exact > 0.0 && exact < 1.0 {
            penumbra += 1;
        }
    }
    println!(
        "{penumbra} of {} points in penumbra; worst |diff| / bound = {worst:.3}",
        results.len()
    );
    assert!(penumbra >= 400, "only {penumbra} points in penumbra");
}

#[test]
fn image_budget_and_progress() {
    let s = assets::default_scene();
    let scene = Scene::from_bytes(s.glb, Path::new(s.file_name)).unwrap();
    let view = s.view();
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let (w, h) = (24u32, 16u32);
    let cam = camera_params(
        &view.camera,
        w,
        h,
        scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
    );
    let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(&scene, &bvh).unwrap(), &cam);
    let rows = std::sync::Mutex::new(Vec::new());
    let on_row = |n: usize| rows.lock().unwrap().push(n);
    let options = ExactImageOptions {
        budget: None,
        on_row: Some(&on_row),
    };
    let image = exact_visibility_image_with(&bvh, &gbuffer, w, h, &view.light, &options).unwrap();
    let mut rows = rows.into_inner().unwrap();
    rows.sort();
    assert_eq!(rows, (1..=h as usize).collect::<Vec<_>>());
    for (p, v) in image.iter().enumerate() {
        let expected = exact_visibility(&bvh, &gbuffer[p], &view.light).unwrap_or(1.0);
        assert_eq!(*v, expected, "pixel {p}");
    }
    let none = ExactImageOptions {
        budget: Some(std::time::Duration::ZERO),
        on_row: None,
    };
    let err = exact_visibility_image_with(&bvh, &gbuffer, w, h, &view.light, &none).unwrap_err();
    assert!(matches!(err, Error::TimeBudget { done: 0, .. }), "{err}");
    assert!(err.to_string().contains("time budget"), "{err}");
}
