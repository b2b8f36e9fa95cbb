//! Writes the generated scenes to `assets/NAME.glb` and `assets/views/NAME.json`.
//!
//! Run after changing `src/assets/`: `cargo run --release --example generate_assets`.

use std::path::Path;

use penumbra::assets::generate::generate_all;

fn main() -> std::io::Result<()> {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    std::fs::create_dir_all(assets.join("views"))?;
    for scene in generate_all() {
        let glb_path = assets.join(format!("{}.glb", scene.name));
        std::fs::write(&glb_path, &scene.glb)?;
        println!(
            "{}: {} bytes, {} triangles",
            glb_path.display(),
            scene.glb.len(),
            scene.triangle_count()
        );
        let view_path = assets.join("views").join(format!("{}.json", scene.name));
        let view_json = format!("{}\n", scene.view.to_json());
        std::fs::write(&view_path, &view_json)?;
        println!("{}: {} bytes", view_path.display(), view_json.len());
    }
    Ok(())
}
