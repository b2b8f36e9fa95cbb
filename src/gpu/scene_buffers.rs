//! The scene on the GPU: BVH nodes, triangles, shading data and materials
//! (moving objects: `motion.rs`).

use super::{GpuContext, storage_buffer};
use crate::bvh::Bvh;
use crate::frame::ShadingData;
use crate::reference::mft::STACK_SIZE;
use crate::scene::Scene;
use crate::{Error, Result};

/// A scene's buffers on one device.
#[derive(Debug)]
pub struct GpuScene {
    /// `array<BvhNode>`.
    pub nodes: wgpu::Buffer,
    /// `array<BvhTriangle>` in leaf order.
    pub triangles: wgpu::Buffer,
    /// `array<ShadingTriangle>` in leaf order.
    pub shading: wgpu::Buffer,
    /// `array<GpuMaterial>`.
    pub materials: wgpu::Buffer,
    /// `array<GpuTexture>` (at least one element; a material's index past the end means none).
    pub textures: wgpu::Buffer,
    /// `array<vec4<f32>>`: linear RGBA texels of all textures.
    pub texels: wgpu::Buffer,
    /// Length of the scene's bounding-box diagonal (for relative offsets).
    pub diagonal: f32,
    /// The CPU copy that moving objects need ([`GpuScene::with_motion`]).
    pub(super) motion: Option<Box<super::motion::Motion>>,
}

/// Checks what the unchecked kernels index with: every child pair and every
/// leaf range lies inside the arrays, and the tree fits the traversal stack.
pub fn validate_for_gpu(bvh: &Bvh) -> Result<()> {
    let n_nodes = bvh.nodes.len() as u64;
    let n_tris = bvh.triangles.len() as u64;
    for (i, n) in bvh.nodes.iter().enumerate() {
        let ok = if n.is_leaf() {
            u64::from(n.first) + u64::from(n.count) <= n_tris
        } else {
            u64::from(n.first) + 1 < n_nodes
        };
        if !ok {
            return Err(Error::Bvh(format!(
                "node {i} points outside the node or triangle arrays"
            )));
        }
    }
    let depth = bvh.stats().max_depth;
    if depth >= STACK_SIZE {
        return Err(Error::Bvh(format!(
            "BVH depth {depth} exceeds the GPU traversal stack ({STACK_SIZE}); \
             try a larger --leaf-size"
        )));
    }
    Ok(())
}

impl GpuScene {
    /// Uploads a scene and its BVH (checked with [`validate_for_gpu`]).
    pub fn new(ctx: &GpuContext, scene: &Scene, bvh: &Bvh) -> Result<GpuScene> {
        validate_for_gpu(bvh)?;
        let usage = wgpu::BufferUsages::COPY_DST;
        let shading = ShadingData::new(scene, bvh)?;
        Ok(GpuScene {
            nodes: storage_buffer(ctx, "BVH nodes", &bvh.nodes, usage)?,
            triangles: storage_buffer(ctx, "BVH triangles", &bvh.triangles, usage)?,
            shading: storage_buffer(ctx, "shading triangles", &shading.triangles, usage)?,
            materials: storage_buffer(ctx, "materials", &shading.materials, usage)?,
            textures: storage_buffer(ctx, "textures", &shading.textures, usage)?,
            texels: storage_buffer(ctx, "texels", &shading.texels, usage)?,
            diagonal: scene.bounds().diagonal(),
            motion: None,
        })
    }
}
