//! The glTF loader: the generated assets, valid variations of a small file
//! (buffers, index types, modes, transforms), and malformed files, each of which
//! must give an error naming the file and the problem, never a panic.

use std::path::{Path, PathBuf};

use glam::Vec3;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::pass_inputs::{ShadingData, texture_dimensions};
use penumbra::scene::Scene;
use penumbra::{Error, assets};
use serde_json::{Value, json};

/// A quad of 4 vertices in the z = 0 plane ([0,1]²) and 6 u16 indices.
const QUAD: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
const QUAD_INDICES: [u32; 6] = [0, 1, 2, 0, 2, 3];

/// A test file under construction: the JSON document and the bytes of buffer 0.
struct TestFile {
    json: Value,
    bin: Vec<u8>,
}

impl TestFile {
    /// One mesh (POSITION + u16 indices) on one node in one scene.
    fn quad() -> Self {
        let mut bin: Vec<u8> = QUAD.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
        let index_offset = bin.len();
        bin.extend(QUAD_INDICES.iter().flat_map(|&i| (i as u16).to_le_bytes()));
        let json = json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "buffers": [{"byteLength": bin.len()}],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": index_offset},
                {"buffer": 0, "byteOffset": index_offset, "byteLength": 12}
            ],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                 "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
                {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}
            ]
        });
        TestFile { json, bin }
    }

    /// Appends bytes to buffer 0 as a new buffer view; returns the view index.
    fn add_view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.json["buffers"][0]["byteLength"] = json!(self.bin.len());
        let views = self.json["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}));
        views.len() - 1
    }

    /// Adds an accessor; returns its index.
    fn add_accessor(&mut self, accessor: Value) -> usize {
        let accessors = self.json["accessors"].as_array_mut().unwrap();
        accessors.push(accessor);
        accessors.len() - 1
    }

    fn primitive(&mut self) -> &mut Value {
        &mut self.json["meshes"][0]["primitives"][0]
    }

    /// `.gltf` + external `.bin` in a fresh directory; returns the `.gltf` path.
    fn write_gltf(&self, name: &str) -> PathBuf {
        let dir = test_dir(name);
        let mut json = self.json.clone();
        json["buffers"][0]["uri"] = json!(format!("{name}.bin"));
        std::fs::write(dir.join(format!("{name}.bin")), &self.bin).unwrap();
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
        path
    }

    /// `.gltf` with the buffer as a base64 data URI.
    fn gltf_data_uri(&self) -> Vec<u8> {
        use base64::Engine;
        let mut json = self.json.clone();
        let b64 = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{b64}"));
        serde_json::to_vec(&json).unwrap()
    }

    /// `.glb` bytes.
    fn glb(&self) -> Vec<u8> {
        let mut json = serde_json::to_vec(&self.json).unwrap();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::new();
        out.extend(b"glTF");
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(0x4E4F_534Au32.to_le_bytes());
        out.extend(json);
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(0x004E_4942u32.to_le_bytes());
        out.extend(bin);
        out
    }
}

fn test_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("scene_loader")
        .join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn load_glb(bytes: &[u8]) -> Result<Scene, Error> {
    Scene::from_bytes(bytes, Path::new("test.glb"))
}

/// Asserts that loading fails with an error naming `path` and containing `needle`.
fn assert_error(result: Result<Scene, Error>, path: &str, needle: &str) {
    match result {
        Ok(s) => panic!(
            "expected an error containing '{needle}', loaded {} triangles",
            s.triangles.len()
        ),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.contains(path), "error does not name the file {path}: {msg}");
            assert!(msg.contains(needle), "error does not say '{needle}': {msg}");
        }
    }
}

#[test]
fn quad_loads_from_glb_gltf_and_data_uri() {
    let f = TestFile::quad();
    let from_glb = load_glb(&f.glb()).unwrap();
    let from_file = Scene::load(&f.write_gltf("quad")).unwrap();
    let from_uri = Scene::from_bytes(&f.gltf_data_uri(), Path::new("quad.gltf")).unwrap();
    for s in [&from_glb, &from_file, &from_uri] {
        assert_eq!(s.triangles.len(), 2);
        let b = s.bounds();
        assert_eq!((b.min, b.max), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
        // No NORMAL attribute: flat normals from the counter-clockwise winding (+z).
        assert!(s.triangles.iter().all(|t| t.normals == [Vec3::Z; 3]));
        assert_eq!(
            s.materials.len(),
            1,
            "a default material is added for primitives without one"
        );
    }
    assert_eq!(from_glb.triangles, from_file.triangles);
    assert_eq!(from_glb.triangles, from_uri.triangles);
}

#[test]
fn index_types_and_non_indexed_give_the_same_triangles() {
    let reference = load_glb(&TestFile::quad().glb()).unwrap().triangles;
    for (component, bytes) in [
        (5121, QUAD_INDICES.iter().map(|&i| i as u8).collect::<Vec<u8>>()),
        (5125, QUAD_INDICES.iter().flat_map(|&i| i.to_le_bytes()).collect()),
    ] {
        let mut f = TestFile::quad();
        let view = f.add_view(&bytes);
        let acc = f.add_accessor(
            json!({"bufferView": view, "componentType": component, "count": 6, "type": "SCALAR"}),
        );
        f.primitive()["indices"] = json!(acc);
        assert_eq!(
            load_glb(&f.glb()).unwrap().triangles,
            reference,
            "component type {component}"
        );
    }
    // Non-indexed: six vertices in index order.
    let mut f = TestFile::quad();
    let flat: Vec<u8> = QUAD_INDICES
        .iter()
        .flat_map(|&i| QUAD[i as usize])
        .flat_map(f32::to_le_bytes)
        .collect();
    let view = f.add_view(&flat);
    let acc = f.add_accessor(
        json!({"bufferView": view, "componentType": 5126, "count": 6, "type": "VEC3",
        "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}),
    );
    f.primitive()["attributes"]["POSITION"] = json!(acc);
    f.primitive().as_object_mut().unwrap().remove("indices");
    assert_eq!(load_glb(&f.glb()).unwrap().triangles, reference);
}

#[test]
fn strips_and_fans_become_lists() {
    // Strip 0 1 3 2 and fan 0 1 2 3 both cover the quad with two front-facing triangles.
    for (mode, order) in [(5, [0u16, 1, 3, 2]), (6, [0, 1, 2, 3])] {
        let mut f = TestFile::quad();
        let view = f.add_view(&order.iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<_>>());
        let acc =
            f.add_accessor(json!({"bufferView": view, "componentType": 5123, "count": 4, "type": "SCALAR"}));
        f.primitive()["indices"] = json!(acc);
        f.primitive()["mode"] = json!(mode);
        let s = load_glb(&f.glb()).unwrap();
        assert_eq!(s.triangles.len(), 2, "mode {mode}");
        assert!(
            s.triangles.iter().all(|t| t.normals[0] == Vec3::Z),
            "mode {mode}: winding kept"
        );
        assert_eq!(s.warnings.converted_strips_and_fans, 1);
    }
}

#[test]
fn node_transforms_compose_and_mirroring_keeps_winding() {
    let mut f = TestFile::quad();
    // Parent: TRS translation; child: matrix scaling x by -2 (a mirror).
    f.json["nodes"] = json!([
        {"translation": [10.0, 0.0, 0.0], "children": [1]},
        {"matrix": [-2.0,0.0,0.0,0.0, 0.0,1.0,0.0,0.0, 0.0,0.0,1.0,0.0, 0.0,0.0,5.0,1.0], "mesh": 0}
    ]);
    let s = load_glb(&f.glb()).unwrap();
    let b = s.bounds();
    assert_eq!(
        (b.min, b.max),
        (Vec3::new(8.0, 0.0, 5.0), Vec3::new(10.0, 1.0, 5.0))
    );
    for t in &s.triangles {
        let face = (t.positions[1] - t.positions[0])
            .cross(t.positions[2] - t.positions[0])
            .normalize();
        assert_eq!(face, Vec3::Z, "mirrored mesh must still face +z");
    }
    assert_eq!(s.instances.len(), 1);
    assert_eq!(s.instances[0].node, 1);
}

#[test]
fn points_beside_triangles_are_skipped_with_a_warning() {
    let mut f = TestFile::quad();
    let tri = f.primitive().clone();
    f.json["meshes"][0]["primitives"] = json!([tri, {"attributes": {"POSITION": 0}, "mode": 0}]);
    let s = load_glb(&f.glb()).unwrap();
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.warnings.skipped_non_triangle_primitives, 1);
}

#[test]
fn zero_area_triangles_are_dropped_and_counted() {
    let mut f = TestFile::quad();
    let view = f.add_view(
        &[0u16, 1, 2, 0, 0, 3, 1, 1, 1]
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect::<Vec<_>>(),
    );
    let acc =
        f.add_accessor(json!({"bufferView": view, "componentType": 5123, "count": 9, "type": "SCALAR"}));
    f.primitive()["indices"] = json!(acc);
    let s = load_glb(&f.glb()).unwrap();
    assert_eq!(s.triangles.len(), 1);
    assert_eq!(s.warnings.degenerate_triangles, 2);
}

#[test]
fn generated_assets_load_with_expected_counts_and_bounds() {
    assert!(!assets::EMBEDDED_SCENES.is_empty());
    for embedded in assets::EMBEDDED_SCENES {
        let s = Scene::from_bytes(embedded.glb, Path::new(embedded.file_name)).unwrap();
        let generated =
            assets::generate::generate(embedded.name).expect("a generator for every embedded scene");
        let again = Scene::from_bytes(&generated.glb, Path::new(embedded.file_name)).unwrap();
        assert_eq!(s.triangles.len(), again.triangles.len(), "{}", embedded.name);
        assert!(
            s.triangles.len() > 500,
            "{}: {} triangles",
            embedded.name,
            s.triangles.len()
        );
        assert_eq!(
            s.warnings,
            Default::default(),
            "{}: generated files load cleanly",
            embedded.name
        );
        let b = s.bounds();
        // Everything stands on the ground plane y = 0, which spans the scene.
        assert_eq!(b.min.y, 0.0, "{}", embedded.name);
        assert!(
            b.max.y > 0.5 && b.max.x - b.min.x > 5.0 && b.max.z - b.min.z > 5.0,
            "{}: {b:?}",
            embedded.name
        );
        assert!(
            s.camera.is_some(),
            "{}: the file carries its camera",
            embedded.name
        );
        let view = embedded.view();
        assert!(
            view.light.area_normal().y < 0.0,
            "{}: light faces down",
            embedded.name
        );
    }
}

#[test]
fn truncated_glb() {
    let glb = TestFile::quad().glb();
    for cut in [5, 12, 30, glb.len() - 3] {
        assert_error(load_glb(&glb[..cut]), "test.glb", "truncated");
    }
}

#[test]
fn lying_chunk_length_and_wrong_version() {
    let mut glb = TestFile::quad().glb();
    glb[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    assert_error(load_glb(&glb), "test.glb", "GLB chunk at byte 12");
    let mut glb = TestFile::quad().glb();
    glb[4] = 1;
    assert_error(load_glb(&glb), "test.glb", "version 1");
    let mut glb = TestFile::quad().glb();
    glb[3] = b'X'; // wrong magic: not GLB, and not JSON either
    assert_error(load_glb(&glb), "test.glb", "invalid glTF JSON");
}

#[test]
fn bad_accessor() {
    let mut f = TestFile::quad();
    f.json["accessors"][0]["count"] = json!(5); // 5 × 12 bytes > the 48-byte view
    assert_error(load_glb(&f.glb()), "test.glb", "does not fit in bufferView 0");
    let mut f = TestFile::quad();
    f.json["accessors"][0]["count"] = json!(u32::MAX);
    assert_error(load_glb(&f.glb()), "test.glb", "does not fit");
    let mut f = TestFile::quad();
    f.json["accessors"][0]["componentType"] = json!(5123);
    assert_error(load_glb(&f.glb()), "test.glb", "expected VEC3 of FLOAT");
    let mut f = TestFile::quad();
    f.json["bufferViews"][0]["byteLength"] = json!(1 << 30);
    assert_error(load_glb(&f.glb()), "test.glb", "runs past the end of buffer 0");
    let mut f = TestFile::quad();
    f.json["accessors"][0]["bufferView"] = json!(7); // no such view: the glTF validator catches it
    assert_error(load_glb(&f.glb()), "test.glb", "invalid glTF");
}

#[test]
fn missing_bin() {
    let path = TestFile::quad().write_gltf("missing_bin");
    std::fs::remove_file(path.with_extension("bin")).unwrap();
    let shown = path.display().to_string();
    assert_error(Scene::load(&path), &shown, "cannot read");
    assert_error(Scene::load(&path), &shown, "missing_bin.bin");
}

#[test]
fn short_bin() {
    let path = TestFile::quad().write_gltf("short_bin");
    std::fs::write(path.with_extension("bin"), [0u8; 10]).unwrap();
    assert_error(
        Scene::load(&path),
        &path.display().to_string(),
        "buffer 0 is truncated",
    );
}

#[test]
fn out_of_range_index() {
    let mut f = TestFile::quad();
    let view = f.add_view(
        &[0u16, 1, 4]
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect::<Vec<_>>(),
    );
    let acc =
        f.add_accessor(json!({"bufferView": view, "componentType": 5123, "count": 3, "type": "SCALAR"}));
    f.primitive()["indices"] = json!(acc);
    assert_error(
        load_glb(&f.glb()),
        "test.glb",
        "index 4 (at position 2) is out of range: there are 4 vertices",
    );
}

/// Asserts that loading fails with exactly `expected`.
fn assert_exact_error(result: Result<Scene, Error>, expected: &str) {
    match result {
        Ok(s) => panic!("expected '{expected}', loaded {} triangles", s.triangles.len()),
        Err(e) => assert_eq!(e.to_string(), expected),
    }
}

#[test]
fn nan_and_infinite_positions_drop_their_triangles() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        // Vertex 1 (bytes 12..24) is only in the first triangle.
        let mut f = TestFile::quad();
        f.bin[16..20].copy_from_slice(&bad.to_le_bytes());
        let s = load_glb(&f.glb()).unwrap();
        assert_eq!(s.triangles.len(), 1, "{bad}");
        assert_eq!(s.warnings.non_finite_triangles, 1, "{bad}");
        assert_eq!(s.warnings.degenerate_triangles, 0, "{bad}");
        assert_eq!(
            s.warnings.messages(),
            ["dropped 1 triangle(s) with non-finite (NaN or infinite) positions"]
        );
        assert!(
            s.triangles
                .iter()
                .all(|t| t.positions.iter().all(|p| p.is_finite()))
        );
        // Vertex 0 is in both: nothing is left, which is an error.
        let mut f = TestFile::quad();
        f.bin[4..8].copy_from_slice(&bad.to_le_bytes());
        assert_exact_error(
            load_glb(&f.glb()),
            "test.glb: scene 0 has no triangles (0 point/line primitives, 0 zero-area and 2 \
             non-finite triangles skipped)",
        );
    }
}

#[test]
fn positions_overflowing_the_node_transform_drop_their_triangles() {
    // Finite in the file, infinite in the world: 1e20 × 1e19 overflows f32
    // (while the other triangle's area, about 1e38, still fits).
    let mut f = TestFile::quad();
    f.json["nodes"][0]["scale"] = json!([1e19, 1e19, 1e19]);
    f.bin[16..20].copy_from_slice(&1e20f32.to_le_bytes());
    let s = load_glb(&f.glb()).unwrap();
    assert_eq!((s.triangles.len(), s.warnings.non_finite_triangles), (1, 1));

    // A node whose transform is not finite (1e39 is infinite as an f32) loses
    // its triangles; the other node keeps its own.
    let mut f = TestFile::quad();
    f.json["scenes"] = json!([{"nodes": [0, 1]}]);
    f.json["nodes"] = json!([{"mesh": 0}, {"mesh": 0, "scale": [1e39, 1.0, 1.0]}]);
    let s = load_glb(&f.glb()).unwrap();
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.warnings.non_finite_triangles, 2);
    assert!(s.triangles.iter().all(|t| t.instance == 0));
}

#[test]
fn non_finite_normals_fall_back_to_the_face_normal() {
    let mut f = TestFile::quad();
    let normals: Vec<u8> = [
        [0.0, 0.0, 1.0],
        [f32::NAN, 0.0, 1.0],
        [0.0, f32::INFINITY, 0.0],
        [0.0; 3],
    ]
    .iter()
    .flatten()
    .flat_map(|c: &f32| c.to_le_bytes())
    .collect();
    let view = f.add_view(&normals);
    let acc = f.add_accessor(json!({"bufferView": view, "componentType": 5126, "count": 4, "type": "VEC3"}));
    f.primitive()["attributes"]["NORMAL"] = json!(acc);
    let s = load_glb(&f.glb()).unwrap();
    assert_eq!(s.warnings, Default::default());
    for t in &s.triangles {
        assert_eq!(
            t.normals,
            [Vec3::Z; 3],
            "every normal is usable or replaced by the face's"
        );
    }
}

#[test]
fn unusable_file_cameras_are_ignored_and_counted() {
    // A vertical field of view of 3.2 radians (183°) gives no image.
    let mut f = TestFile::quad();
    f.json["scenes"] = json!([{"nodes": [0, 1]}]);
    f.json["nodes"] = json!([{"mesh": 0}, {"camera": 0}]);
    f.json["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 3.2, "znear": 0.1}}]);
    let s = load_glb(&f.glb()).unwrap();
    assert_eq!(s.camera, None);
    assert_eq!(s.warnings.unusable_cameras, 1);
    assert_eq!(s.warnings.messages(), ["ignored 1 unusable camera(s)"]);
}

#[test]
fn cyclic_node_graph() {
    let mut f = TestFile::quad();
    f.json["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
    assert_error(load_glb(&f.glb()), "test.glb", "reached twice");
}

#[test]
fn compressed_meshes_are_refused() {
    let mut f = TestFile::quad();
    f.json["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    f.json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    assert_error(load_glb(&f.glb()), "test.glb", "KHR_draco_mesh_compression");
}

#[test]
fn files_without_triangles() {
    let mut f = TestFile::quad();
    f.primitive()["mode"] = json!(1); // lines only
    assert_error(
        load_glb(&f.glb()),
        "test.glb",
        "no triangles (1 point/line primitives",
    );
    let mut f = TestFile::quad();
    f.json["scenes"] = json!([{"nodes": []}]);
    assert_error(load_glb(&f.glb()), "test.glb", "no triangles");
    let mut f = TestFile::quad();
    f.json.as_object_mut().unwrap().remove("scene");
    f.json.as_object_mut().unwrap().remove("scenes");
    assert_error(load_glb(&f.glb()), "test.glb", "defines no scene");
}

#[test]
fn garbage_never_panics() {
    // Every prefix and many single-byte corruptions of a valid file: errors, not panics.
    let glb = TestFile::quad().glb();
    for cut in 0..glb.len() {
        let _ = load_glb(&glb[..cut]);
    }
    for i in 0..glb.len() {
        for v in [0u8, 0xff, b'9'] {
            let mut g = glb.clone();
            g[i] = v;
            let _ = load_glb(&g);
        }
    }
    let _ = load_glb(b"");
    let _ = Scene::from_bytes(b"{\"asset\":{\"version\":\"2.0\"}}", Path::new("x.gltf"));
}

#[test]
fn missing_or_unreadable_texture_is_an_error_naming_the_file() {
    let mut f = TestFile::quad();
    f.json["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    f.json["textures"] = json!([{"source": 0}]);
    f.json["images"] = json!([{"uri": "wood.png"}]);
    f.primitive()["material"] = json!(0);
    let path = f.write_gltf("missing_texture");
    let texture = path.with_file_name("wood.png");
    let _ = std::fs::remove_file(&texture);
    let _ = std::fs::remove_dir(&texture);
    // Textures are read when a renderer needs them, not by the loader.
    let scene = Scene::load(&path).unwrap();
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let prefix = format!("{}: image 0 '{}'", path.display(), texture.display());

    let io = std::fs::read(&texture).unwrap_err();
    let expected = format!("{prefix}: cannot read the texture: {io}");
    assert_eq!(ShadingData::new(&scene, &bvh).unwrap_err().to_string(), expected);
    assert_eq!(texture_dimensions(&scene, 0).unwrap_err().to_string(), expected);

    std::fs::write(&texture, b"not an image").unwrap();
    let expected = format!("{prefix}: cannot decode the texture: The image format could not be determined");
    assert_eq!(ShadingData::new(&scene, &bvh).unwrap_err().to_string(), expected);
    assert_eq!(texture_dimensions(&scene, 0).unwrap_err().to_string(), expected);

    std::fs::remove_file(&texture).unwrap();
    std::fs::create_dir(&texture).unwrap();
    let expected = format!("{prefix}: cannot read the texture: not a regular file");
    assert_eq!(ShadingData::new(&scene, &bvh).unwrap_err().to_string(), expected);
    std::fs::remove_dir(&texture).unwrap();

    // A real texture loads, and its size is read from the header alone.
    image::RgbaImage::from_pixel(3, 2, image::Rgba([255, 0, 0, 255]))
        .save(&texture)
        .unwrap();
    assert_eq!(texture_dimensions(&scene, 0).unwrap(), (3, 2));
    let data = ShadingData::new(&scene, &bvh).unwrap();
    assert_eq!(data.texels.len(), 6);
}

#[test]
fn what_the_gltf_crate_would_unwrap_is_an_error() {
    // Found by fuzzing: the gltf crate unwraps these when the image is read.
    let mut f = TestFile::quad();
    f.json["images"] = json!([{"name": "nothing"}]);
    assert_exact_error(
        load_glb(&f.glb()),
        "test.glb: image 0 has neither a uri nor a bufferView",
    );
    let mut f = TestFile::quad();
    f.json["images"] = json!([{"bufferView": 0}]);
    assert_exact_error(
        load_glb(&f.glb()),
        "test.glb: image 0 has a bufferView but no mimeType (glTF 2.0 requires one)",
    );
    // Found reading the gltf crate after that: the projection is unwrapped by type.
    let mut f = TestFile::quad();
    f.json["cameras"] = json!([{"type": "perspective", "orthographic":
        {"xmag": 1.0, "ymag": 1.0, "zfar": 10.0, "znear": 0.1}}]);
    f.json["nodes"] = json!([{"mesh": 0, "camera": 0}]);
    assert_exact_error(
        load_glb(&f.glb()),
        "test.glb: camera 0: its type names a projection the camera does not define",
    );
}

#[test]
fn inputs_that_crashed_the_fuzzer_are_errors() {
    // Each file under tests/fuzz_regressions/scene_loader/ once panicked the loader
    // (see README, "Fuzzing"); loaded as the fuzz target loads it.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions/scene_loader");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(!files.is_empty());
    for file in files {
        let bytes = std::fs::read(&file).unwrap();
        for name in [
            "/nonexistent-fuzz-dir/fuzz.glb",
            "/nonexistent-fuzz-dir/fuzz.gltf",
        ] {
            let err = Scene::from_bytes(&bytes, Path::new(name))
                .expect_err(&format!("{}: a malformed file", file.display()));
            eprintln!("{}: {err}", file.display());
        }
    }
}

/// An `alphaCutoff` that is not a finite number ≥ 0 is refused, naming the file and the
/// material: negative (which the JSON can say) or beyond f32 (1e999, which f32 reads as ∞).
#[test]
fn alpha_cutoff_that_is_not_a_finite_number_is_an_error() {
    let mut file = TestFile::quad();
    file.json["materials"] = json!([{"name": "leaves", "alphaMode": "MASK", "alphaCutoff": -0.5}]);
    file.primitive()["material"] = json!(0);
    assert_error(
        load_glb(&file.glb()),
        "test.glb",
        "material 0 'leaves' has alphaCutoff -0.5",
    );
    file.json["materials"][0]["alphaCutoff"] = json!(12345.0);
    let text = String::from_utf8(file.gltf_data_uri())
        .unwrap()
        .replace("12345.0", "1e999");
    let path = test_dir("alpha_cutoff").join("infinite.gltf");
    std::fs::write(&path, text).unwrap();
    match Scene::load(&path) {
        Ok(_) => panic!("alphaCutoff 1e999 loaded"),
        Err(e) => {
            let msg = e.to_string();
            assert!(
                msg.contains("infinite.gltf") && msg.contains("out of range"),
                "{msg}"
            );
        }
    }
}
