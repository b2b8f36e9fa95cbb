//! The scenes the project ships: generated from code ([`generate`]) and
//! committed under `assets/` as `NAME.glb` plus `views/NAME.json`, then
//! embedded in the binary ([`EMBEDDED_SCENES`]) so the CLI and the tests run
//! without any files around.
//!
//! `tests/cpu/assets.rs` checks that the committed files are exactly what the
//! generator produces; after changing the generator, run
//! `cargo run --release --example generate_assets`.

use std::path::Path;

use crate::scene::view::View;

pub mod generate;
pub mod glb_writer;
pub mod shapes;

/// A scene the project ships, embedded in the binary.
#[derive(Debug)]
pub struct EmbeddedScene {
    /// Scene name, as given on the command line.
    pub name: &'static str,
    /// File name of the scene under `assets/` (used in error messages).
    pub file_name: &'static str,
    /// The binary glTF file.
    pub glb: &'static [u8],
    /// The view (camera + light) as JSON, in the format [`View::from_json`] reads.
    pub view_json: &'static str,
}

impl EmbeddedScene {
    /// The scene's parsed view.
    pub fn view(&self) -> View {
        let path = Path::new("assets/views").join(format!("{}.json", self.name));
        // Every embedded view is parsed by tests/cpu/assets.rs: failing here is a bug.
        View::from_json(self.view_json, &path).expect("embedded views are valid")
    }
}

/// Every shipped scene, the default ([`default_scene`]) first.
pub const EMBEDDED_SCENES: &[EmbeddedScene] = &[
    EmbeddedScene {
        name: "playground",
        file_name: "playground.glb",
        glb: include_bytes!("../../assets/playground.glb"),
        view_json: include_str!("../../assets/views/playground.json"),
    },
    EmbeddedScene {
        name: "lattice",
        file_name: "lattice.glb",
        glb: include_bytes!("../../assets/lattice.glb"),
        view_json: include_str!("../../assets/views/lattice.json"),
    },
    EmbeddedScene {
        name: "screen",
        file_name: "screen.glb",
        glb: include_bytes!("../../assets/screen.glb"),
        view_json: include_str!("../../assets/views/screen.json"),
    },
];

/// The scene used when none is named: `playground`.
pub fn default_scene() -> &'static EmbeddedScene {
    &EMBEDDED_SCENES[0]
}

/// The shipped scene called `name`, if there is one.
pub fn embedded_scene(name: &str) -> Option<&'static EmbeddedScene> {
    EMBEDDED_SCENES.iter().find(|scene| scene.name == name)
}
