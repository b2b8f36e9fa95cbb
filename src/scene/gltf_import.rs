//! glTF document → [`Scene`]: walks the chosen scene's node tree, applies
//! transforms and turns every triangle primitive into world-space triangles.

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};
use gltf::mesh::{Mode, Semantic};

use super::accessor::{read_indices, read_texcoords, read_vec3};
use super::buffers::{load_buffers, load_uri, resolve_uri_path};
use super::{AlphaMode, ImageSource, Instance, LoadWarnings, Material, Scene, SceneTriangle, glb};
use crate::scene::view::Camera;

/// Extensions that may be *required* without changing what penumbra computes:
/// they only affect appearance terms penumbra does not use.
const HARMLESS_REQUIRED_EXTENSIONS: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_lights_punctual",
    "KHR_texture_transform",
];

/// Parses and imports a scene; errors are messages, the caller adds the path.
pub(super) fn import(bytes: &[u8], path: &Path) -> Result<Scene, String> {
    let (json_bytes, bin) = if glb::is_glb(bytes) {
        let chunks = glb::split(bytes)?;
        (chunks.json, chunks.bin)
    } else {
        (bytes, None)
    };
    let root = gltf::json::Root::from_slice(json_bytes).map_err(|e| format!("invalid glTF JSON: {e}"))?;
    if let Some(ext) = root
        .extensions_required
        .iter()
        .find(|e| !HARMLESS_REQUIRED_EXTENSIONS.contains(&e.as_str()))
    {
        return Err(format!(
            "requires glTF extension {ext}, which penumbra does not support{}",
            if ext.contains("draco") || ext.contains("meshopt") {
                " (decompress the file first, e.g. with gltf-transform)"
            } else {
                ""
            }
        ));
    }
    check_what_gltf_assumes(&root)?;
    // gltf-json's validator indexes arrays before checking some indices; a
    // panic there is a malformed file, so it becomes an error like the rest.
    let doc = std::panic::catch_unwind(|| gltf::Document::from_json(root))
        .map_err(|_| "invalid glTF (the glTF validator failed on it)".to_owned())?
        .map_err(|e| format!("invalid glTF: {e}"))?;
    let base_dir = path.parent();
    let buffers = load_buffers(&doc, bin, base_dir)?;

    let gltf_scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or("the file defines no scene")?;

    let mut builder = Builder {
        materials: doc.materials().map(|m| material(&m)).collect::<Result<_, _>>()?,
        default_material: None,
        triangles: Vec::new(),
        instances: Vec::new(),
        camera: None,
        warnings: LoadWarnings::default(),
        buffers: &buffers,
    };

    // Iterative walk with a visited set: glTF node graphs must be disjoint trees,
    // so a node reached twice means a cycle or a shared child; both are errors.
    let mut visited = vec![false; doc.nodes().count()];
    let mut stack: Vec<(gltf::Node, Mat4)> = gltf_scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(format!(
                "node {} is reached twice in scene {} (a cycle or a shared child)",
                node.index(),
                gltf_scene.index()
            ));
        }
        // A non-finite transform is not an error: the triangles it makes
        // non-finite are dropped and counted like any other such triangle.
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            builder.add_mesh(&node, &mesh, world)?;
        }
        if builder.camera.is_none()
            && let Some(cam) = node.camera()
            && let gltf::camera::Projection::Perspective(p) = cam.projection()
        {
            let camera = node_camera(world, p.yfov());
            match camera.validate() {
                Ok(()) => builder.camera = Some(camera),
                Err(_) => builder.warnings.unusable_cameras += 1,
            }
        }
        let mut children: Vec<_> = node.children().map(|c| (c, world)).collect();
        children.reverse();
        stack.extend(children);
    }

    if builder.triangles.is_empty() {
        let w = &builder.warnings;
        return Err(format!(
            "scene {} has no triangles ({} point/line primitives, {} zero-area and {} non-finite \
             triangles skipped)",
            gltf_scene.index(),
            w.skipped_non_triangle_primitives,
            w.degenerate_triangles,
            w.non_finite_triangles
        ));
    }
    let camera = match builder.camera {
        Some(camera) => Some(camera),
        None => match extras_camera(&doc) {
            Some(camera) if camera.validate().is_err() => {
                builder.warnings.unusable_cameras += 1;
                None
            }
            other => other,
        },
    };
    let images = doc
        .images()
        .map(|img| image_source(&img, &buffers, base_dir))
        .collect::<Result<Vec<_>, String>>()?;
    let mut materials = builder.materials;
    if let Some(default) = builder.default_material {
        debug_assert_eq!(default as usize, materials.len());
        materials.push(Material::default());
    }
    Ok(Scene {
        source: path.to_owned(),
        triangles: builder.triangles,
        materials,
        images,
        instances: builder.instances,
        camera,
        warnings: builder.warnings,
    })
}

/// Checks what gltf 1.4 would index or unwrap unchecked: the accessors named
/// by mesh primitive attributes (its validator indexes them), an image's
/// `uri` or `bufferView` + `mimeType`, and a camera's projection of its
/// `type` (both unwrapped when read; found by fuzzing).
fn check_what_gltf_assumes(root: &gltf::json::Root) -> Result<(), String> {
    for (i, image) in root.images.iter().enumerate() {
        match (&image.buffer_view, &image.mime_type, &image.uri) {
            (Some(_), None, _) => {
                return Err(format!(
                    "image {i} has a bufferView but no mimeType (glTF 2.0 requires one)"
                ));
            }
            (None, _, None) => return Err(format!("image {i} has neither a uri nor a bufferView")),
            _ => {}
        }
    }
    for (i, camera) in root.cameras.iter().enumerate() {
        use gltf::json::camera::Type;
        use gltf::json::validation::Checked;
        let consistent = match camera.type_ {
            Checked::Valid(Type::Perspective) => camera.perspective.is_some(),
            Checked::Valid(Type::Orthographic) => camera.orthographic.is_some(),
            // The validator reports an invalid type.
            Checked::Invalid => true,
        };
        if !consistent {
            return Err(format!(
                "camera {i}: its type names a projection the camera does not define"
            ));
        }
    }
    check_attribute_indices(root)
}

/// The accessors named by mesh primitive attributes exist.
fn check_attribute_indices(root: &gltf::json::Root) -> Result<(), String> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for acc in prim.attributes.values() {
                if acc.value() >= root.accessors.len() {
                    return Err(format!(
                        "mesh {m} primitive {p}: attribute accessor {} does not exist ({} accessors)",
                        acc.value(),
                        root.accessors.len()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Accumulates triangles while the node tree is walked.
struct Builder<'a> {
    materials: Vec<Material>,
    /// Index of the default material, appended after the file's materials when first used.
    default_material: Option<u32>,
    triangles: Vec<SceneTriangle>,
    instances: Vec<Instance>,
    camera: Option<Camera>,
    warnings: LoadWarnings,
    buffers: &'a [Vec<u8>],
}

impl Builder<'_> {
    fn add_mesh(&mut self, node: &gltf::Node, mesh: &gltf::Mesh, world: Mat4) -> Result<(), String> {
        let instance = self.instances.len() as u32;
        self.instances.push(Instance {
            node: node.index() as u32,
            name: node.name().map(str::to_owned),
            world_from_object: world,
        });
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        // A mirroring transform turns counter-clockwise corners clockwise; swap two to keep fronts in front.
        let flip = world.determinant() < 0.0;
        for prim in mesh.primitives() {
            let what = format!(
                "mesh {}{} primitive {}",
                mesh.index(),
                mesh.name().map(|n| format!(" '{n}'")).unwrap_or_default(),
                prim.index()
            );
            if matches!(
                prim.mode(),
                Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
            ) {
                self.warnings.skipped_non_triangle_primitives += 1;
                continue;
            }
            let positions_acc = prim
                .get(&Semantic::Positions)
                .ok_or_else(|| format!("{what} has no POSITION attribute"))?;
            let positions = read_vec3(&positions_acc, self.buffers).map_err(|e| format!("{what}: {e}"))?;
            let normals = prim
                .get(&Semantic::Normals)
                .map(|a| read_vec3(&a, self.buffers))
                .transpose()
                .map_err(|e| format!("{what}: {e}"))?;
            let uvs = prim
                .get(&Semantic::TexCoords(0))
                .map(|a| read_texcoords(&a, self.buffers))
                .transpose()
                .map_err(|e| format!("{what}: {e}"))?;
            for (name, len) in [
                ("NORMAL", normals.as_ref().map(Vec::len)),
                ("TEXCOORD_0", uvs.as_ref().map(Vec::len)),
            ] {
                if let Some(len) = len.filter(|&l| l != positions.len()) {
                    return Err(format!(
                        "{what}: {name} has {len} elements but POSITION has {}",
                        positions.len()
                    ));
                }
            }
            let indices = match prim.indices() {
                Some(acc) => read_indices(&acc, self.buffers).map_err(|e| format!("{what}: {e}"))?,
                None => (0..positions.len() as u32).collect(),
            };
            if let Some((i, &bad)) = indices
                .iter()
                .enumerate()
                .find(|&(_, &ix)| ix as usize >= positions.len())
            {
                return Err(format!(
                    "{what}: index {bad} (at position {i}) is out of range: there are {} vertices",
                    positions.len()
                ));
            }
            let material = match prim.material().index() {
                Some(m) => m as u32,
                None => *self.default_material.get_or_insert(self.materials.len() as u32),
            };
            let triangles = triangle_corners(prim.mode(), &indices);
            if prim.mode() != Mode::Triangles {
                self.warnings.converted_strips_and_fans += 1;
            }
            for mut tri in triangles {
                if flip {
                    tri.swap(1, 2);
                }
                let p = tri.map(|i| world.transform_point3(Vec3::from(positions[i as usize])));
                let face = (p[1] - p[0]).cross(p[2] - p[0]);
                // Dropped, not refused: one bad triangle should not cost the
                // whole scene, and the BVH must never see it.
                if !p.iter().all(|v| v.is_finite()) || !face.is_finite() {
                    self.warnings.non_finite_triangles += 1;
                    continue;
                }
                // Scaled first so that tiny and huge (but finite) faces normalise too.
                let largest = face.abs().max_element();
                if largest == 0.0 {
                    self.warnings.degenerate_triangles += 1;
                    continue;
                }
                let face = (face / largest).normalize();
                let n = match &normals {
                    Some(ns) => tri.map(|i| {
                        let n = normal_matrix * Vec3::from(ns[i as usize]);
                        // A zero or non-finite normal (in the file, or from a singular
                        // transform) falls back to the face normal.
                        n.try_normalize().unwrap_or(face)
                    }),
                    None => [face; 3],
                };
                let uv = match &uvs {
                    Some(uvs) => tri.map(|i| Vec2::from(uvs[i as usize])),
                    None => [Vec2::ZERO; 3],
                };
                self.triangles.push(SceneTriangle {
                    positions: p,
                    normals: n,
                    uvs: uv,
                    material,
                    instance,
                });
            }
        }
        Ok(())
    }
}

/// Corner indices of each triangle of a triangle list, strip or fan.
fn triangle_corners(mode: Mode, ix: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (0..ix.len().saturating_sub(2))
            .map(|i| {
                // Every other strip triangle is reversed to keep a consistent winding.
                if i % 2 == 0 {
                    [ix[i], ix[i + 1], ix[i + 2]]
                } else {
                    [ix[i + 1], ix[i], ix[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..ix.len().saturating_sub(1))
            .map(|i| [ix[0], ix[i], ix[i + 1]])
            .collect(),
        // A list with a count not divisible by 3 ignores the incomplete tail.
        _ => ix.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}

/// The material, or why it cannot be used: an `alphaCutoff` that is not a finite number
/// ≥ 0 (glTF 2.0 §5.19 asks for one; a NaN or negative cutoff would silently make the
/// mask all surface or all hole).
fn material(m: &gltf::Material) -> Result<Material, String> {
    let pbr = m.pbr_metallic_roughness();
    let alpha_cutoff = m.alpha_cutoff().unwrap_or(0.5);
    if !(alpha_cutoff.is_finite() && alpha_cutoff >= 0.0) {
        let name = m.name().map(|n| format!(" '{n}'")).unwrap_or_default();
        return Err(format!(
            "material {}{name} has alphaCutoff {alpha_cutoff}; it must be a finite number >= 0",
            m.index().map_or("default".to_owned(), |i| i.to_string())
        ));
    }
    Ok(Material {
        name: m.name().map(str::to_owned),
        base_color_factor: pbr.base_color_factor(),
        base_color_texture: pbr
            .base_color_texture()
            .map(|info| info.texture().source().index() as u32),
        alpha_mode: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask,
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        alpha_cutoff,
        double_sided: m.double_sided(),
        emissive: (Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0)).to_array(),
    })
}

fn image_source(
    img: &gltf::Image,
    buffers: &[Vec<u8>],
    base_dir: Option<&Path>,
) -> Result<ImageSource, String> {
    let what = format!("image {}", img.index());
    match img.source() {
        gltf::image::Source::View { view, mime_type } => {
            let buffer = &buffers[view.buffer().index()];
            let bytes = view
                .offset()
                .checked_add(view.length())
                .and_then(|end| buffer.get(view.offset()..end))
                .ok_or_else(|| format!("{what}: bufferView {} runs past its buffer", view.index()))?;
            Ok(ImageSource::Embedded {
                bytes: bytes.to_vec(),
                mime_type: Some(mime_type.to_owned()),
            })
        }
        gltf::image::Source::Uri { uri, mime_type } if uri.starts_with("data:") => {
            Ok(ImageSource::Embedded {
                bytes: load_uri(uri, base_dir, u64::MAX).map_err(|e| format!("{what}: {e}"))?,
                mime_type: mime_type.map(str::to_owned),
            })
        }
        gltf::image::Source::Uri { uri, .. } => Ok(ImageSource::File(
            resolve_uri_path(uri, base_dir).map_err(|e| format!("{what}: {e}"))?,
        )),
    }
}

/// A glTF camera looks down its node's -Z with +Y up.
fn node_camera(world: Mat4, yfov_radians: f32) -> Camera {
    let eye = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
    let up = world.transform_vector3(Vec3::Y).normalize_or(Vec3::Y);
    Camera {
        eye,
        target: eye + forward,
        up,
        fov_y_degrees: yfov_radians.to_degrees(),
    }
}

/// The camera some converted scenes keep in `asset.extras.camera`
/// (`{eye, target, up, yfov_deg}`); ignored when malformed.
fn extras_camera(doc: &gltf::Document) -> Option<Camera> {
    #[derive(serde::Deserialize)]
    struct ExtrasCamera {
        eye: Vec3,
        target: Vec3,
        #[serde(default = "up")]
        up: Vec3,
        yfov_deg: f32,
    }
    fn up() -> Vec3 {
        Vec3::Y
    }
    #[derive(serde::Deserialize)]
    struct AssetExtras {
        camera: ExtrasCamera,
    }
    let raw = doc.as_json().asset.extras.as_ref()?;
    let extras: AssetExtras = serde_json::from_str(raw.get()).ok()?;
    let c = extras.camera;
    Some(Camera {
        eye: c.eye,
        target: c.target,
        up: c.up,
        fov_y_degrees: c.yfov_deg,
    })
}
