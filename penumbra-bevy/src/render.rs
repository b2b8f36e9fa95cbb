//! The render world: the scene on the GPU, per-view shadow targets, the shadow pass after
//! Bevy's prepass and the composite after the main pass.

use std::sync::Arc;

use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::core_pipeline::{Core3d, Core3dSystems};
use bevy::pbr::{ExtractedRectLight, extract_lights};
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::sync_world::RenderEntity;
use bevy::render::view::{ExtractedView, ViewTarget};
use bevy::render::{Extract, ExtractSchedule, Render, RenderStartup, RenderSystems};
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::{
    GpuContext, GpuScene, MotionSettings, NormalEncoding, ShadowInputs, ShadowPass, ShadowSettings,
    ShadowTargets, SurfaceInput,
};
use penumbra::scene::Scene;

use crate::PenumbraShadows;
use crate::casters::{Casters, to_penumbra};
use crate::composite::Composite;

/// The casters and lights as extracted this frame.
#[derive(Resource, Default)]
pub struct ExtractedShadowWorld {
    /// [`Casters::version`] of `scene`.
    pub version: u64,
    /// The casters' scene.
    pub scene: Option<Arc<Scene>>,
    /// Moves not yet applied to the GPU scene.
    pub moves: Vec<(u32, glam::Mat4)>,
    /// Every visible `RectLight`, world space, in entity order.
    pub lights: Vec<penumbra::scene::view::QuadLight>,
}

/// penumbra on Bevy's device: the scene, the passes, the composite pipeline.
#[derive(Resource)]
pub struct PenumbraGpu {
    /// Bevy's device and queue, wrapped.
    pub ctx: GpuContext,
    /// The casters on the GPU, with the version it was made from.
    pub scene: Option<(u64, GpuScene)>,
    /// The version whose scene failed to build (reported once, not retried).
    failed_version: Option<u64>,
    /// One pass per distinct camera setting.
    passes: Vec<(ShadowSettings, ShadowPass)>,
    composite: Composite,
}

impl PenumbraGpu {
    /// The pass built for `settings`, if a camera asked for it.
    pub fn pass(&self, settings: &ShadowSettings) -> Option<&ShadowPass> {
        self.passes.iter().find(|(s, _)| s == settings).map(|(_, p)| p)
    }
}

/// A view's shadow targets, one per light (the order of [`ExtractedShadowWorld::lights`]).
#[derive(Component)]
pub struct ViewShadowTargets(pub Vec<ShadowTargets>);

pub(crate) fn build(render_app: &mut SubApp) {
    render_app
        .init_resource::<ExtractedShadowWorld>()
        .add_systems(RenderStartup, init_gpu)
        .add_systems(
            ExtractSchedule,
            (extract, take_over_rect_lights.after(extract_lights)),
        )
        .add_systems(Render, prepare.in_set(RenderSystems::PrepareResources))
        .add_systems(
            Core3d,
            (
                trace
                    .after(Core3dSystems::Prepass)
                    .before(Core3dSystems::MainPass),
                composite
                    .after(Core3dSystems::MainPass)
                    .before(Core3dSystems::EarlyPostProcess),
            ),
        );
}

fn init_gpu(mut commands: Commands, device: Res<RenderDevice>, queue: Res<RenderQueue>) {
    let queue: &wgpu::Queue = &queue;
    let ctx = GpuContext::from_device(device.wgpu_device(), queue);
    let composite = Composite::new(&ctx.device);
    commands.insert_resource(PenumbraGpu {
        ctx,
        scene: None,
        failed_version: None,
        passes: Vec::new(),
        composite,
    });
}

/// A rect light as penumbra's quad light: in its entity's XY plane, centred, facing −Z;
/// radiance in nits from Bevy's lumens as Bevy converts them (over area × π).
fn world_light(light: &RectLight, transform: &GlobalTransform) -> penumbra::scene::view::QuadLight {
    let m = transform.to_matrix();
    let corner = m.transform_point3(Vec3::new(-0.5 * light.width, -0.5 * light.height, 0.0));
    let edge_u = m.transform_vector3(Vec3::X * light.width);
    let edge_v = m.transform_vector3(Vec3::Y * light.height);
    let area = edge_u.length() * edge_v.length();
    let v = |p: Vec3| glam::Vec3::from_array(p.to_array());
    // penumbra's light faces cross(edge_u, edge_v) = +Z here; swapping the edges faces −Z.
    let linear = light.color.to_linear();
    penumbra::scene::view::QuadLight {
        corner: v(corner),
        edge_u: v(edge_v),
        edge_v: v(edge_u),
        color: glam::Vec3::new(linear.red, linear.green, linear.blue),
        intensity: light.intensity / (area * std::f32::consts::PI),
    }
}

fn extract(
    mut commands: Commands,
    casters: Extract<Res<Casters>>,
    lights: Extract<Query<(Entity, &RectLight, &GlobalTransform, &ViewVisibility)>>,
    cameras: Extract<Query<(RenderEntity, &PenumbraShadows, &Camera)>>,
    mut world: ResMut<ExtractedShadowWorld>,
) {
    if world.version != casters.version {
        world.version = casters.version;
        world.scene = casters.scene.clone();
        world.moves.clear();
    } else {
        world.moves.extend_from_slice(&casters.moves);
    }
    let mut found: Vec<_> = lights.iter().collect();
    found.sort_by_key(|(e, ..)| *e);
    world.lights = found
        .into_iter()
        .filter(|(_, l, _, visible)| visible.get() && l.width > 0.0 && l.height > 0.0 && l.intensity > 0.0)
        .map(|(_, l, t, _)| world_light(l, t))
        .collect();
    for (entity, settings, camera) in &cameras {
        let mut e = commands.entity(entity);
        if camera.is_active {
            e.insert(*settings);
        } else {
            e.remove::<PenumbraShadows>();
        }
    }
}

/// Removes the rect lights from Bevy's light list (extracted just before): penumbra's
/// composite lights them instead, shadowed. Bevy extracts a light again only when it
/// changes, so this runs every frame.
fn take_over_rect_lights(mut commands: Commands, lights: Extract<Query<RenderEntity, With<RectLight>>>) {
    for entity in &lights {
        if let Ok(mut e) = commands.get_entity(entity) {
            e.remove::<ExtractedRectLight>();
        }
    }
}

fn prepare(
    mut commands: Commands,
    mut gpu: ResMut<PenumbraGpu>,
    mut world: ResMut<ExtractedShadowWorld>,
    views: Query<(
        Entity,
        &ExtractedCamera,
        &PenumbraShadows,
        Option<&ViewShadowTargets>,
    )>,
) {
    let gpu = &mut *gpu;
    let version = world.version;
    match (&world.scene, &mut gpu.scene) {
        (None, _) => gpu.scene = None,
        (Some(_), _) if gpu.failed_version == Some(version) => {}
        (Some(scene), current) if current.as_ref().is_none_or(|(v, _)| *v != version) => {
            let built = Bvh::build(scene, &BvhSettings::default())
                .and_then(|bvh| GpuScene::with_motion(&gpu.ctx, scene, &bvh, MotionSettings::default()));
            match built {
                Ok(s) => *current = Some((version, s)),
                Err(e) => {
                    error!("penumbra: the shadow casters' scene could not be built: {e}");
                    *current = None;
                    gpu.failed_version = Some(version);
                }
            }
        }
        (Some(_), Some((_, scene))) if !world.moves.is_empty() => {
            if let Err(e) = scene.set_transforms(&gpu.ctx.queue, &world.moves) {
                error!("penumbra: moving shadow casters failed: {e}");
            }
        }
        _ => {}
    }
    world.moves.clear();

    for (entity, camera, settings, targets) in &views {
        let Some(size) = camera.physical_target_size else {
            continue;
        };
        let pass_settings = settings.pass_settings();
        if gpu.pass(&pass_settings).is_none() {
            match ShadowPass::new(&gpu.ctx, pass_settings) {
                Ok(pass) => gpu.passes.push((pass_settings, pass)),
                Err(e) => {
                    error!("penumbra: the shadow pass could not be built: {e}");
                    continue;
                }
            }
        }
        let fits = targets.is_some_and(|t| {
            t.0.len() == world.lights.len() && t.0.iter().all(|t| (t.width(), t.height()) == (size.x, size.y))
        });
        if !fits {
            let made: Result<Vec<_>, _> = world
                .lights
                .iter()
                .map(|_| ShadowTargets::new(&gpu.ctx, size.x, size.y))
                .collect();
            match made {
                Ok(t) => {
                    commands.entity(entity).insert(ViewShadowTargets(t));
                }
                Err(e) => error!("penumbra: shadow targets of {}×{}: {e}", size.x, size.y),
            }
        }
    }
}

/// The view's camera matrices in penumbra's glam: world-to-view and view-to-clip.
fn camera_matrices(view: &ExtractedView) -> (glam::Mat4, glam::Mat4) {
    (
        to_penumbra(view.world_from_view.to_matrix().inverse()),
        to_penumbra(view.clip_from_view),
    )
}

/// The view's depth and normal prepass textures, when it has both.
fn prepass_textures(prepass: &ViewPrepassTextures) -> Option<(&wgpu::Texture, &wgpu::Texture)> {
    Some((
        &prepass.depth.as_ref()?.texture.texture,
        &prepass.normal.as_ref()?.texture.texture,
    ))
}

fn trace(
    view: ViewQuery<(
        &ViewPrepassTextures,
        &ExtractedView,
        &PenumbraShadows,
        &ViewShadowTargets,
    )>,
    gpu: Res<PenumbraGpu>,
    world: Res<ExtractedShadowWorld>,
    mut ctx: RenderContext,
) {
    let (prepass, extracted, settings, targets) = view.into_inner();
    let (Some((_, scene)), Some(pass)) = (&gpu.scene, gpu.pass(&settings.pass_settings())) else {
        return;
    };
    let Some((depth, normal)) = prepass_textures(prepass) else {
        return;
    };
    let (view_matrix, projection) = camera_matrices(extracted);
    for (light, targets) in world.lights.iter().zip(&targets.0) {
        let inputs = ShadowInputs {
            surface: SurfaceInput::Depth {
                texture: depth,
                view: view_matrix,
                projection,
                // Bevy's projections are reversed-Z: the depth buffer is cleared to 0.
                background_depth: 0.0,
            },
            normal,
            geometric_normal: None,
            normal_encoding: NormalEncoding::Biased,
            light,
        };
        if let Err(e) = pass.record(ctx.command_encoder(), scene, &inputs, targets) {
            error!("penumbra: the shadow pass was not recorded: {e}");
            return;
        }
    }
}

fn composite(
    view: ViewQuery<(
        &ViewTarget,
        &ViewPrepassTextures,
        &ExtractedView,
        &ExtractedCamera,
        &PenumbraShadows,
        &ViewShadowTargets,
    )>,
    gpu: Res<PenumbraGpu>,
    world: Res<ExtractedShadowWorld>,
    mut ctx: RenderContext,
) {
    let (target, prepass, extracted, camera, settings, targets) = view.into_inner();
    let Some((depth, normal)) = prepass_textures(prepass) else {
        return;
    };
    if depth.sample_count() != 1 {
        error_once!("penumbra: a camera with PenumbraShadows renders with MSAA; put Msaa::Off on it");
        return;
    }
    if target.main_texture_format() != crate::composite::HDR_FORMAT {
        warn_once!(
            "penumbra: a camera with PenumbraShadows renders without Hdr; its quad lights are not added"
        );
        return;
    }
    let traced = gpu.scene.is_some();
    let (view_matrix, projection) = camera_matrices(extracted);
    let device = gpu.ctx.device.clone();
    for (light, targets) in world.lights.iter().zip(&targets.0) {
        gpu.composite.record(
            &device,
            ctx.command_encoder(),
            target.main_texture_view(),
            &crate::composite::CompositeInputs {
                depth,
                normal,
                visibility: traced.then_some(&targets.filtered),
                world_from_clip: (projection * view_matrix).inverse(),
                light,
                exposure: camera.exposure,
                albedo: settings.albedo,
            },
        );
    }
}
