//! Writes the seed corpora of the fuzz targets (see README, "Fuzzing"):
//!
//! - `fuzz/corpus/scene_loader/`: the generated scenes `assets/*.glb`, each
//!   also as a `.gltf` whose buffer is a data URI, and two small files (a
//!   quad; a textured, strip-drawn, camera-carrying quad with normals, UVs
//!   and TRS and matrix nodes), each as GLB and as glTF JSON. Small seeds
//!   matter: libFuzzer mutates small inputs much faster.
//! - `fuzz/corpus/view_parser/`: the views `assets/views/*.json`.
//!
//! `cargo run --release --example fuzz_seeds`; the corpora are git-ignored.

use std::path::{Path, PathBuf};

use base64::Engine;
use serde_json::{Value, json};

fn main() -> std::io::Result<()> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scenes = root.join("fuzz/corpus/scene_loader");
    let views = root.join("fuzz/corpus/view_parser");
    std::fs::create_dir_all(&scenes)?;
    std::fs::create_dir_all(&views)?;
    let mut written = 0;

    for path in files_with_extension(&root.join("assets"), "glb")? {
        let glb = std::fs::read(&path)?;
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let (json, bin) = split_glb(&glb);
        std::fs::write(scenes.join(format!("{name}.glb")), &glb)?;
        std::fs::write(scenes.join(format!("{name}.gltf")), data_uri_gltf(json, bin))?;
        written += 2;
    }
    for (name, (json, bin)) in [("quad", quad()), ("rich_quad", rich_quad())] {
        std::fs::write(scenes.join(format!("{name}.glb")), glb(&json, &bin))?;
        std::fs::write(scenes.join(format!("{name}.gltf")), data_uri_gltf(json, &bin))?;
        written += 2;
    }
    for path in files_with_extension(&root.join("assets/views"), "json")? {
        std::fs::copy(&path, views.join(path.file_name().unwrap()))?;
        written += 1;
    }
    println!(
        "wrote {written} seeds to {} and {}",
        scenes.display(),
        views.display()
    );
    Ok(())
}

fn files_with_extension(dir: &Path, ext: &str) -> std::io::Result<Vec<PathBuf>> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()?;
    out.retain(|p| p.extension().is_some_and(|e| e == ext));
    out.sort();
    Ok(out)
}

/// The JSON and BIN chunks of a GLB file the project wrote (so well-formed).
fn split_glb(glb: &[u8]) -> (Value, &[u8]) {
    let u32_at = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    let json_len = u32_at(12);
    let json = serde_json::from_slice(&glb[20..20 + json_len]).expect("the GLB's JSON chunk");
    let bin_at = 20 + json_len;
    let bin_len = u32_at(bin_at);
    (json, &glb[bin_at + 8..bin_at + 8 + bin_len])
}

/// `json` as a `.gltf` file whose buffer 0 is `bin` as a base64 data URI.
fn data_uri_gltf(mut json: Value, bin: &[u8]) -> Vec<u8> {
    let b64 = base64::engine::general_purpose::STANDARD.encode(bin);
    json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{b64}"));
    serde_json::to_vec(&json).unwrap()
}

/// A GLB file of `json` and `bin`.
fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(json).unwrap();
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// Two triangles in the z = 0 plane, u16 indices.
fn quad() -> (Value, Vec<u8>) {
    let mut bin = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0]);
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let json = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    });
    (json, bin)
}

/// The quad drawn as a strip with normals, UVs, a material with an embedded
/// 1×1 PNG texture, on a TRS node under a matrix node, plus a camera node.
fn rich_quad() -> (Value, Vec<u8>) {
    let mut bin = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0]); // 0..48
    bin.extend(floats(&[0.0, 0.0, 1.0].repeat(4))); // normals 48..96
    bin.extend(floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0])); // uvs 96..128
    bin.extend([0u8, 1, 2, 3]); // strip indices 128..132
    let png = {
        let mut png = Vec::new();
        image::RgbImage::from_pixel(1, 1, image::Rgb([200, 100, 50]))
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        png
    };
    let png_at = bin.len();
    bin.extend(&png);
    let json = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 2]}],
        "nodes": [
            {"matrix": [1.0,0.0,0.0,0.0, 0.0,1.0,0.0,0.0, 0.0,0.0,1.0,0.0, 0.0,2.0,0.0,1.0], "children": [1]},
            {"mesh": 0, "translation": [1.0, 0.0, 0.0], "rotation": [0.0, 0.0, 0.0, 1.0], "scale": [2.0, 2.0, 2.0]},
            {"camera": 0, "translation": [0.0, 1.0, 5.0]}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
            "indices": 3, "mode": 5, "material": 0
        }]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.5, 0.5, 1.0],
                                                 "baseColorTexture": {"index": 0}},
                       "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": true}],
        "textures": [{"source": 0}],
        "images": [{"bufferView": 4, "mimeType": "image/png"}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 32},
            {"buffer": 0, "byteOffset": 128, "byteLength": 4},
            {"buffer": 0, "byteOffset": png_at, "byteLength": png.len()}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5121, "count": 4, "type": "SCALAR"}
        ]
    });
    (json, bin)
}
