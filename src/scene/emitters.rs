//! Lights from the file: emissive geometry that is a planar parallelogram (two triangles of
//! one node and material) becomes a quad light of that radiance, for a scene rendered
//! without a view file.

use glam::Vec3;

use super::Scene;
use super::view::QuadLight;

/// What [`find`] made of the file's emissive geometry.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Emitters {
    /// One quad light per emissive parallelogram, in the order of the file's triangles.
    pub lights: Vec<QuadLight>,
    /// Emissive groups (node, material) that are not one parallelogram, as
    /// "material NAME: N triangles, why": not used as lights.
    pub unusable: Vec<String>,
}

/// Relative tolerance (of the longest edge) for "planar" and "parallelogram": f32 vertices
/// written by exporters are accurate to a few ulps, far below this.
const SHAPE_TOLERANCE: f32 = 1e-4;

/// The quad lights of `scene`'s emissive geometry. Each light faces the side its
/// triangles' fronts (counter-clockwise) face, and lies `offset` in front of them, so that
/// shadow rays, which end at the light's points, never reach the emitter's own triangles.
pub fn find(scene: &Scene, offset: f32) -> Emitters {
    let mut groups: Vec<((u32, u32), Vec<usize>)> = Vec::new();
    for (i, t) in scene.triangles.iter().enumerate() {
        let e = scene.materials[t.material as usize].emissive;
        if e.iter().all(|&c| c <= 0.0) {
            continue;
        }
        let key = (t.instance, t.material);
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, list)) => list.push(i),
            None => groups.push((key, vec![i])),
        }
    }
    let mut found = Emitters::default();
    for ((_, material), list) in groups {
        let m = &scene.materials[material as usize];
        let name = m.name.as_deref().unwrap_or("(unnamed)");
        let corners = |i: usize| scene.triangles[i].positions;
        let quad = if list.len() == 2 {
            parallelogram(corners(list[0]), corners(list[1]))
        } else {
            Err(format!("{} triangles, not 2", list.len()))
        };
        match quad {
            Ok((corner, edge_u, edge_v)) => {
                let radiance = Vec3::from(m.emissive);
                let peak = radiance.max_element();
                let normal = edge_u.cross(edge_v).normalize();
                found.lights.push(QuadLight {
                    corner: corner + offset * normal,
                    edge_u,
                    edge_v,
                    color: radiance / peak,
                    intensity: peak,
                });
            }
            Err(why) => found
                .unusable
                .push(format!("material '{name}': {why}; not used as a light")),
        }
    }
    found
}

/// The parallelogram two triangles make, as (corner, edge_u, edge_v) with
/// `cross(edge_u, edge_v)` along the first triangle's front normal; or why not.
fn parallelogram(a: [Vec3; 3], b: [Vec3; 3]) -> Result<(Vec3, Vec3, Vec3), String> {
    let scale = a
        .iter()
        .chain(&b)
        .flat_map(|p| a.iter().chain(&b).map(move |q| (*p - *q).length()))
        .fold(0.0f32, f32::max);
    let tol = SHAPE_TOLERANCE * scale;
    let close = |p: Vec3, q: Vec3| (p - q).length() <= tol;
    // The two shared corners (the diagonal) and the one of each triangle that is not shared.
    let shared: Vec<Vec3> = a
        .iter()
        .copied()
        .filter(|&p| b.iter().any(|&q| close(p, q)))
        .collect();
    if shared.len() != 2 {
        return Err("two triangles that do not share one edge".into());
    }
    let (Some(&pa), Some(&pb)) = (
        a.iter().find(|&&p| !shared.iter().any(|&s| close(p, s))),
        b.iter().find(|&&p| !shared.iter().any(|&s| close(p, s))),
    ) else {
        return Err("degenerate triangles".into());
    };
    let (s0, s1) = (shared[0], shared[1]);
    // A parallelogram: the diagonals bisect each other, and pb is pa mirrored through the centre.
    if !close(pa + pb, s0 + s1) {
        return Err("not a parallelogram (or not planar)".into());
    }
    let normal = (a[1] - a[0]).cross(a[2] - a[0]);
    if normal.length() <= tol * tol {
        return Err("degenerate triangles".into());
    }
    let (edge_u, edge_v) = (s0 - pa, s1 - pa);
    Ok(if edge_u.cross(edge_v).dot(normal) > 0.0 {
        (pa, edge_u, edge_v)
    } else {
        (pa, edge_v, edge_u)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const Q: [Vec3; 4] = [
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(2.0, 1.0, 0.0),
        Vec3::new(2.0, 1.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
    ];

    #[test]
    fn two_triangles_of_a_rectangle_make_it_facing_their_fronts() {
        // Counter-clockwise seen from below (-y): the fronts face down.
        let (c, u, v) = parallelogram([Q[0], Q[1], Q[2]], [Q[0], Q[2], Q[3]]).unwrap();
        let n = u.cross(v);
        assert!(n.normalize().abs_diff_eq(Vec3::NEG_Y, 1e-6), "{n}");
        assert!((n.length() - 2.0).abs() < 1e-6, "area 2, got {}", n.length());
        assert!([Q[1], Q[3]].contains(&c) || [Q[0], Q[2]].contains(&c));
        let (_, u2, v2) = parallelogram([Q[0], Q[2], Q[1]], [Q[0], Q[3], Q[2]]).unwrap();
        assert!(u2.cross(v2).normalize().abs_diff_eq(Vec3::Y, 1e-6));
    }

    #[test]
    fn other_shapes_are_refused() {
        let kite = [Q[0], Q[1], Q[2]];
        let bent = [Q[0], Q[2], Q[3] + Vec3::new(0.0, 0.3, 0.0)];
        assert!(parallelogram(kite, bent).is_err());
        let apart = [Q[0] + Vec3::X * 5.0, Q[2] + Vec3::X * 5.0, Q[3] + Vec3::X * 5.0];
        assert!(parallelogram(kite, apart).is_err());
    }
}
