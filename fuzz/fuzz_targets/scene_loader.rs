//! Bytes in, `Result` out: the glTF/GLB loader must never panic, whatever the
//! file. The same bytes are loaded as a `.glb` and as a `.gltf` path (the
//! loader decides by the GLB magic; the path only names the file and the
//! folder external URIs resolve in: a folder that does not exist, so relative
//! URIs fail to read and nothing depends on the files around).

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use penumbra::scene::Scene;

fuzz_target!(|data: &[u8]| {
    for name in ["/nonexistent-fuzz-dir/fuzz.glb", "/nonexistent-fuzz-dir/fuzz.gltf"] {
        if let Ok(scene) = Scene::from_bytes(data, Path::new(name)) {
            // What the loader promises: only finite, non-degenerate triangles,
            // indices that name existing materials and instances.
            for t in &scene.triangles {
                assert!(t.positions.iter().all(|p| p.is_finite()), "{t:?}");
                assert!(t.normals.iter().all(|n| n.is_finite()), "{t:?}");
                assert!(t.uvs.iter().all(|uv| uv.is_finite()), "{t:?}");
                assert!((t.material as usize) < scene.materials.len(), "{t:?}");
                assert!((t.instance as usize) < scene.instances.len(), "{t:?}");
            }
            assert!(!scene.triangles.is_empty());
            if let Some(camera) = scene.camera {
                assert!(camera.validate().is_ok(), "{camera:?}");
            }
        }
    }
});
