//! Ray-traced soft shadows from quad lights in Bevy 0.20, by penumbra's embedded shadow pass
//! (multi-frusta tracing, 16 rays per pixel, the 4×4 discontinuity filter).
//!
//! Add [`PenumbraPlugin`] and put [`PenumbraShadows`] on a 3-D camera: Bevy's `RectLight`s
//! then cast penumbra's shadows. Each frame the plugin
//!
//! 1. keeps a penumbra scene of the world's meshes (`Mesh3d` + `GlobalTransform`, except
//!    those marked [`NotShadowCaster`](bevy::light::NotShadowCaster)): rebuilt when meshes are added, removed or edited,
//!    refitted ([`GpuScene::set_transforms`]) when they only move ([`casters`]);
//! 2. after Bevy's prepass, traces each light's visibility from the camera's depth and
//!    normal prepass textures ([`ShadowPass::record`] into Bevy's command encoder);
//! 3. after the main pass, adds each light's diffuse light times that visibility to the
//!    camera's HDR target ([`composite`]), in place of Bevy's own, unshadowed, rect-light
//!    shading (the plugin removes the lights from Bevy's light list after extraction).
//!
//! What is supported: forward rendering with `Hdr` cameras, `Msaa::Off` (the prepass
//! textures must be single-sampled), perspective and orthographic projections, any number
//! of cameras and lights. What is not: MSAA, deferred rendering's material data (the added
//! light uses [`PenumbraShadows::albedo`], not the mesh's material), the rect lights'
//! specular highlights (Bevy's shading of them is replaced by a diffuse term), rect lights
//! seen by cameras without [`PenumbraShadows`] (they see none), skinned or morphed meshes
//! (their rest pose is traced).

pub mod casters;
pub mod composite;
pub mod render;

use bevy::camera::Hdr;
use bevy::core_pipeline::prepass::{DepthPrepass, NormalPrepass};
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy::render::renderer::RenderDevice;

pub use penumbra::gpu::{GpuScene, LeafMode, ShadowPass, ShadowSettings, VectorVariant};

/// Adds penumbra's soft shadows to cameras with [`PenumbraShadows`] for every visible
/// `RectLight`.
pub struct PenumbraPlugin;

/// A camera that gets penumbra's soft shadows; its settings. Requires the depth and normal
/// prepasses and an HDR target (added with it) and no MSAA: `Camera3d` brings 4× MSAA
/// with it, so spawn the camera with `Msaa::Off` (a multisampled camera gets no shadows
/// and an error in the log).
#[derive(Component, Clone, Copy, Debug, PartialEq)]
#[require(DepthPrepass, NormalPrepass, Hdr)]
pub struct PenumbraShadows {
    /// The discontinuity filter's `(depth_tolerance, normal_tolerance)`, or `None` to skip
    /// it. The filter turns the 16 rays per pixel into an image close to 256 rays; without
    /// it penumbrae are noisy (16 levels). Looser tolerances (larger depth, smaller normal)
    /// blur across more geometric edges.
    pub filter: Option<(f32, f32)>,
    /// The 16-wide vector's implementation, or `None` for the device's best (subgroups
    /// where they are a multiple of 16 wide, else workgroup memory).
    pub variant: Option<VectorVariant>,
    /// Resume dispatches for tiles that ran out of loop iterations (see
    /// [`ShadowSettings::resume_rounds`]); dense scenes on lavapipe need more.
    pub resume_rounds: u32,
    /// Diffuse albedo the added light is reflected with (linear, 0..1): Bevy's forward
    /// renderer keeps no material colour in screen space, so one albedo serves all.
    pub albedo: f32,
}

impl Default for PenumbraShadows {
    fn default() -> Self {
        let pass = ShadowSettings::default();
        PenumbraShadows {
            filter: pass.filter,
            variant: None,
            resume_rounds: pass.resume_rounds,
            albedo: 0.8,
        }
    }
}

impl PenumbraShadows {
    /// The embedded pass's settings for this camera.
    pub fn pass_settings(&self) -> ShadowSettings {
        ShadowSettings {
            filter: self.filter,
            variant: self.variant,
            resume_rounds: self.resume_rounds,
            ..ShadowSettings::default()
        }
    }
}

impl Plugin for PenumbraPlugin {
    fn build(&self, app: &mut App) {
        casters::build(app);
    }

    /// Checks the device (Bevy's convention: the render device exists from `finish` on)
    /// and adds the render-world systems; on a device that lacks what the pass needs, logs
    /// what is missing and adds nothing, so the app renders without these shadows.
    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        let device = render_app.world().resource::<RenderDevice>();
        if let Err(e) = ShadowPass::check_device(device.wgpu_device(), &ShadowSettings::default()) {
            error!("PenumbraPlugin not loaded: {e}");
            return;
        }
        render::build(render_app);
    }
}
