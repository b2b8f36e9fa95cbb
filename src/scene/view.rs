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
//!
//! A file may give several lights instead, as `"lights": [ {…}, {…} ]` (not both
//! `light` and `lights`): [`ViewFile`] reads either form, `penumbra render` traces each
//! light's shadows and sums their light; a [`View`] is the camera with one of them.

use std::path::Path;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// The narrowest vertical field of view a camera may have, in degrees.
///
/// Far below any real lens (a 1000 mm telephoto on full frame sees 1.4°), it
/// keeps the camera frame away from f32 underflow: the image plane's half
/// height is `tan(fov / 2)`, which for a field of view of 4e-44° (found by
/// fuzzing) is 0, collapsing every pixel's ray into one.
pub const MIN_FOV_Y_DEGREES: f32 = 1e-3;

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
    /// Vertical field of view in degrees, in [[`MIN_FOV_Y_DEGREES`], 180).
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

    /// The same light moved by `offset`.
    pub fn translated(&self, offset: Vec3) -> QuadLight {
        QuadLight {
            corner: self.corner + offset,
            ..*self
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

/// What a view file describes: a camera, one or more quad lights, and an optional ground
/// plane (see the module's documentation for the format).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewFile {
    /// Where the image is seen from.
    pub camera: Camera,
    /// The area lights, at least one.
    pub lights: Vec<QuadLight>,
    /// As [`View::ground_y`].
    pub ground_y: Option<f32>,
}

/// A view file as written: one `light` or a list of `lights`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ViewFileJson {
    camera: Camera,
    #[serde(default)]
    light: Option<QuadLight>,
    #[serde(default)]
    lights: Option<Vec<QuadLight>>,
    #[serde(default)]
    ground_y: Option<f32>,
}

impl ViewFile {
    /// Parses a view file with one light or several; `path` is only used in error messages.
    /// Errors name the file and the field at fault, e.g. `lights[1]: light has zero area …`.
    pub fn from_json(text: &str, path: &Path) -> Result<ViewFile> {
        let json: ViewFileJson = serde_json::from_str(text).map_err(|e| Error::view(path, e.to_string()))?;
        let lights = match (json.light, json.lights) {
            (Some(_), Some(_)) => {
                return Err(Error::view(
                    path,
                    "has both \"light\" and \"lights\"; give one light or a list of lights",
                ));
            }
            (None, None) => {
                return Err(Error::view(
                    path,
                    "has no light: give \"light\": {…} or \"lights\": [{…}, …]",
                ));
            }
            (None, Some(lights)) if lights.is_empty() => {
                return Err(Error::view(path, "\"lights\" is empty: give at least one light"));
            }
            (Some(light), None) => vec![light],
            (None, Some(lights)) => lights,
        };
        let file = ViewFile {
            camera: json.camera,
            lights,
            ground_y: json.ground_y,
        };
        for (i, view) in file.views().iter().enumerate() {
            view.validate().map_err(|m| match file.lights.len() {
                1 => Error::view(path, m),
                _ => Error::view(path, format!("lights[{i}]: {m}")),
            })?;
        }
        Ok(file)
    }

    /// Reads and parses a view file.
    pub fn load(path: &Path) -> Result<ViewFile> {
        ViewFile::from_json(&read_text(path)?, path)
    }

    /// The same camera and lights moved by `offset` (see [`View::translated`]).
    pub fn translated(&self, offset: Vec3) -> ViewFile {
        ViewFile {
            camera: self.camera.translated(offset),
            lights: self.lights.iter().map(|l| l.translated(offset)).collect(),
            ground_y: self.ground_y.map(|y| y + offset.y),
        }
    }

    /// The camera with each light in turn: one [`View`] per light, in the file's order.
    pub fn views(&self) -> Vec<View> {
        self.lights
            .iter()
            .map(|&light| View {
                camera: self.camera,
                light,
                ground_y: self.ground_y,
            })
            .collect()
    }
}

impl From<View> for ViewFile {
    /// A file with the view's one light.
    fn from(view: View) -> ViewFile {
        ViewFile {
            camera: view.camera,
            lights: vec![view.light],
            ground_y: view.ground_y,
        }
    }
}

impl View {
    /// The same camera and light moved by `offset` (see [`crate::scene::Scene::translate`]).
    pub fn translated(&self, offset: Vec3) -> View {
        View {
            camera: self.camera.translated(offset),
            light: self.light.translated(offset),
            ground_y: self.ground_y.map(|y| y + offset.y),
        }
    }

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

    /// Parses a view file with one light ([`ViewFile::from_json`]; a file with several is
    /// an error that says `penumbra render` takes them); `path` is only used in error messages.
    pub fn from_json(text: &str, path: &Path) -> Result<View> {
        let file = ViewFile::from_json(text, path)?;
        match file.views()[..] {
            [view] => Ok(view),
            ref views => Err(Error::view(
                path,
                format!(
                    "has {} lights; this traces one (penumbra render takes several)",
                    views.len()
                ),
            )),
        }
    }

    /// Reads and parses a view file with one light.
    pub fn load(path: &Path) -> Result<View> {
        View::from_json(&read_text(path)?, path)
    }

    /// The view as pretty JSON, in the format [`View::from_json`] reads.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a View always serialises")
    }

    /// Checks that the view describes a usable camera and light: every number
    /// finite, and everything the renderer derives from them (the camera's
    /// basis, the light's unit normal and area, its radiance) finite and
    /// non-degenerate. The message names the field at fault and its value.
    ///
    /// Legal but suspicious views (a light that faces away from the whole
    /// scene, a camera inside a closed object) pass; see
    /// [`crate::scene::view_checks`] for the warnings the CLI prints about them.
    pub fn validate(&self) -> Result<(), String> {
        self.camera.validate()?;
        self.light.validate()?;
        match self.ground_y {
            Some(y) if !y.is_finite() => Err(format!("ground_y {y} is not finite")),
            _ => Ok(()),
        }
    }
}

impl Camera {
    /// The same camera moved by `offset`.
    pub fn translated(&self, offset: Vec3) -> Camera {
        Camera {
            eye: self.eye + offset,
            target: self.target + offset,
            ..*self
        }
    }

    /// Checks that the camera gives a view: finite fields and a [`Camera::basis`].
    pub fn validate(&self) -> Result<(), String> {
        check_finite(&[
            ("camera.eye", self.eye),
            ("camera.target", self.target),
            ("camera.up", self.up),
        ])?;
        if !self.fov_y_degrees.is_finite() {
            return Err(format!(
                "camera.fov_y_degrees {} is not finite",
                self.fov_y_degrees
            ));
        }
        self.basis().map(|_| ())
    }

    /// The unit `(forward, right, up)` frame the renderer builds from the
    /// camera (see [`crate::pass_inputs::camera_params`]), or why there is none: eye
    /// and target at the same point, `up` zero or parallel to the view
    /// direction, or `fov_y_degrees` outside [[`MIN_FOV_Y_DEGREES`], 180). Assumes finite fields
    /// ([`Camera::validate`] checks them first).
    pub fn basis(&self) -> Result<(Vec3, Vec3, Vec3), String> {
        let to_target = self.target - self.eye;
        let forward = direction(to_target).ok_or_else(|| {
            if self.eye == self.target {
                format!(
                    "camera.eye and camera.target are the same point {}",
                    show_vec(self.eye)
                )
            } else {
                format!(
                    "camera.target - camera.eye = {} overflows f32",
                    show_vec(to_target)
                )
            }
        })?;
        // sin(angle) below 1e-6: the image's horizontal axis would be mostly rounding noise.
        let right = direction(self.up)
            .map(|up| forward.cross(up))
            .filter(|r| r.length_squared() > 1e-12)
            .ok_or_else(|| {
                format!(
                    "camera.up {} is zero or parallel to the view direction {}",
                    show_vec(self.up),
                    show_vec(forward)
                )
            })?
            .normalize();
        if !(self.fov_y_degrees >= MIN_FOV_Y_DEGREES && self.fov_y_degrees < 180.0) {
            return Err(format!(
                "camera.fov_y_degrees is {}, must be in [{MIN_FOV_Y_DEGREES}, 180)",
                self.fov_y_degrees
            ));
        }
        Ok((forward, right, right.cross(forward)))
    }
}

/// `v` scaled to unit length, or `None` when it is zero or not finite. Scaled
/// by its largest component first, so that tiny and huge vectors, whose
/// squared length under- or overflows f32, still have a direction.
fn direction(v: Vec3) -> Option<Vec3> {
    let largest = v.abs().max_element();
    if !largest.is_finite() || largest == 0.0 {
        return None;
    }
    (v / largest).try_normalize()
}

impl QuadLight {
    /// Checks what the shading needs: finite fields, a unit normal and a
    /// finite, non-zero area, finite corners, non-negative colour and
    /// intensity, and a finite radiance.
    pub fn validate(&self) -> Result<(), String> {
        check_finite(&[
            ("light.corner", self.corner),
            ("light.edge_u", self.edge_u),
            ("light.edge_v", self.edge_v),
            ("light.color", self.color),
        ])?;
        if !self.intensity.is_finite() {
            return Err(format!("light.intensity {} is not finite", self.intensity));
        }
        let n = self.area_normal();
        let area = n.length();
        if n.try_normalize().is_none() {
            return Err(if area.is_finite() {
                format!(
                    "light has zero area: |edge_u × edge_v| = {area} (edge_u {} and edge_v {} are zero, \
                     parallel or too short)",
                    show_vec(self.edge_u),
                    show_vec(self.edge_v)
                )
            } else {
                format!(
                    "light is too large: |edge_u × edge_v|² overflows f32 (edge_u {}, edge_v {})",
                    show_vec(self.edge_u),
                    show_vec(self.edge_v)
                )
            });
        }
        // Corners beyond f32 range would make light samples infinite.
        let corners = [
            self.corner + self.edge_u,
            self.corner + self.edge_v,
            self.corner + self.edge_u + self.edge_v,
            self.center(),
        ];
        if let Some(p) = corners.iter().find(|p| !p.is_finite()) {
            return Err(format!(
                "light reaches past the f32 range (a corner or its centre is {})",
                show_vec(*p)
            ));
        }
        if self.intensity < 0.0 {
            return Err(format!(
                "light.intensity is {}, must not be negative",
                self.intensity
            ));
        }
        if self.color.min_element() < 0.0 {
            return Err(format!(
                "light.color {} has a negative component",
                show_vec(self.color)
            ));
        }
        if !(self.color * self.intensity).is_finite() {
            return Err(format!(
                "light radiance color × intensity = {} × {} overflows f32",
                show_vec(self.color),
                self.intensity
            ));
        }
        Ok(())
    }
}

/// The text of the file at `path`, or an I/O error naming it.
fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_owned(),
        source,
    })
}

/// An error naming the first of `fields` that has a NaN or infinite component.
fn check_finite(fields: &[(&str, Vec3)]) -> Result<(), String> {
    match fields.iter().find(|(_, v)| !v.is_finite()) {
        Some((name, v)) => Err(format!("{name} {} is not finite", show_vec(*v))),
        None => Ok(()),
    }
}

/// `[x, y, z]` with each number as Rust prints an `f32` (`NaN`, `inf` included).
fn show_vec(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}
