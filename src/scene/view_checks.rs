//! Views that are legal but probably not what was meant: the renderer draws
//! them (their result is defined), and the CLI prints a warning line for each.
//!
//! - [`ViewWarning::LightFacesAway`]: every scene vertex lies behind the
//!   one-sided light's plane, so every surface gets visibility 0 and the image
//!   is black. Checked exactly, over all triangle corners.
//! - [`ViewWarning::CameraInsideGeometry`]: every one of 26 rays from the eye
//!   (the axes, the face and the corner diagonals of a cube) hits the back of
//!   a triangle, the signature of an eye inside a closed mesh. A heuristic: an
//!   eye inside an open or double-sided object may pass unnoticed, and the
//!   rays only see geometry, not materials.

use glam::Vec3;

use crate::bvh::Bvh;
use crate::reference::closest_hit;
use crate::scene::Scene;
use crate::scene::view::View;

/// A legal but suspicious view; [`std::fmt::Display`] gives the warning line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewWarning {
    /// Every point of the scene is behind the light (or in its plane).
    LightFacesAway {
        /// The light's unit normal, the side it emits to.
        normal: Vec3,
    },
    /// The camera's eye appears to be inside closed geometry.
    CameraInsideGeometry {
        /// The eye.
        eye: Vec3,
    },
}

impl std::fmt::Display for ViewWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ViewWarning::LightFacesAway { normal } => write!(
                f,
                "the light faces away from the whole scene (every vertex is behind its plane; \
                 it emits toward [{}, {}, {}]): every surface is unlit",
                normal.x, normal.y, normal.z
            ),
            ViewWarning::CameraInsideGeometry { eye } => write!(
                f,
                "the camera eye [{}, {}, {}] seems to be inside closed geometry \
                 (all {} probe rays hit back faces): the image shows the inside of an object",
                eye.x,
                eye.y,
                eye.z,
                PROBE_DIRECTIONS.len()
            ),
        }
    }
}

/// The axes, face diagonals and corner diagonals of a cube: 6 + 12 + 8 directions.
const PROBE_DIRECTIONS: [[f32; 3]; 26] = [
    [1.0, 0.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -1.0],
    [1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, 1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, 1.0],
    [0.0, -1.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0],
    [1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, 1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [-1.0, -1.0, -1.0],
];

/// The warnings `view` deserves for `scene` and its BVH (built from the same
/// scene); empty for an ordinary view. Assumes the view passed [`View::validate`].
pub fn view_warnings(view: &View, scene: &Scene, bvh: &Bvh) -> Vec<ViewWarning> {
    let mut out = Vec::new();
    let normal = view.light.area_normal().normalize_or_zero();
    let in_front = |p: &Vec3| (*p - view.light.corner).dot(normal) > 0.0;
    if !scene.triangles.iter().any(|t| t.positions.iter().any(in_front)) {
        out.push(ViewWarning::LightFacesAway { normal });
    }
    if camera_inside(view.camera.eye, bvh) {
        out.push(ViewWarning::CameraInsideGeometry { eye: view.camera.eye });
    }
    out
}

/// Whether every probe ray from `eye` hits a triangle from behind.
fn camera_inside(eye: Vec3, bvh: &Bvh) -> bool {
    if bvh.triangles.is_empty() {
        return false;
    }
    PROBE_DIRECTIONS.iter().all(|&d| {
        let dir = Vec3::from(d);
        closest_hit(bvh, eye, dir, f32::INFINITY).is_some_and(|hit| {
            let t = &bvh.triangles[hit.triangle as usize];
            // Counter-clockwise corners face (v1 − v0) × (v2 − v0); a back face has it along the ray.
            (t.v1 - t.v0).cross(t.v2 - t.v0).dot(dir) > 0.0
        })
    })
}
