//! A small, deterministic glTF 2.0 binary (.glb) writer for the generated
//! scenes: meshes with positions, normals, optional texture coordinates and `u32`
//! indices, flat-coloured materials (optionally with an alpha-masked PNG base colour
//! texture), node transforms (TRS or matrix) and one perspective camera.
//!
//! The same input always gives the same bytes: the JSON is built in a fixed
//! order, with no timestamps, and every float is written as the shortest
//! decimal that reads back to the same `f32`.

use glam::{Mat4, Quat, Vec3};
use serde_json::{Value, json};

use super::shapes::TriangleMesh;

/// How a node is placed in its parent (the scene root): glTF allows either a
/// translation/rotation/scale triple or a column-major 4×4 matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placement {
    /// `T · R · S`, written as the node's `translation`, `rotation`, `scale`.
    Trs {
        /// Translation.
        translation: Vec3,
        /// Unit rotation quaternion.
        rotation: Quat,
        /// Scale per axis.
        scale: Vec3,
    },
    /// Written as the node's `matrix` (column-major, like glTF).
    Matrix(Mat4),
}

impl Placement {
    /// A pure translation, as TRS.
    pub fn translation(translation: Vec3) -> Self {
        Placement::Trs {
            translation,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        }
    }

    /// The transform as a matrix (object to world).
    pub fn matrix(&self) -> Mat4 {
        match *self {
            Placement::Trs {
                translation,
                rotation,
                scale,
            } => Mat4::from_scale_rotation_translation(scale, rotation, translation),
            Placement::Matrix(m) => m,
        }
    }
}

/// A flat-coloured, fully rough dielectric material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name stored in the file.
    pub name: String,
    /// Linear RGBA `baseColorFactor`.
    pub base_color: [f32; 4],
    /// A base colour texture whose alpha masks the surface (`alphaMode: MASK`).
    pub mask: Option<MaskTexture>,
}

/// An embedded PNG base colour texture and the `alphaCutoff` its alpha is tested with.
#[derive(Clone, Debug, PartialEq)]
pub struct MaskTexture {
    /// The PNG file's bytes.
    pub png: Vec<u8>,
    /// `alphaCutoff`.
    pub cutoff: f32,
}

/// One mesh on its own node.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Name of both the node and the mesh.
    pub name: String,
    /// Geometry, in the node's space.
    pub mesh: TriangleMesh,
    /// TEXCOORD_0, one per position of the mesh, or empty for none.
    pub uvs: Vec<[f32; 2]>,
    /// Index into [`GlbScene::materials`].
    pub material: usize,
    /// Where the node is.
    pub placement: Placement,
}

/// A perspective camera (aspect 1) placed on its own node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlbCamera {
    /// Eye position, world space.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in radians.
    pub yfov_radians: f32,
}

impl GlbCamera {
    /// The camera node's matrix: a rigid transform whose -Z looks from `eye`
    /// at `target` and whose +Y is `up` made orthogonal (glTF's convention).
    pub fn node_matrix(&self) -> Mat4 {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let true_up = right.cross(forward);
        Mat4::from_cols(
            right.extend(0.0),
            true_up.extend(0.0),
            (-forward).extend(0.0),
            self.eye.extend(1.0),
        )
    }
}

/// Everything one .glb file holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GlbScene {
    /// Materials, referenced by index from [`Object::material`].
    pub materials: Vec<Material>,
    /// One node and one mesh each, in this order.
    pub objects: Vec<Object>,
    /// An optional camera, on a node after the objects' nodes.
    pub camera: Option<GlbCamera>,
}

const GLB_MAGIC: &[u8; 4] = b"glTF";
const GLB_VERSION: u32 = 2;
const CHUNK_JSON: &[u8; 4] = b"JSON";
const CHUNK_BIN: &[u8; 4] = b"BIN\0";
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const COMPONENT_F32: u32 = 5126;
const COMPONENT_U32: u32 = 5125;
const MODE_TRIANGLES: u32 = 4;

/// The shortest decimal that reads back (through `f64`, as JSON readers do)
/// as exactly `x`; keeps the JSON readable (`0.1`, not `0.10000000149011612`).
fn json_f32(x: f32) -> Value {
    let short: f64 = x.to_string().parse().unwrap_or(f64::from(x));
    let value = if short as f32 == x { short } else { f64::from(x) };
    serde_json::Number::from_f64(value).map_or(Value::Null, Value::Number)
}

fn json_floats(xs: &[f32]) -> Value {
    Value::Array(xs.iter().copied().map(json_f32).collect())
}

/// The BIN chunk being assembled and the views/accessors that describe it.
#[derive(Default)]
struct BinBuilder {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl BinBuilder {
    /// Appends `data` as a new buffer view, 4-byte aligned, with `target` (none for an
    /// image); returns its index.
    fn push_view(&mut self, data: &[u8], target: Option<u32>) -> usize {
        pad_to_4(&mut self.bytes, 0);
        let mut view = json!({
            "buffer": 0,
            "byteOffset": self.bytes.len(),
            "byteLength": data.len(),
        });
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.views.push(view);
        self.bytes.extend_from_slice(data);
        self.views.len() - 1
    }

    fn push_accessor(&mut self, accessor: Value) -> usize {
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Adds a VEC3 float attribute; returns its accessor index.
    fn push_vec3s(&mut self, data: &[[f32; 3]], with_bounds: bool) -> usize {
        let view = self.push_view(bytemuck::cast_slice(data), Some(ARRAY_BUFFER));
        let mut accessor = json!({
            "bufferView": view,
            "componentType": COMPONENT_F32,
            "count": data.len(),
            "type": "VEC3",
        });
        if with_bounds {
            let (min, max) = vec3_bounds(data);
            accessor["min"] = json_floats(&min);
            accessor["max"] = json_floats(&max);
        }
        self.push_accessor(accessor)
    }

    /// Adds a VEC2 float attribute; returns its accessor index.
    fn push_vec2s(&mut self, data: &[[f32; 2]]) -> usize {
        let view = self.push_view(bytemuck::cast_slice(data), Some(ARRAY_BUFFER));
        self.push_accessor(json!({
            "bufferView": view,
            "componentType": COMPONENT_F32,
            "count": data.len(),
            "type": "VEC2",
        }))
    }

    /// Adds a `u32` index list; returns its accessor index.
    fn push_indices(&mut self, indices: &[u32]) -> usize {
        let view = self.push_view(bytemuck::cast_slice(indices), Some(ELEMENT_ARRAY_BUFFER));
        self.push_accessor(json!({
            "bufferView": view,
            "componentType": COMPONENT_U32,
            "count": indices.len(),
            "type": "SCALAR",
        }))
    }
}

fn vec3_bounds(data: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in data {
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    (min, max)
}

fn pad_to_4(bytes: &mut Vec<u8>, fill: u8) {
    while !bytes.len().is_multiple_of(4) {
        bytes.push(fill);
    }
}

fn node_json(name: &str, placement: &Placement) -> Value {
    match *placement {
        Placement::Trs {
            translation,
            rotation,
            scale,
        } => json!({
            "name": name,
            "translation": json_floats(&translation.to_array()),
            "rotation": json_floats(&rotation.to_array()),
            "scale": json_floats(&scale.to_array()),
        }),
        Placement::Matrix(m) => json!({
            "name": name,
            "matrix": json_floats(&m.to_cols_array()),
        }),
    }
}

/// The material's JSON; a mask texture becomes the next image (a buffer view of `bin`)
/// and texture, index `textures.len()`.
fn material_json(
    material: &Material,
    bin: &mut BinBuilder,
    images: &mut Vec<Value>,
    textures: &mut Vec<Value>,
) -> Value {
    let mut json = json!({
        "name": material.name,
        "pbrMetallicRoughness": {
            "baseColorFactor": json_floats(&material.base_color),
            "metallicFactor": 0,
            "roughnessFactor": 1,
        },
    });
    if let Some(mask) = &material.mask {
        let view = bin.push_view(&mask.png, None);
        images.push(json!({ "bufferView": view, "mimeType": "image/png" }));
        textures.push(json!({ "source": images.len() - 1 }));
        json["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": textures.len() - 1 });
        json["alphaMode"] = json!("MASK");
        json["alphaCutoff"] = json_f32(mask.cutoff);
    }
    json
}

/// The glTF JSON document and its BIN chunk (not yet padded).
fn document(scene: &GlbScene) -> (Value, Vec<u8>) {
    let mut bin = BinBuilder::default();
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    for object in &scene.objects {
        let position = bin.push_vec3s(&object.mesh.positions, true);
        let normal = bin.push_vec3s(&object.mesh.normals, false);
        let mut attributes = json!({ "POSITION": position, "NORMAL": normal });
        if !object.uvs.is_empty() {
            attributes["TEXCOORD_0"] = json!(bin.push_vec2s(&object.uvs));
        }
        let indices = bin.push_indices(&object.mesh.indices);
        let mut node = node_json(&object.name, &object.placement);
        node["mesh"] = json!(meshes.len());
        meshes.push(json!({
            "name": object.name,
            "primitives": [{
                "attributes": attributes,
                "indices": indices,
                "material": object.material,
                "mode": MODE_TRIANGLES,
            }],
        }));
        nodes.push(node);
    }
    let (mut images, mut textures) = (Vec::new(), Vec::new());
    let materials: Vec<Value> = scene
        .materials
        .iter()
        .map(|m| material_json(m, &mut bin, &mut images, &mut textures))
        .collect();
    let mut root = json!({
        "asset": { "version": "2.0", "generator": "penumbra assets generator" },
        "scene": 0,
        "materials": materials,
        "meshes": meshes,
    });
    if !images.is_empty() {
        root["images"] = Value::Array(images);
        root["textures"] = Value::Array(textures);
    }
    if let Some(camera) = &scene.camera {
        let mut node = node_json("camera", &Placement::Matrix(camera.node_matrix()));
        node["camera"] = json!(0);
        nodes.push(node);
        root["cameras"] = json!([{
            "name": "camera",
            "type": "perspective",
            "perspective": {
                "yfov": json_f32(camera.yfov_radians),
                "aspectRatio": 1,
                "znear": json_f32(0.01),
            },
        }]);
    }
    root["scenes"] = json!([{ "name": "scene", "nodes": (0..nodes.len()).collect::<Vec<_>>() }]);
    root["nodes"] = Value::Array(nodes);
    root["accessors"] = Value::Array(bin.accessors);
    root["bufferViews"] = Value::Array(bin.views);
    root["buffers"] = json!([{ "byteLength": bin.bytes.len() }]);
    (root, bin.bytes)
}

fn push_chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    let length = u32::try_from(data.len()).expect("generated GLB chunks stay far below 4 GiB");
    out.extend_from_slice(&length.to_le_bytes());
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
}

/// Encodes `scene` as a binary glTF file.
pub fn write_glb(scene: &GlbScene) -> Vec<u8> {
    let (root, mut bin) = document(scene);
    let mut json = serde_json::to_vec(&root).expect("a JSON value always serialises");
    // The spec pads the JSON chunk with spaces and the BIN chunk with zeros.
    pad_to_4(&mut json, b' ');
    pad_to_4(&mut bin, 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&GLB_VERSION.to_le_bytes());
    let total = u32::try_from(total).expect("generated GLB files stay far below 4 GiB");
    out.extend_from_slice(&total.to_le_bytes());
    push_chunk(&mut out, CHUNK_JSON, &json);
    push_chunk(&mut out, CHUNK_BIN, &bin);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assets::shapes;

    fn sample_scene() -> GlbScene {
        GlbScene {
            materials: vec![Material {
                name: "grey".into(),
                base_color: [0.5, 0.5, 0.5, 1.0],
                mask: None,
            }],
            objects: vec![
                Object {
                    name: "box".into(),
                    mesh: shapes::box_on_ground(Vec3::new(1.0, 0.5, 0.1)),
                    uvs: Vec::new(),
                    material: 0,
                    placement: Placement::Trs {
                        translation: Vec3::new(1.0, 0.0, -2.0),
                        rotation: Quat::from_xyzw(0.0, 0.6, 0.0, 0.8),
                        scale: Vec3::ONE,
                    },
                },
                Object {
                    name: "ball".into(),
                    mesh: shapes::uv_sphere(0.3, 6, 8),
                    uvs: Vec::new(),
                    material: 0,
                    placement: Placement::Matrix(Mat4::from_translation(Vec3::Y * 0.3)),
                },
            ],
            camera: Some(GlbCamera {
                eye: Vec3::new(3.0, 2.0, 4.0),
                target: Vec3::ZERO,
                up: Vec3::Y,
                yfov_radians: 0.8,
            }),
        }
    }

    #[test]
    fn gltf_crate_accepts_the_output() {
        let bytes = write_glb(&sample_scene());
        assert!(bytes.len().is_multiple_of(4));
        assert_eq!(&bytes[..4], b"glTF");
        let gltf = gltf::Gltf::from_slice(&bytes).expect("valid glTF");
        assert_eq!(gltf.meshes().count(), 2);
        assert_eq!(gltf.nodes().count(), 3);
        assert_eq!(gltf.cameras().count(), 1);
        assert_eq!(gltf.document.as_json().asset.version, "2.0");
        let blob = gltf.blob.as_ref().expect("BIN chunk");
        let buffer = gltf.buffers().next().expect("one buffer");
        assert_eq!(buffer.length(), blob.len());
        for view in gltf.views() {
            assert!(view.offset().is_multiple_of(4));
        }
        let position = gltf.meshes().next().unwrap().primitives().next().unwrap();
        let bounds = position.bounding_box();
        assert_eq!(bounds.min, [-0.5, 0.0, -0.05]);
        assert_eq!(bounds.max, [0.5, 0.5, 0.05]);
    }

    #[test]
    fn output_is_deterministic() {
        assert_eq!(write_glb(&sample_scene()), write_glb(&sample_scene()));
    }

    #[test]
    fn camera_node_looks_down_its_negative_z() {
        let camera = sample_scene().camera.unwrap();
        let m = camera.node_matrix();
        let forward = m.transform_vector3(Vec3::NEG_Z);
        let expected = (camera.target - camera.eye).normalize();
        assert!(forward.abs_diff_eq(expected, 1e-6));
        assert!(m.transform_point3(Vec3::ZERO).abs_diff_eq(camera.eye, 1e-6));
        assert!(m.transform_vector3(Vec3::Y).y > 0.0);
    }

    #[test]
    fn floats_are_written_short_and_exact() {
        assert_eq!(json_f32(0.1).to_string(), "0.1");
        for x in [0.1f32, 1.0 / 3.0, 1e-7, 12345.678, -0.04] {
            let back: f64 = json_f32(x).as_f64().unwrap();
            assert_eq!(back as f32, x);
        }
    }
}
