//! The SCENE argument: a glTF/GLB path, or the name of a built-in scene.

use std::path::Path;

use penumbra::scene::view::{QuadLight, View, ViewFile};
use penumbra::{Result, assets, scene::Scene};

/// Loads the scene the argument names: none → the built-in default scene; a
/// built-in scene's name (when no file of that name exists) → that scene;
/// otherwise a file path.
pub fn load_scene(arg: Option<&Path>) -> Result<Scene> {
    let builtin = match arg {
        None => Some(assets::default_scene()),
        Some(p) if !p.exists() => p.to_str().and_then(assets::embedded_scene),
        Some(_) => None,
    };
    match (builtin, arg) {
        (Some(s), _) => Scene::from_bytes(s.glb, Path::new(s.file_name)),
        (None, Some(p)) => Scene::load(p),
        (None, None) => unreachable!("no argument always selects the default scene"),
    }
}

/// The view of the built-in scene the argument selects, if it selects one.
pub fn builtin_view(arg: Option<&Path>) -> Option<penumbra::scene::view::View> {
    match arg {
        None => Some(assets::default_scene().view()),
        Some(p) if !p.exists() => p.to_str().and_then(assets::embedded_scene).map(|s| s.view()),
        Some(_) => None,
    }
}

/// Names of the built-in scenes, for help text.
pub fn builtin_names() -> String {
    assets::EMBEDDED_SCENES
        .iter()
        .map(|s| s.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The scene and view a one-light command works on ([`load_scene_and_views`]): a view file
/// with several lights is an error; of a file's emissive quads, the most powerful lights it.
pub fn load_scene_and_view(scene_arg: Option<&Path>, view_arg: Option<&Path>) -> Result<(Scene, View)> {
    let (scene, file) = load(scene_arg, view_arg, Lights::One)?;
    match file.views()[..] {
        [view] => Ok((scene, view)),
        ref views => Err(penumbra::Error::view(
            view_arg.unwrap_or(Path::new("view")),
            format!(
                "has {} lights; this command traces one (penumbra render takes several)",
                views.len()
            ),
        )),
    }
}

/// The scene and view(s) a command works on: the scene argument (see [`load_scene`]), the
/// view file if given, else the built-in scene's view, else a camera from the scene (its
/// own, or one made from its bounds) with every emissive quad of the file as a light, or
/// one light placed above the bounds when it has none; with the view's ground plane
/// added, both moved to the origin when the scene lies far from it ([`Scene::recentre`];
/// a note says so), and load warnings printed.
pub fn load_scene_and_views(scene_arg: Option<&Path>, view_arg: Option<&Path>) -> Result<(Scene, ViewFile)> {
    load(scene_arg, view_arg, Lights::All)
}

/// Which of a file's emissive quads light it when no view file is given.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Lights {
    /// The most powerful.
    One,
    /// All of them.
    All,
}

fn load(scene_arg: Option<&Path>, view_arg: Option<&Path>, lights: Lights) -> Result<(Scene, ViewFile)> {
    let mut scene = load_scene(scene_arg)?;
    let file = match (view_arg, builtin_view(scene_arg)) {
        (Some(path), _) => ViewFile::load(path)?,
        (None, Some(view)) => ViewFile::from(view),
        (None, None) => {
            let mut view = View::default_for(&scene.bounds(), scene.camera);
            let emitters = file_lights(&scene);
            if let Some(light) = brightest(&emitters.lights) {
                view.light = light;
            }
            // The scene's bounds can be too large for a light above them.
            view.validate().map_err(|m| {
                penumbra::Error::scene(
                    &scene.source,
                    format!("the default view for this scene is unusable ({m}); give one with --view"),
                )
            })?;
            let source = scene.source.display();
            let camera = if scene.camera.is_some() {
                "the file's camera"
            } else {
                "a camera looking at the bounds"
            };
            let describe = |l: &QuadLight| {
                let centre = fmt_point(l.corner + 0.5 * (l.edge_u + l.edge_v));
                let (u, v) = (l.edge_u.length(), l.edge_v.length());
                (centre, u, v)
            };
            let mut file = ViewFile::from(view);
            match (emitters.lights.len(), lights) {
                (0, _) => {
                    let (centre, u, v) = describe(&view.light);
                    eprintln!(
                        "note: {source}: no view file, so a {u:.3} × {v:.3} quad light facing down is \
                         placed at {centre} (a quarter of the bounds' diagonal above them), with \
                         {camera}; give your own with --view"
                    );
                }
                (1, _) | (_, Lights::One) => {
                    let l = &view.light;
                    let (centre, u, v) = describe(l);
                    let n = emitters.lights.len();
                    eprintln!(
                        "note: {source}: no view file: lit by the file's emissive quad at {centre} \
                         ({u:.3} × {v:.3}, radiance {}){}, with {camera}",
                        fmt_point(l.color * l.intensity),
                        if n == 1 {
                            String::new()
                        } else {
                            format!(", the most powerful of the {n} the file has (this command traces one)")
                        }
                    );
                }
                (n, Lights::All) => {
                    eprintln!(
                        "note: {source}: no view file: lit by the file's {n} emissive quads, with {camera}:"
                    );
                    for l in &emitters.lights {
                        let (centre, u, v) = describe(l);
                        eprintln!(
                            "note:   {u:.3} × {v:.3} at {centre}, radiance {}",
                            fmt_point(l.color * l.intensity)
                        );
                    }
                    file.lights = emitters.lights.clone();
                }
            }
            for why in &emitters.unusable {
                eprintln!("warning: {source}: emissive geometry of {why}");
            }
            file
        }
    };
    let mut file = file;
    if let Some(y) = file.ground_y {
        scene.add_ground_plane(y);
    }
    let shift = scene.recentre();
    if shift != glam::Vec3::ZERO {
        file = file.translated(-shift);
        eprintln!(
            "note: {}: the scene lies {:.0} from the origin; it is traced moved by {:?} so that \
             f32 keeps its precision (images are the same as seen from the view)",
            scene.source.display(),
            shift.length(),
            -shift
        );
    }
    for w in scene.warnings.messages() {
        eprintln!("warning: {}: {w}", scene.source.display());
    }
    Ok((scene, file))
}

/// The quad lights of the file's emissive parallelograms, each a ray offset in front of
/// its triangles ([`penumbra::scene::emitters::find`]).
pub fn file_lights(scene: &Scene) -> penumbra::scene::emitters::Emitters {
    let offset = scene.bounds().diagonal() * penumbra::pass_inputs::RAY_OFFSET_FRACTION;
    penumbra::scene::emitters::find(scene, offset)
}

/// The light that emits the most power (radiance × area, summed over colour).
fn brightest(lights: &[QuadLight]) -> Option<QuadLight> {
    let power = |l: &QuadLight| (l.color * l.intensity).element_sum() * l.edge_u.cross(l.edge_v).length();
    lights
        .iter()
        .copied()
        .max_by(|a, b| power(a).total_cmp(&power(b)))
}

/// A point as `[x, y, z]` with three decimals, as view files write it.
fn fmt_point(p: glam::Vec3) -> String {
    format!("[{:.3}, {:.3}, {:.3}]", p.x, p.y, p.z)
}

/// Moves a far scene and its view to the origin ([`Scene::recentre`]); returns the offset
/// (zero, and both left as they were, for a scene near the origin).
pub fn recentre(scene: &mut Scene, view: &mut View) -> glam::Vec3 {
    let shift = scene.recentre();
    if shift != glam::Vec3::ZERO {
        *view = view.translated(-shift);
    }
    shift
}
