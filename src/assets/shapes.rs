//! Triangle-mesh builders for the generated scenes: boxes, spheres, cylinders
//! and a subdivided ground plane.
//!
//! Every builder returns outward normals and counter-clockwise winding seen
//! from outside. Angles go through [`sin_cos`], which uses only correctly
//! rounded IEEE arithmetic, so the generated files are byte-identical on every
//! platform (the platform's `sin`/`cos` may differ in the last bit).

use glam::Vec3;

/// An indexed triangle mesh in the layout glTF stores: one normal per
/// position, three indices per triangle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions, object space.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<[f32; 3]>,
    /// Triangle list: every three indices make one triangle.
    pub indices: Vec<u32>,
}

impl TriangleMesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Appends `other`, moved by `offset`, to this mesh; used to bake many
    /// bars into one mesh so a lattice is one node, not hundreds.
    pub fn append(&mut self, other: &TriangleMesh, offset: Vec3) {
        let base = self.vertex_count_u32();
        self.positions.extend(
            other
                .positions
                .iter()
                .map(|&p| (Vec3::from(p) + offset).to_array()),
        );
        self.normals.extend_from_slice(&other.normals);
        self.indices.extend(other.indices.iter().map(|&i| base + i));
    }

    /// Object-space bounding box `(min, max)`; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut points = self.positions.iter().map(|&p| Vec3::from(p));
        let first = points.next()?;
        Some(points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }

    fn vertex_count_u32(&self) -> u32 {
        u32::try_from(self.positions.len()).expect("generated meshes stay far below 2^32 vertices")
    }

    fn push_vertex(&mut self, position: Vec3, normal: Vec3) -> u32 {
        let index = self.vertex_count_u32();
        self.positions.push(position.to_array());
        self.normals.push(normal.to_array());
        index
    }

    /// A quad `a b c d`, counter-clockwise seen from the side `normal` points to.
    fn push_quad(&mut self, corners: [Vec3; 4], normal: Vec3) {
        let [a, b, c, d] = corners.map(|p| self.push_vertex(p, normal));
        self.indices.extend_from_slice(&[a, b, c, a, c, d]);
    }
}

/// Sine and cosine of `angle` (radians) from a Taylor series in `f64`.
///
/// Deterministic on every platform: only `+`, `-`, `*`, `/` and a rounding,
/// unlike `f64::sin`, which calls the platform's math library.
pub fn sin_cos(angle: f64) -> (f64, f64) {
    use std::f64::consts::PI;
    // Reduce to [-π, π], where 30 terms are far below f64 precision.
    let x = angle - (angle / (2.0 * PI)).round() * (2.0 * PI);
    let (mut sin, mut cos) = (0.0, 0.0);
    let (mut sin_term, mut cos_term) = (x, 1.0);
    for i in 0..30 {
        sin += sin_term;
        cos += cos_term;
        let n = f64::from(2 * i + 1);
        sin_term *= -x * x / ((n + 1.0) * (n + 2.0));
        cos_term *= -x * x / (n * (n + 1.0));
    }
    (sin, cos)
}

/// Sine and cosine of `k/n` of a full turn, rounded to `f32`.
fn turn_sin_cos(k: u32, n: u32) -> (f32, f32) {
    let (s, c) = sin_cos(2.0 * std::f64::consts::PI * f64::from(k) / f64::from(n));
    (s as f32, c as f32)
}

/// An axis-aligned box between `min` and `max`, flat-shaded (24 vertices,
/// 12 triangles).
pub fn box_min_max(min: Vec3, max: Vec3) -> TriangleMesh {
    let center = 0.5 * (min + max);
    let half = 0.5 * (max - min);
    let mut mesh = TriangleMesh::default();
    // For each face: its normal n and in-plane axes u, v with u × v = n, so
    // that (-u-v, u-v, u+v, -u+v) is counter-clockwise seen from outside.
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ];
    for (n, u, v) in faces {
        let face_center = center + n * half;
        let (u, v) = (u * half, v * half);
        mesh.push_quad(
            [
                face_center - u - v,
                face_center + u - v,
                face_center + u + v,
                face_center - u + v,
            ],
            n,
        );
    }
    mesh
}

/// An axis-aligned box of `size` centred on the origin.
pub fn box_centered(size: Vec3) -> TriangleMesh {
    box_min_max(-0.5 * size, 0.5 * size)
}

/// A box of `size` whose bottom face is centred on the origin, so it rests on
/// the plane y = 0 wherever it is translated to on that plane.
pub fn box_on_ground(size: Vec3) -> TriangleMesh {
    box_min_max(
        Vec3::new(-0.5 * size.x, 0.0, -0.5 * size.z),
        Vec3::new(0.5 * size.x, size.y, 0.5 * size.z),
    )
}

/// A UV sphere of `radius` centred on the origin, smooth-shaded, with
/// `rings` latitude bands (≥ 2) and `segments` longitude slices (≥ 3):
/// `2 · segments · (rings − 1)` triangles. Its poles are vertices, so a sphere
/// translated up by `radius` touches y = 0 in exactly one point.
pub fn uv_sphere(radius: f32, rings: u32, segments: u32) -> TriangleMesh {
    assert!(
        rings >= 2 && segments >= 3,
        "a UV sphere needs at least 2 rings and 3 segments"
    );
    let mut mesh = TriangleMesh::default();
    let top = mesh.push_vertex(Vec3::Y * radius, Vec3::Y);
    // Ring r (1..rings) sits at polar angle r/rings of half a turn.
    for ring in 1..rings {
        let (sin_polar, cos_polar) = turn_sin_cos(ring, 2 * rings);
        for segment in 0..segments {
            let (sin_az, cos_az) = turn_sin_cos(segment, segments);
            let normal = Vec3::new(sin_polar * cos_az, cos_polar, -sin_polar * sin_az);
            mesh.push_vertex(normal * radius, normal);
        }
    }
    let bottom = mesh.push_vertex(Vec3::NEG_Y * radius, Vec3::NEG_Y);
    let ring_vertex = |ring: u32, segment: u32| 1 + (ring - 1) * segments + segment % segments;
    // Azimuth grows counter-clockwise seen from +y, so these windings face out.
    for s in 0..segments {
        mesh.indices
            .extend_from_slice(&[top, ring_vertex(1, s), ring_vertex(1, s + 1)]);
    }
    for ring in 1..rings - 1 {
        for s in 0..segments {
            let (a, b) = (ring_vertex(ring, s), ring_vertex(ring, s + 1));
            let (c, d) = (ring_vertex(ring + 1, s), ring_vertex(ring + 1, s + 1));
            mesh.indices.extend_from_slice(&[a, c, d, a, d, b]);
        }
    }
    for s in 0..segments {
        let last = rings - 1;
        mesh.indices
            .extend_from_slice(&[bottom, ring_vertex(last, s + 1), ring_vertex(last, s)]);
    }
    mesh
}

/// A closed cylinder along +y from y = 0 to `height`, with smooth sides and
/// flat caps: `4 · segments` triangles.
pub fn cylinder(radius: f32, height: f32, segments: u32) -> TriangleMesh {
    assert!(segments >= 3, "a cylinder needs at least 3 segments");
    let mut mesh = TriangleMesh::default();
    let directions: Vec<Vec3> = (0..segments)
        .map(|s| {
            let (sin, cos) = turn_sin_cos(s, segments);
            Vec3::new(cos, 0.0, -sin)
        })
        .collect();
    let up = Vec3::Y * height;
    let side_base = mesh.vertex_count_u32();
    for &d in &directions {
        mesh.push_vertex(d * radius, d);
        mesh.push_vertex(d * radius + up, d);
    }
    for s in 0..segments {
        let (b0, t0) = (side_base + 2 * s, side_base + 2 * s + 1);
        let next = (s + 1) % segments;
        let (b1, t1) = (side_base + 2 * next, side_base + 2 * next + 1);
        mesh.indices.extend_from_slice(&[b0, b1, t1, b0, t1, t0]);
    }
    for (y, normal) in [(0.0, Vec3::NEG_Y), (height, Vec3::Y)] {
        let center = mesh.push_vertex(Vec3::new(0.0, y, 0.0), normal);
        let rim = mesh.vertex_count_u32();
        for &d in &directions {
            mesh.push_vertex(d * radius + Vec3::Y * y, normal);
        }
        for s in 0..segments {
            let (a, b) = (rim + s, rim + (s + 1) % segments);
            let triangle = if normal.y > 0.0 {
                [center, a, b]
            } else {
                [center, b, a]
            };
            mesh.indices.extend_from_slice(&triangle);
        }
    }
    mesh
}

/// A horizontal plane at y = 0, `size_x` by `size_z`, centred on the origin
/// and facing +y, split into `cells_x` × `cells_z` quads (two triangles each)
/// so that no triangle spans the whole scene.
pub fn ground_plane(size_x: f32, size_z: f32, cells_x: u32, cells_z: u32) -> TriangleMesh {
    assert!(cells_x >= 1 && cells_z >= 1, "a plane needs at least one cell");
    let mut mesh = TriangleMesh::default();
    for iz in 0..=cells_z {
        for ix in 0..=cells_x {
            let x = size_x * (ix as f32 / cells_x as f32 - 0.5);
            let z = size_z * (iz as f32 / cells_z as f32 - 0.5);
            mesh.push_vertex(Vec3::new(x, 0.0, z), Vec3::Y);
        }
    }
    let vertex = |ix: u32, iz: u32| iz * (cells_x + 1) + ix;
    for iz in 0..cells_z {
        for ix in 0..cells_x {
            // Going +z then +x is counter-clockwise seen from +y.
            let (a, b) = (vertex(ix, iz), vertex(ix, iz + 1));
            let (c, d) = (vertex(ix + 1, iz + 1), vertex(ix + 1, iz));
            mesh.indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangles(mesh: &TriangleMesh) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        mesh.indices
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| Vec3::from(mesh.positions[t[k] as usize])))
    }

    /// Every triangle of a convex mesh must face away from `inside` and agree
    /// with its vertex normals.
    fn assert_outward(mesh: &TriangleMesh, inside: Vec3) {
        assert_eq!(mesh.positions.len(), mesh.normals.len());
        assert!(mesh.indices.iter().all(|&i| (i as usize) < mesh.positions.len()));
        for (t, [a, b, c]) in triangles(mesh).enumerate() {
            let n = (b - a).cross(c - a);
            assert!(n.length() > 0.0, "triangle {t} is degenerate");
            let centroid = (a + b + c) / 3.0;
            assert!(n.dot(centroid - inside) > 0.0, "triangle {t} faces inward");
            for k in 0..3 {
                let vertex_normal = Vec3::from(mesh.normals[mesh.indices[3 * t + k] as usize]);
                assert!((vertex_normal.length() - 1.0).abs() < 1e-5);
                assert!(
                    vertex_normal.dot(n) > 0.0,
                    "triangle {t} disagrees with its normals"
                );
            }
        }
    }

    #[test]
    fn sin_cos_matches_std() {
        for k in -20..=20 {
            let angle = f64::from(k) * 0.37;
            let (s, c) = sin_cos(angle);
            assert!((s - angle.sin()).abs() < 1e-14, "sin({angle})");
            assert!((c - angle.cos()).abs() < 1e-14, "cos({angle})");
        }
    }

    #[test]
    fn box_faces_outward() {
        let mesh = box_min_max(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(0.5, 3.0, 2.1));
        assert_eq!(mesh.triangle_count(), 12);
        assert_outward(&mesh, Vec3::new(-0.25, 1.5, 2.05));
        let (lo, hi) = box_on_ground(Vec3::new(1.0, 2.0, 3.0)).bounds().unwrap();
        assert_eq!((lo, hi), (Vec3::new(-0.5, 0.0, -1.5), Vec3::new(0.5, 2.0, 1.5)));
    }

    #[test]
    fn sphere_faces_outward_and_touches_its_bounds() {
        let mesh = uv_sphere(0.5, 8, 12);
        assert_eq!(mesh.triangle_count(), 2 * 12 * 7);
        assert_outward(&mesh, Vec3::ZERO);
        let (lo, hi) = mesh.bounds().unwrap();
        assert_eq!(lo.y, -0.5);
        assert_eq!(hi.y, 0.5);
    }

    #[test]
    fn cylinder_faces_outward() {
        let mesh = cylinder(0.1, 2.0, 16);
        assert_eq!(mesh.triangle_count(), 4 * 16);
        assert_outward(&mesh, Vec3::new(0.0, 1.0, 0.0));
    }

    #[test]
    fn ground_plane_faces_up() {
        let mesh = ground_plane(4.0, 6.0, 8, 3);
        assert_eq!(mesh.triangle_count(), 2 * 8 * 3);
        assert_outward(&mesh, Vec3::new(0.0, -1.0, 0.0));
        let (lo, hi) = mesh.bounds().unwrap();
        assert_eq!((lo, hi), (Vec3::new(-2.0, 0.0, -3.0), Vec3::new(2.0, 0.0, 3.0)));
    }

    #[test]
    fn append_offsets_positions_and_indices() {
        let mut mesh = box_centered(Vec3::ONE);
        mesh.append(&box_centered(Vec3::ONE), Vec3::X * 3.0);
        assert_eq!(mesh.triangle_count(), 24);
        assert_eq!(mesh.indices[36], 24);
        let (lo, hi) = mesh.bounds().unwrap();
        assert_eq!((lo.x, hi.x), (-0.5, 3.5));
    }
}
