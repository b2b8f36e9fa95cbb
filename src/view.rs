//! Views: a pinhole camera and a quad area light, read from a small JSON file.
//!
//! ```json
//! {
//!   "camera": { "eye": [-13.5, 1.8, 0], "target": [0, 4, 0], "up": [0, 1, 0], "fov_y_degrees": 60 },
//!   "light": { "corner": [1.5, 40, -7.5], "edge_u": [5, 0, 0], "edge_v": [0, 0, 5],
//!              "color": [1, 1, 1], "intensity": 1 }
//! }
//! ```
//!
//! The light is the parallelogram `corner + s·edge_u + t·edge_v`, `s, t ∈ [0, 1]`.
//! It emits to the side `cross(edge_u, edge_v)` points to (one-sided), with
//! radiance `color × intensity`. `up` defaults to +y, `color` to white and
//! `intensity` to 1.

use std::path::Path;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// A pinhole camera looking from `eye` at `target`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Position of the eye, world space.
    pub eye: Vec3,
    /// A point the camera looks at (the image centre).
    pub target: Vec3,
    /// Up direction; only its component orthogonal to the view direction counts.
    #[serde(default = "default_up")]
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov_y_degrees: f32,
}

/// A one-sided parallelogram area light.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuadLight {
    /// One corner of the light, world space.
    pub corner: Vec3,
    /// First edge from `corner`.
    pub edge_u: Vec3,
    /// Second edge from `corner`; the light faces `cross(edge_u, edge_v)`.
    pub edge_v: Vec3,
    /// Linear RGB colour of the emitted radiance.
    #[serde(default = "default_color")]
    pub color: Vec3,
    /// Scale of the emitted radiance.
    #[serde(default = "default_intensity")]
    pub intensity: f32,
}

/// A camera and a light: everything besides the scene that a render needs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct View {
    /// Where the image is seen from.
    pub camera: Camera,
    /// The area light whose soft shadows are traced.
    pub light: QuadLight,
    /// Height of a ground plane to add under a scene that has none (scanned
    /// models): a square, facing +y, four times the scene's extent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_y: Option<f32>,
}

fn default_up() -> Vec3 {
    Vec3::Y
}
fn default_color() -> Vec3 {
    Vec3::ONE
}
fn default_intensity() -> f32 {
    1.0
}

impl QuadLight {
    /// A light from its centre and full edge vectors (the form `../shared/scenes/README.md` uses).
    pub fn from_center(center: Vec3, edge_u: Vec3, edge_v: Vec3) -> Self {
        QuadLight {
            corner: center - 0.5 * (edge_u + edge_v),
            edge_u,
            edge_v,
            color: Vec3::ONE,
            intensity: 1.0,
        }
    }

    /// Centre of the parallelogram.
    pub fn center(&self) -> Vec3 {
        self.corner + 0.5 * (self.edge_u + self.edge_v)
    }

    /// Unnormalised normal `cross(edge_u, edge_v)`; its length is the area.
    pub fn area_normal(&self) -> Vec3 {
        self.edge_u.cross(self.edge_v)
    }
}

impl View {
    /// A view for a scene that comes without one: the scene's own camera if
    /// it has one, else a camera looking at the bounds' centre from above one
    /// corner; and a square light a tenth of the diagonal wide, a quarter of
    /// the diagonal above the top of the bounds, bright enough that a surface
    /// facing it at the bounds' centre gets an irradiance of about 1.
    pub fn default_for(bounds: &crate::scene::Bounds, camera: Option<Camera>) -> View {
        let centre = (bounds.min + bounds.max) * 0.5;
        let diag = bounds.diagonal().max(1e-6);
        let camera = camera.unwrap_or(Camera {
            eye: centre + Vec3::new(0.8, 0.6, 0.9) * diag,
            target: centre,
            up: Vec3::Y,
            fov_y_degrees: 45.0,
        });
        let size = 0.1 * diag;
        let light_centre = Vec3::new(centre.x, bounds.max.y + 0.25 * diag, centre.z);
        let height = light_centre.y - centre.y;
        let mut light =
            QuadLight::from_center(light_centre, Vec3::new(size, 0.0, 0.0), Vec3::new(0.0, 0.0, size));
        // E ≈ L·A/h² for a small light straight above: L = h²/A gives E ≈ 1.
        light.intensity = height * height / (size * size);
        View {
            camera,
            light,
            ground_y: None,
        }
    }

    /// Parses a view from JSON text; `path` is only used in error messages.
    pub fn from_json(text: &str, path: &Path) -> Result<View> {
        let view: View = serde_json::from_str(text).map_err(|e| Error::view(path, e.to_string()))?;
        view.validate().map_err(|m| Error::view(path, m))?;
        Ok(view)
    }

    /// Reads and parses a view file.
    pub fn load(path: &Path) -> Result<View> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_owned(),
            source,
        })?;
        View::from_json(&text, path)
    }

    /// The view as pretty JSON, in the format [`View::from_json`] reads.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a View always serialises")
    }

    /// Checks that the view describes a usable camera and light.
    pub fn validate(&self) -> Result<(), String> {
        let c = &self.camera;
        let l = &self.light;
        let finite = [c.eye, c.target, c.up, l.corner, l.edge_u, l.edge_v, l.color]
            .iter()
            .all(|v| v.is_finite())
            && c.fov_y_degrees.is_finite()
            && l.intensity.is_finite()
            && self.ground_y.is_none_or(f32::is_finite);
        if !finite {
            return Err("view has a non-finite number (NaN or infinity)".into());
        }
        let dir = c.target - c.eye;
        if dir.length_squared() == 0.0 {
            return Err("camera eye and target are the same point".into());
        }
        if dir.cross(c.up).length_squared() <= 1e-12 * dir.length_squared() * c.up.length_squared() {
            return Err("camera up is zero or parallel to the view direction".into());
        }
        if !(c.fov_y_degrees > 0.0 && c.fov_y_degrees < 180.0) {
            return Err(format!(
                "camera fov_y_degrees is {}, must be in (0, 180)",
                c.fov_y_degrees
            ));
        }
        if l.area_normal().length_squared() == 0.0 {
            return Err("light has zero area (edge_u and edge_v are parallel or zero)".into());
        }
        if l.intensity < 0.0 || l.color.min_element() < 0.0 {
            return Err("light color and intensity must not be negative".into());
        }
        Ok(())
    }
}
