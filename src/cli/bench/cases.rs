//! The scenes and views `penumbra bench` measures: the built-in scenes and those of
//! `../shared/scenes/` with their views; a scene with alpha-tested materials also with its
//! masks ignored (`VIEW, masks opaque`), just before it, so the table shows what they cost.

use std::path::{Path, PathBuf};

use penumbra::scene::view::{View, ViewFile};
use penumbra::scene::{AlphaMode, Scene};
use penumbra::{Result, assets};

use super::BenchArgs;

/// Views for the scenes of `../shared/scenes/` (their README's "views that give
/// interesting soft shadows"), by file name: `(file, view name, view JSON)`.
pub(super) const SHARED_VIEWS: &[(&str, &str, &str)] = &[
    (
        "sponza.gltf",
        "sunlit atrium",
        include_str!("../../../assets/views/sponza-atrium.json"),
    ),
    (
        "sponza.gltf",
        "columns",
        include_str!("../../../assets/views/sponza-columns.json"),
    ),
    (
        "cornell_box.gltf",
        "luminaire",
        include_str!("../../../assets/views/cornell-box.json"),
    ),
    (
        "stanford-bunny.gltf",
        "ground",
        include_str!("../../../assets/views/bunny.json"),
    ),
    (
        "duck.gltf",
        "ground",
        include_str!("../../../assets/views/duck.json"),
    ),
    (
        "2CylinderEngine.glb",
        "above",
        include_str!("../../../assets/views/engine.json"),
    ),
];

/// One scene and view to bench.
pub(super) struct Case {
    pub(super) name: String,
    pub(super) view_name: String,
    pub(super) scene: Scene,
    pub(super) view: View,
    /// Trace the scene with its alpha masks ignored ([`penumbra::bvh::Bvh::without_alpha`]):
    /// the case after a scene with alpha-tested materials, to show what the masks cost.
    pub(super) opaque_masks: bool,
}

pub(super) fn cases(args: &BenchArgs) -> Result<Vec<Case>> {
    let mut out = Vec::new();
    // A view file with several lights gives a case per light (`FILE, light N`).
    let forced_views: Option<Vec<(String, View)>> = match args.view.as_deref() {
        None => None,
        Some(path) => {
            let views = ViewFile::load(path)?.views();
            let several = views.len() > 1;
            Some(
                views
                    .into_iter()
                    .enumerate()
                    .map(|(i, v)| {
                        let name = if several {
                            format!("{}, light {}", path.display(), i + 1)
                        } else {
                            path.display().to_string()
                        };
                        (name, v)
                    })
                    .collect(),
            )
        }
    };
    let mut push = |name: String, scene: Scene, views: Vec<(String, View)>| {
        let views = forced_views.clone().unwrap_or(views);
        for (view_name, view) in views {
            let mut scene = scene.clone();
            if let Some(y) = view.ground_y {
                scene.add_ground_plane(y);
            }
            // As render does (scene_arg::load_scene_and_view): far scenes are traced at the origin.
            let mut view = view;
            super::super::scene_arg::recentre(&mut scene, &mut view);
            let masked = scene.materials.iter().any(|m| m.alpha_mode != AlphaMode::Opaque);
            if masked {
                out.push(Case {
                    name: name.clone(),
                    view_name: format!("{view_name}, masks opaque"),
                    scene: scene.clone(),
                    view,
                    opaque_masks: true,
                });
            }
            out.push(Case {
                name: name.clone(),
                view_name,
                scene,
                view,
                opaque_masks: false,
            });
        }
    };
    let builtin = |name: &str| assets::embedded_scene(name);
    let shared_views = |path: &Path, scene: &Scene| -> Result<Vec<(String, View)>> {
        let file = path.file_name().and_then(|f| f.to_str()).unwrap_or_default();
        let known: Vec<(String, View)> = SHARED_VIEWS
            .iter()
            .filter(|(f, _, _)| *f == file)
            .map(|(_, name, json)| Ok(((*name).to_owned(), View::from_json(json, Path::new(name))?)))
            .collect::<Result<_>>()?;
        Ok(if known.is_empty() {
            vec![(
                "default".to_owned(),
                View::default_for(&scene.bounds(), scene.camera),
            )]
        } else {
            known
        })
    };
    if args.scenes.is_empty() {
        for s in assets::EMBEDDED_SCENES {
            let scene = Scene::from_bytes(s.glb, Path::new(s.file_name))?;
            push(s.name.to_owned(), scene, vec![("built-in".to_owned(), s.view())]);
        }
        let mut files: Vec<PathBuf> = std::fs::read_dir(&args.shared_scenes)
            .into_iter()
            .flatten()
            .flatten()
            .filter(|d| d.path().is_dir())
            .flat_map(|d| std::fs::read_dir(d.path()).into_iter().flatten().flatten())
            .map(|e| e.path())
            .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")))
            .collect();
        files.sort();
        if files.is_empty() {
            eprintln!(
                "note: no scenes under {}; benching the built-in scenes only",
                args.shared_scenes.display()
            );
        }
        for path in files {
            let scene = Scene::load(&path)?;
            let views = shared_views(&path, &scene)?;
            push(path.display().to_string(), scene, views);
        }
    } else {
        for arg in &args.scenes {
            match (arg.exists(), arg.to_str().and_then(builtin)) {
                (false, Some(s)) => {
                    let scene = Scene::from_bytes(s.glb, Path::new(s.file_name))?;
                    push(s.name.to_owned(), scene, vec![("built-in".to_owned(), s.view())]);
                }
                _ => {
                    let scene = Scene::load(arg)?;
                    let views = shared_views(arg, &scene)?;
                    push(arg.display().to_string(), scene, views);
                }
            }
        }
    }
    Ok(out)
}
