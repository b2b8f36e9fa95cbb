//! The committed scenes under `assets/` are exactly what the generator makes,
//! load as glTF, and come with usable views.

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use penumbra::assets::{self, generate::GeneratedScene, generate::generate_all};

const REGENERATE: &str = "run `cargo run --release --example generate_assets` and commit the result";

fn assets_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets")
}

fn read(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}; {REGENERATE}", path.display()))
}

/// Expected (meshes, nodes including the camera's, materials) per scene.
fn expected_counts(name: &str) -> (usize, usize, usize) {
    match name {
        "playground" => (8, 9, 6),
        "lattice" => (7, 8, 6),
        "screen" => (3, 4, 7),
        other => panic!("no expected counts for scene {other}"),
    }
}

/// World-space bounds of every mesh node, from the POSITION accessors'
/// min/max and the node transforms, by node name.
fn node_bounds(scene: &GeneratedScene) -> Vec<(String, Vec3, Vec3)> {
    let gltf = gltf::Gltf::from_slice(&scene.glb).expect("valid glTF");
    let mut bounds = Vec::new();
    for node in gltf.nodes() {
        let Some(mesh) = node.mesh() else { continue };
        let matrix = Mat4::from_cols_array_2d(&node.transform().matrix());
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for primitive in mesh.primitives() {
            let bbox = primitive.bounding_box();
            for corner in 0..8 {
                let pick = |axis: usize| {
                    if corner & (1 << axis) == 0 {
                        bbox.min[axis]
                    } else {
                        bbox.max[axis]
                    }
                };
                let p = matrix.transform_point3(Vec3::new(pick(0), pick(1), pick(2)));
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        bounds.push((node.name().unwrap_or("").to_owned(), lo, hi));
    }
    bounds
}

#[test]
fn committed_files_match_the_generator() {
    for scene in generate_all() {
        let glb_path = assets_dir().join(format!("{}.glb", scene.name));
        assert!(
            read(&glb_path) == scene.glb,
            "{} differs from the generator's output; {REGENERATE}",
            glb_path.display()
        );
        let view_path = assets_dir().join("views").join(format!("{}.json", scene.name));
        let view_json = String::from_utf8(read(&view_path)).expect("view files are UTF-8");
        assert_eq!(
            view_json,
            format!("{}\n", scene.view.to_json()),
            "{} differs from the generator's output; {REGENERATE}",
            view_path.display()
        );
    }
}

#[test]
fn embedded_scenes_are_the_generated_ones() {
    let generated = generate_all();
    let names: Vec<_> = assets::EMBEDDED_SCENES.iter().map(|s| s.name).collect();
    let generated_names: Vec<_> = generated.iter().map(|s| s.name).collect();
    assert_eq!(names, generated_names);
    assert_eq!(assets::default_scene().name, "playground");
    assert!(assets::embedded_scene("no such scene").is_none());
    for scene in &generated {
        let embedded = assets::embedded_scene(scene.name).expect("embedded");
        assert_eq!(embedded.file_name, format!("{}.glb", scene.name));
        assert!(embedded.glb == scene.glb, "{}: {REGENERATE}", scene.name);
        assert_eq!(embedded.view(), scene.view, "{}: {REGENERATE}", scene.name);
    }
}

#[test]
fn gltf_crate_loads_every_scene_with_expected_counts() {
    for scene in generate_all() {
        let gltf = gltf::Gltf::from_slice(&scene.glb)
            .unwrap_or_else(|e| panic!("{}: not valid glTF: {e}", scene.name));
        let counts = (
            gltf.meshes().count(),
            gltf.nodes().count(),
            gltf.materials().count(),
        );
        assert_eq!(counts, expected_counts(scene.name), "{}", scene.name);
        assert_eq!(gltf.cameras().count(), 1, "{}", scene.name);
        assert_eq!(
            gltf.document.as_json().asset.generator.as_deref(),
            Some("penumbra assets generator")
        );
        // A loader must handle both ways glTF places a node.
        let decomposed =
            |node: &gltf::Node| matches!(node.transform(), gltf::scene::Transform::Decomposed { .. });
        let mesh_nodes: Vec<_> = gltf.nodes().filter(|n| n.mesh().is_some()).collect();
        assert!(mesh_nodes.iter().any(decomposed), "{}: no TRS node", scene.name);
        assert!(
            mesh_nodes.iter().any(|n| !decomposed(n)),
            "{}: no matrix node",
            scene.name
        );
        let triangles = scene.triangle_count();
        assert!((100..20_000).contains(&triangles), "{}: {triangles}", scene.name);
    }
}

#[test]
fn objects_rest_on_the_ground() {
    for scene in generate_all() {
        for (node, lo, _) in node_bounds(&scene) {
            // The lattice and the screen float on purpose; everything else touches y = 0.
            if node == "lattice" || node == "screen" {
                assert!(lo.y > 0.5, "{}: {node} at {}", scene.name, lo.y);
            } else {
                assert!(lo.y.abs() < 1e-5, "{}: {node} bottom at {}", scene.name, lo.y);
            }
        }
    }
}

/// Irradiance at `point` on an upward-facing surface, unoccluded, by
/// midpoint integration over the light.
fn irradiance(light: &penumbra::scene::view::QuadLight, point: Vec3) -> f32 {
    let n = 64;
    let area = light.area_normal().length();
    let light_normal = light.area_normal() / area;
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            let s = (i as f32 + 0.5) / n as f32;
            let t = (j as f32 + 0.5) / n as f32;
            let to_light = light.corner + s * light.edge_u + t * light.edge_v - point;
            let d2 = to_light.length_squared();
            let dir = to_light / d2.sqrt();
            sum += dir.y.max(0.0) * (-light_normal.dot(dir)).max(0.0) / d2;
        }
    }
    light.intensity * light.color.y * sum * area / (n * n) as f32
}

#[test]
fn views_are_valid_and_frame_the_scene() {
    for scene in generate_all() {
        let view = scene.view;
        view.validate().unwrap_or_else(|e| panic!("{}: {e}", scene.name));
        assert!(
            view.light.area_normal().y < 0.0,
            "{}: light does not face down",
            scene.name
        );
        let bounds = node_bounds(&scene);
        let lo = bounds.iter().fold(Vec3::INFINITY, |acc, b| acc.min(b.1));
        let hi = bounds.iter().fold(Vec3::NEG_INFINITY, |acc, b| acc.max(b.2));
        let target = view.camera.target;
        assert!(
            target.cmpge(lo).all() && target.cmple(hi).all(),
            "{}: camera target {target} outside the scene bounds {lo}..{hi}",
            scene.name
        );
        assert!(
            view.light.center().y > hi.y,
            "{}: light inside the scene",
            scene.name
        );
        assert!(
            view.camera.eye.y > hi.y.min(2.0),
            "{}: camera not elevated",
            scene.name
        );
        let e = irradiance(&view.light, Vec3::ZERO);
        assert!((0.9..1.1).contains(&e), "{}: ground irradiance {e}", scene.name);
    }
}
