//! Scenes: world-space triangles with shading data, materials and an optional camera,
//! loaded from glTF 2.0 (`.gltf` with external or data-URI buffers, or `.glb`).

mod accessor;
mod buffers;
pub mod emitters;
mod glb;
mod gltf_import;
pub mod view;
pub mod view_checks;

use std::path::{Path, PathBuf};

pub(crate) use buffers::read_file_prefix;

use glam::{Vec2, Vec3};

use crate::{Error, Result};

/// One triangle in world space, with what shading needs at its corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneTriangle {
    /// Corner positions, counter-clockwise seen from the front.
    pub positions: [Vec3; 3],
    /// Unit shading normals at the corners (the face normal when the file has none).
    pub normals: [Vec3; 3],
    /// TEXCOORD_0 at the corners (zero when the file has none).
    pub uvs: [Vec2; 3],
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// Index into [`Scene::instances`]: the node this triangle came from.
    pub instance: u32,
}

/// How a material's alpha is used (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    Opaque,
    /// Alpha below the cutoff makes the surface absent, for camera and shadow rays alike.
    Mask,
    /// Alpha blends. Rays treat it as [`AlphaMode::Mask`] at
    /// [`crate::contract::alpha::BLEND_ALPHA_CUTOFF`] (0.05), the cutoff Bevy's shadow and
    /// depth passes discard blended surfaces at: nearly clear texels let light through,
    /// the rest block it (a ray is blocked or not; there is no partial transmission).
    Blend,
}

/// The part of a glTF material penumbra uses: diffuse base colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// The material's name, if the file gives one.
    pub name: Option<String>,
    /// Linear RGBA base colour factor.
    pub base_color_factor: [f32; 4],
    /// Index into [`Scene::images`] of the base colour texture, if any.
    pub base_color_texture: Option<u32>,
    /// Alpha mode.
    pub alpha_mode: AlphaMode,
    /// Alpha cutoff for [`AlphaMode::Mask`]: a finite number ≥ 0 (the loader refuses others).
    pub alpha_cutoff: f32,
    /// Whether back faces are shaded as front faces.
    pub double_sided: bool,
    /// Emitted linear RGB radiance: `emissiveFactor` × `KHR_materials_emissive_strength`
    /// (no emissive texture). Where it is not zero the geometry may become a light
    /// ([`crate::scene::emitters`]).
    pub emissive: [f32; 3],
}

impl Default for Material {
    /// The glTF default material: white, opaque, single-sided.
    fn default() -> Self {
        Material {
            name: None,
            base_color_factor: [1.0; 4],
            base_color_texture: None,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            double_sided: false,
            emissive: [0.0; 3],
        }
    }
}

/// Where an image's encoded bytes are (decoded only when a renderer needs them).
#[derive(Clone, Debug, PartialEq)]
pub enum ImageSource {
    /// A file next to the scene.
    File(PathBuf),
    /// Bytes inside the scene (a buffer view or a data URI), with their MIME type if given.
    Embedded {
        /// The encoded image (PNG or JPEG).
        bytes: Vec<u8>,
        /// MIME type from the file, if any.
        mime_type: Option<String>,
    },
}

/// A node of the glTF scene that carries a mesh, placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// Index of the glTF node.
    pub node: u32,
    /// The node's name, if the file gives one.
    pub name: Option<String>,
    /// Object-to-world matrix (the product of the node path's transforms).
    pub world_from_object: glam::Mat4,
}

/// Things skipped while loading that did not make the file unusable.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadWarnings {
    /// Primitives that are points or lines (not triangles), skipped.
    pub skipped_non_triangle_primitives: usize,
    /// Triangles with zero area (repeated or collinear corners), dropped: no ray can hit them.
    pub degenerate_triangles: usize,
    /// Triangles with a NaN or infinite corner (in the file or after the node
    /// transforms), or whose area overflows f32, dropped: they cannot be traced.
    pub non_finite_triangles: usize,
    /// Cameras in the file that describe no usable view (for example a
    /// non-finite node transform, or up parallel to the view direction), ignored.
    pub unusable_cameras: usize,
    /// Triangle strips or fans converted to triangle lists.
    pub converted_strips_and_fans: usize,
}

impl LoadWarnings {
    /// One line per kind of warning that occurred.
    pub fn messages(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.skipped_non_triangle_primitives > 0 {
            out.push(format!(
                "skipped {} point/line primitive(s)",
                self.skipped_non_triangle_primitives
            ));
        }
        if self.degenerate_triangles > 0 {
            out.push(format!(
                "dropped {} zero-area triangle(s)",
                self.degenerate_triangles
            ));
        }
        if self.non_finite_triangles > 0 {
            out.push(format!(
                "dropped {} triangle(s) with non-finite (NaN or infinite) positions",
                self.non_finite_triangles
            ));
        }
        if self.unusable_cameras > 0 {
            out.push(format!("ignored {} unusable camera(s)", self.unusable_cameras));
        }
        if self.converted_strips_and_fans > 0 {
            out.push(format!(
                "converted {} triangle strip/fan primitive(s) to lists",
                self.converted_strips_and_fans
            ));
        }
        out
    }
}

/// A loaded scene: everything in world space, ready for the BVH builder.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The file it came from (for embedded scenes, a name).
    pub source: PathBuf,
    /// All triangles of the glTF scene, node transforms applied.
    pub triangles: Vec<SceneTriangle>,
    /// Materials; index 0.. as in the file, plus a default one at the end when a primitive has none.
    pub materials: Vec<Material>,
    /// Images referenced by materials, in file order.
    pub images: Vec<ImageSource>,
    /// The nodes that contributed triangles.
    pub instances: Vec<Instance>,
    /// The first perspective camera (node cameras first, then `asset.extras.camera`), aspect ratio left to the renderer.
    pub camera: Option<crate::scene::view::Camera>,
    /// What was skipped or converted.
    pub warnings: LoadWarnings,
}

/// Axis-aligned bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Bounds {
    /// The empty box (min = +inf, max = -inf), neutral for [`Bounds::grow`].
    pub const EMPTY: Bounds = Bounds {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// Grows the box to contain `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The centre of bounds that lie farther from the origin than their own diagonal
    /// (rounded to f32), else zero: the offset [`Scene::recentre`] and
    /// [`crate::gpu::GpuScene`] subtract so that f32 keeps its precision.
    pub fn far_centre(&self) -> Vec3 {
        let centre = (self.min + self.max) * 0.5;
        if !centre.is_finite() || centre.length() <= self.diagonal() {
            Vec3::ZERO
        } else {
            centre
        }
    }

    /// Length of the diagonal; the scene's size for relative tolerances.
    pub fn diagonal(&self) -> f32 {
        (self.max - self.min).length()
    }
}

impl Scene {
    /// Loads a `.gltf` or `.glb` file.
    pub fn load(path: &Path) -> Result<Scene> {
        let bytes = std::fs::read(path).map_err(|source| Error::Io {
            path: path.to_owned(),
            source,
        })?;
        Scene::from_bytes(&bytes, path)
    }

    /// Loads a scene from the bytes of a `.gltf` or `.glb` file; `path` names it in
    /// errors, and its directory is where external buffers and images are looked for.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Scene> {
        gltf_import::import(bytes, path).map_err(|message| Error::scene(path, message))
    }

    /// Adds a ground plane at height `y`: a square facing +y, centred under the
    /// scene and four times its larger horizontal extent, with a default material.
    pub fn add_ground_plane(&mut self, y: f32) {
        let b = self.bounds();
        let centre = (b.min + b.max) * 0.5;
        let half = 2.0 * (b.max.x - b.min.x).max(b.max.z - b.min.z).max(1e-3);
        let p = |dx: f32, dz: f32| Vec3::new(centre.x + dx * half, y, centre.z + dz * half);
        let material = self.materials.len() as u32;
        self.materials.push(Material {
            name: Some("ground".into()),
            base_color_factor: [0.8, 0.8, 0.8, 1.0],
            ..Material::default()
        });
        let instance = self.instances.len() as u32;
        self.instances.push(Instance {
            node: u32::MAX,
            name: Some("ground".into()),
            world_from_object: glam::Mat4::IDENTITY,
        });
        for positions in [
            [p(-1.0, -1.0), p(-1.0, 1.0), p(1.0, 1.0)],
            [p(-1.0, -1.0), p(1.0, 1.0), p(1.0, -1.0)],
        ] {
            self.triangles.push(SceneTriangle {
                positions,
                normals: [Vec3::Y; 3],
                uvs: [Vec2::ZERO; 3],
                material,
                instance,
            });
        }
    }

    /// Moves the whole scene by `offset`: every triangle corner (in f32, as a file that
    /// stored the scene there would hold it), every instance's transform and the camera.
    /// For georeferenced data and for checking precision far from the origin.
    pub fn translate(&mut self, offset: Vec3) {
        for t in &mut self.triangles {
            for p in &mut t.positions {
                *p += offset;
            }
        }
        for i in &mut self.instances {
            i.world_from_object = glam::Mat4::from_translation(offset) * i.world_from_object;
        }
        if let Some(c) = &mut self.camera {
            *c = c.translated(offset);
        }
    }

    /// Moves a scene that lies farther from the origin than its own diagonal to it: there
    /// f32 steps are as fine as the scene needs, while far out (a georeferenced site at
    /// 1e6 m has steps of 6 cm) hit points, ray origins and triangle tests all round that
    /// coarsely. Returns the offset subtracted (the bounds' centre, as f32), or zero for a
    /// scene near enough, which is left as it was, bit for bit. Move the view alike:
    /// `view.translated(-offset)`. The CLI does this for every scene it loads.
    pub fn recentre(&mut self) -> Vec3 {
        let centre = self.bounds().far_centre();
        if centre != Vec3::ZERO {
            self.translate(-centre);
        }
        centre
    }

    /// Bounds of all triangles.
    pub fn bounds(&self) -> Bounds {
        let mut b = Bounds::EMPTY;
        for t in &self.triangles {
            t.positions.iter().for_each(|&p| b.grow(p));
        }
        b
    }
}
