//! A ground, a picket fence, a sphere and a box under one quad light with penumbra's soft
//! shadows, rendered headless by Bevy to a PNG (no window: it runs on lavapipe).
//!
//! ```text
//! cargo run -p penumbra-bevy --release --ignore-rust-version --example fence -- [OUTPUT.png] [--moved]
//! ```
//!
//! `--moved` renders the box 0.9 m to the right (its shadow follows). The small sphere at
//! the back is a `NotShadowCaster`: it is lit, and casts no penumbra shadow.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::{Arc, Mutex};

use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::light::NotShadowCaster;
use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::render_resource::TextureFormat;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy::window::ExitCondition;
use penumbra_bevy::{PenumbraPlugin, PenumbraShadows};

/// The image size.
const SIZE: (u32, u32) = (480, 320);
/// Frames rendered before the one saved (pipelines and assets settle), and after it (the
/// screenshot's readback completes).
const FRAMES_BEFORE: u32 = 3;
const FRAMES_AFTER: u32 = 4;

/// Marks the box that `--moved` moves.
#[derive(Component)]
pub struct Mover;

fn main() -> ExitCode {
    // SAFETY: first thing in main, before any thread or Vulkan instance exists.
    unsafe { penumbra::gpu::set_driver_defaults_for_drawing() };
    let mut output = PathBuf::from("fence.png");
    let mut moved = false;
    for arg in std::env::args().skip(1) {
        match arg.as_str() {
            "--moved" => moved = true,
            "-h" | "--help" => {
                println!("usage: fence [OUTPUT.png] [--moved]");
                return ExitCode::SUCCESS;
            }
            a if a.starts_with('-') => {
                eprintln!("error: unknown option {a} (usage: fence [OUTPUT.png] [--moved])");
                return ExitCode::from(2);
            }
            a => output = PathBuf::from(a),
        }
    }
    match render(&output, moved) {
        Ok(()) => {
            println!("wrote {}", output.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The example's app, finished and ready for `update`: headless (no window), pipelines
/// compiled when first used, the render world updated in step with the main world.
pub fn app(moved: bool) -> App {
    let mut app = App::new();
    app.add_plugins(
        DefaultPlugins
            .set(WindowPlugin {
                primary_window: None,
                exit_condition: ExitCondition::DontExit,
                ..default()
            })
            .set(RenderPlugin {
                synchronous_pipeline_compilation: true,
                ..default()
            })
            .disable::<PipelinedRenderingPlugin>(),
    )
    .add_plugins(PenumbraPlugin)
    .insert_resource(GlobalAmbientLight {
        color: Color::WHITE,
        brightness: 60.0,
        ..default()
    })
    .add_systems(
        Startup,
        move |commands: Commands,
              meshes: ResMut<Assets<Mesh>>,
              materials: ResMut<Assets<StandardMaterial>>,
              images: ResMut<Assets<Image>>| setup(commands, meshes, materials, images, moved),
    );
    app.finish();
    app.cleanup();
    app
}

/// Renders the scene and saves the frame to `output` (whole or not at all).
fn render(output: &Path, moved: bool) -> Result<(), String> {
    let mut app = app(moved);
    let saved: Arc<Mutex<Option<Result<(), String>>>> = Arc::default();
    for frame in 0..FRAMES_BEFORE + 1 + FRAMES_AFTER {
        if frame == FRAMES_BEFORE {
            let world = app.world_mut();
            let target = world
                .query_filtered::<&RenderTarget, With<Camera3d>>()
                .single(world)
                .map_err(|e| format!("no camera: {e}"))?
                .as_image()
                .cloned()
                .ok_or("the camera does not render to an image")?;
            let (saved, output) = (saved.clone(), output.to_owned());
            world
                .spawn(Screenshot::image(target))
                .observe(move |captured: On<ScreenshotCaptured>| {
                    *saved.lock().unwrap() = Some(save_png(&captured.image, &output));
                });
        }
        let start = std::time::Instant::now();
        app.update();
        println!("frame {frame}: {:.0} ms", start.elapsed().as_secs_f64() * 1e3);
        if let Some(result) = saved.lock().unwrap().take() {
            return result;
        }
    }
    Err(format!(
        "the screenshot did not arrive within {FRAMES_AFTER} frames; nothing written to {}",
        output.display()
    ))
}

/// Writes `image` as an 8-bit PNG: to a temporary file beside `output`, then renamed.
fn save_png(image: &Image, output: &Path) -> Result<(), String> {
    let rgb = image
        .clone()
        .try_into_dynamic()
        .map_err(|e| format!("the screenshot cannot be converted: {e}"))?
        .to_rgb8();
    let tmp = output.with_extension("png.partial");
    rgb.save_with_format(&tmp, image::ImageFormat::Png)
        .and_then(|()| std::fs::rename(&tmp, output).map_err(image::ImageError::IoError))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            format!("{}: {e}", output.display())
        })
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut images: ResMut<Assets<Image>>,
    moved: bool,
) {
    let mut material = |color: Color| {
        materials.add(StandardMaterial {
            base_color: color,
            perceptual_roughness: 0.9,
            ..default()
        })
    };
    let grey = material(Color::srgb(0.55, 0.55, 0.55));
    let wood = material(Color::srgb(0.55, 0.4, 0.25));
    let red = material(Color::srgb(0.7, 0.2, 0.15));
    let blue = material(Color::srgb(0.2, 0.3, 0.7));

    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(8.0, 8.0))),
        MeshMaterial3d(grey.clone()),
    ));
    // The fence: 11 pickets and two rails, 0.5 m in front of the light.
    let picket = meshes.add(Cuboid::new(0.09, 1.0, 0.04));
    for i in 0..11 {
        commands.spawn((
            Mesh3d(picket.clone()),
            MeshMaterial3d(wood.clone()),
            Transform::from_xyz(-1.5 + 0.3 * i as f32, 0.5, 0.5),
        ));
    }
    let rail = meshes.add(Cuboid::new(3.3, 0.06, 0.03));
    for y in [0.3, 0.8] {
        commands.spawn((
            Mesh3d(rail.clone()),
            MeshMaterial3d(wood.clone()),
            Transform::from_xyz(0.0, y, 0.535),
        ));
    }
    commands.spawn((
        Mesh3d(meshes.add(Sphere::new(0.4).mesh().uv(32, 16))),
        MeshMaterial3d(red),
        Transform::from_xyz(-1.1, 0.4, -0.6),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(0.6, 0.6, 0.6))),
        MeshMaterial3d(blue.clone()),
        Transform::from_xyz(if moved { 1.9 } else { 1.0 }, 0.3, -0.7)
            .with_rotation(Quat::from_rotation_y(0.4)),
        Mover,
    ));
    // Lit, but penumbra ignores it: no shadow under it.
    commands.spawn((
        Mesh3d(meshes.add(Sphere::new(0.25).mesh().uv(24, 12))),
        MeshMaterial3d(blue),
        Transform::from_xyz(0.1, 0.6, -1.6),
        NotShadowCaster,
    ));
    // A 1.2 m × 0.5 m panel 2.6 m above the ground, facing down: Bevy's rect light, whose
    // lumens over area × π are its radiance, 60,000 nits.
    commands.spawn((
        RectLight {
            intensity: 60_000.0 * 1.2 * 0.5 * std::f32::consts::PI,
            width: 1.2,
            height: 0.5,
            ..default()
        },
        Transform::from_xyz(0.0, 2.6, 0.1).looking_to(Vec3::NEG_Y, Vec3::Z),
    ));

    let mut target = Image::new_target_texture(SIZE.0, SIZE.1, TextureFormat::Rgba8UnormSrgb, None);
    target.asset_usage = RenderAssetUsages::RENDER_WORLD;
    commands.spawn((
        Camera3d::default(),
        RenderTarget::Image(images.add(target).into()),
        Transform::from_xyz(0.0, 3.4, 4.6).looking_at(Vec3::new(0.0, 0.0, -0.3), Vec3::Y),
        // Camera3d requires 4× MSAA by default; penumbra reads single-sampled prepass textures.
        Msaa::Off,
        PenumbraShadows::default(),
    ));
}
