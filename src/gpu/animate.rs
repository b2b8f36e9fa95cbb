//! A benchmark of moving objects: one instance circles and spins through the scene for a
//! number of frames; each frame updates the GPU scene ([`GpuScene::set_transform`]) and
//! waits for the writes to land, and the costs are reported per frame.
//! `examples/animate.rs` prints them; `penumbra bench` can call [`animate_instance`].

use std::time::Instant;

use glam::{Mat4, Quat, Vec3};

use super::{GpuContext, GpuScene, MotionSettings, MotionUpdate};
use crate::bvh::Bvh;
use crate::scene::Scene;
use crate::{Error, Result};

/// One animated frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnimationFrame {
    /// What the update did and what it cost on the CPU.
    pub update: MotionUpdate,
    /// Milliseconds from submitting the staged writes until the GPU has them (an empty
    /// submission and a wait: the transfer itself).
    pub flush_ms: f64,
}

/// The frames of one animation, with what was moved.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationReport {
    /// Triangles in the scene.
    pub scene_triangles: usize,
    /// Index of the instance that moved.
    pub instance: u32,
    /// Its triangles.
    pub instance_triangles: usize,
    /// Every frame, in order.
    pub frames: Vec<AnimationFrame>,
}

impl AnimationReport {
    /// Mean and largest value of `f` over the frames that `keep`.
    fn stat(
        &self,
        keep: impl Fn(&AnimationFrame) -> bool,
        f: impl Fn(&AnimationFrame) -> f64,
    ) -> (f64, f64, usize) {
        let values: Vec<f64> = self.frames.iter().filter(|a| keep(a)).map(f).collect();
        let n = values.len();
        let mean = if n == 0 {
            0.0
        } else {
            values.iter().sum::<f64>() / n as f64
        };
        (mean, values.iter().copied().fold(0.0, f64::max), n)
    }

    /// A few lines: refit and rebuild ms (mean / max), upload and flush ms, bytes per frame.
    pub fn summary(&self) -> String {
        let refit = self.stat(|a| !a.update.rebuilt, |a| a.update.bvh_ms);
        let rebuild = self.stat(|a| a.update.rebuilt, |a| a.update.bvh_ms);
        let upload = self.stat(|_| true, |a| a.update.upload_ms);
        let flush = self.stat(|_| true, |a| a.flush_ms);
        let bytes = self.stat(|_| true, |a| a.update.bytes_uploaded as f64);
        let sah = self.stat(|_| true, |a| a.update.sah_ratio);
        format!(
            "{} frames, instance {} ({} of {} triangles) moving\n\
             refit   {:>3} frames  {:.3} ms mean, {:.3} ms max (CPU)\n\
             rebuild {:>3} frames  {:.3} ms mean, {:.3} ms max (CPU)\n\
             upload  {:.3} ms mean, {:.3} ms max (write_buffer); flush {:.3} ms mean, {:.3} ms max\n\
             bytes   {:.0} per frame mean, {:.0} max; SAH ratio {:.3} mean, {:.3} max",
            self.frames.len(),
            self.instance,
            self.instance_triangles,
            self.scene_triangles,
            refit.2,
            refit.0,
            refit.1,
            rebuild.2,
            rebuild.0,
            rebuild.1,
            upload.0,
            upload.1,
            flush.0,
            flush.1,
            bytes.0,
            bytes.1,
            sah.0,
            sah.1,
        )
    }
}

/// Moves `instance` of `scene` for `frames` frames on a horizontal circle (radius a tenth
/// of the scene's diagonal, starting and ending where it is) while it turns once about
/// its vertical axis, updating a [`GpuScene::with_motion`] copy on `ctx` each frame.
pub fn animate_instance(
    ctx: &GpuContext,
    scene: &Scene,
    bvh: &Bvh,
    instance: u32,
    frames: u32,
    settings: MotionSettings,
) -> Result<AnimationReport> {
    let start = scene
        .instances
        .get(instance as usize)
        .ok_or_else(|| {
            Error::invalid(
                "animate_instance",
                format!(
                    "instance {instance} does not exist (the scene has {})",
                    scene.instances.len()
                ),
            )
        })?
        .world_from_object;
    let mut gpu = GpuScene::with_motion(ctx, scene, bvh, settings)?;
    let radius = 0.1 * scene.bounds().diagonal();
    let pivot = start.w_axis.truncate();
    let mut report = AnimationReport {
        scene_triangles: scene.triangles.len(),
        instance,
        instance_triangles: scene.triangles.iter().filter(|t| t.instance == instance).count(),
        frames: Vec::with_capacity(frames as usize),
    };
    for k in 1..=frames {
        let angle = std::f32::consts::TAU * k as f32 / frames as f32;
        let offset = radius * Vec3::new(angle.cos() - 1.0, 0.0, angle.sin());
        // Turn about the instance's own origin, then move it along the circle.
        let m = Mat4::from_translation(pivot + offset)
            * Mat4::from_quat(Quat::from_rotation_y(angle))
            * Mat4::from_translation(-pivot)
            * start;
        let update = gpu.set_transform(&ctx.queue, instance, m)?;
        let flush = Instant::now();
        ctx.queue.submit([]);
        ctx.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the GPU failed: {e}")))?;
        report.frames.push(AnimationFrame {
            update,
            flush_ms: flush.elapsed().as_secs_f64() * 1e3,
        });
    }
    Ok(report)
}

/// The instance an animation benchmark moves by default: the one with the most triangles
/// among those smaller than half the scene (an object, not the ground or the building).
pub fn default_moving_instance(scene: &Scene) -> Option<u32> {
    let half = 0.5 * scene.bounds().diagonal();
    let mut stats = vec![(0usize, crate::scene::Bounds::EMPTY); scene.instances.len()];
    for t in &scene.triangles {
        if let Some((n, b)) = stats.get_mut(t.instance as usize) {
            *n += 1;
            t.positions.iter().for_each(|&p| b.grow(p));
        }
    }
    stats
        .iter()
        .enumerate()
        .filter(|(_, (n, b))| *n > 0 && b.diagonal() < half)
        .max_by_key(|(_, (n, _))| *n)
        .map(|(i, _)| i as u32)
}
