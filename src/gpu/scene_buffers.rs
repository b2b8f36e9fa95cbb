//! The scene on the GPU: BVH nodes, triangles, shading data and materials
//! (moving objects: `motion.rs`).

use std::borrow::Cow;

use glam::Vec3;

use super::{GpuContext, storage_buffer};
use crate::bvh::Bvh;
use crate::contract::bvh::{MAX_LEAF_TRIANGLES, STACK_SIZE};
use crate::contract::layout::{BvhNode, BvhTriangle};
use crate::pass_inputs::ShadingData;
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
    /// `array<u32>`: the alpha words ([`crate::bvh::AlphaMasks`]) the shadow kernels read.
    pub alpha: wgpu::Buffer,
    /// Triangles whose alpha is tested ([`crate::bvh::AlphaMasks::triangles`]).
    pub alpha_triangles: usize,
    /// Length of the scene's bounding-box diagonal (for relative offsets).
    pub diagonal: f32,
    /// The world point the BVH buffers are relative to: the centre of a scene that lies
    /// farther from the origin than its diagonal ([`crate::scene::Bounds::far_centre`]),
    /// else zero (then the buffers hold the world coordinates as they are). Far out, f32
    /// rounds hit points and ray origins by centimetres (1e5 m) to decimetres (1e6 m);
    /// relative to the scene's centre the kernels keep a scene built at the origin's
    /// precision. The renderer and the embedded pass move the camera, the light and the
    /// host's surface points by it; G-buffer texels read back are relative to it.
    pub origin: Vec3,
    /// The CPU copy that moving objects need ([`GpuScene::with_motion`]).
    pub(super) motion: Option<Box<super::motion::Motion>>,
    /// The driver's acceleration structures over `triangles`, for the ray-query tracer:
    /// built when the device has [`wgpu::Features::EXPERIMENTAL_RAY_QUERY`]
    /// ([`super::GpuOptions::ray_query`]), else `None`; rebuilt when objects move.
    pub ray_query: Option<super::RayQueryScene>,
}

/// Checks what the unchecked kernels index with: every child pair and every
/// leaf range lies inside the arrays, no leaf holds more than [`MAX_LEAF_TRIANGLES`], and
/// the tree fits the traversal stack.
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
        if n.is_leaf() && n.count > MAX_LEAF_TRIANGLES {
            return Err(Error::Bvh(format!(
                "leaf {i} holds {} triangles, more than the GPU kernels' {MAX_LEAF_TRIANGLES}",
                n.count
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

/// `items` with `shift` moving each by `-origin` (the same slice when it is zero).
fn relative<T: Clone>(items: &[T], origin: Vec3, shift: impl Fn(&T, Vec3) -> T) -> Cow<'_, [T]> {
    if origin == Vec3::ZERO {
        return Cow::Borrowed(items);
    }
    Cow::Owned(items.iter().map(|x| shift(x, origin)).collect())
}

/// Nodes the GPU buffer holds at least. The vector kernels load a child pair even for a
/// vector with nothing to visit (so that their subgroup operations stay in control flow
/// uniform across the workgroup), nodes 0 and 1, which a one-leaf BVH does not have.
pub(super) const MIN_GPU_NODES: usize = 2;

/// `nodes` relative to `origin`. Rounding is monotonic, so a box still holds its
/// triangles' moved corners.
pub(super) fn nodes_from(nodes: &[BvhNode], origin: Vec3) -> Cow<'_, [BvhNode]> {
    relative(nodes, origin, |n, o| BvhNode {
        bmin: n.bmin - o,
        bmax: n.bmax - o,
        ..*n
    })
}

/// `nodes` with unused nodes appended up to [`MIN_GPU_NODES`].
fn padded(mut nodes: Cow<'_, [BvhNode]>) -> Cow<'_, [BvhNode]> {
    if nodes.len() < MIN_GPU_NODES {
        nodes.to_mut().resize(MIN_GPU_NODES, BvhNode::default());
    }
    nodes
}

/// `triangles` relative to `origin`.
pub(super) fn triangles_from(triangles: &[BvhTriangle], origin: Vec3) -> Cow<'_, [BvhTriangle]> {
    relative(triangles, origin, |t, o| BvhTriangle {
        v0: t.v0 - o,
        v1: t.v1 - o,
        v2: t.v2 - o,
        ..*t
    })
}

impl GpuScene {
    /// Uploads a scene and its BVH (checked with [`validate_for_gpu`]), relative to the
    /// scene's [`GpuScene::origin`].
    pub fn new(ctx: &GpuContext, scene: &Scene, bvh: &Bvh) -> Result<GpuScene> {
        GpuScene::with_origin(ctx, scene, bvh, scene.bounds().far_centre())
    }

    /// [`GpuScene::new`] relative to a given `origin` (`Vec3::ZERO`: the world
    /// coordinates as they are, which tests use to trace a far scene unmoved).
    pub fn with_origin(ctx: &GpuContext, scene: &Scene, bvh: &Bvh, origin: Vec3) -> Result<GpuScene> {
        validate_for_gpu(bvh)?;
        let usage = wgpu::BufferUsages::COPY_DST;
        let shading = ShadingData::new(scene, bvh)?;
        let ray_query = ctx
            .device
            .features()
            .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY);
        let triangle_usage = if ray_query {
            usage | wgpu::BufferUsages::BLAS_INPUT
        } else {
            usage
        };
        let triangles = storage_buffer(
            ctx,
            "BVH triangles",
            &triangles_from(&bvh.triangles, origin),
            triangle_usage,
        )?;
        let ray_query = if ray_query {
            let count = u32::try_from(bvh.triangles.len())
                .map_err(|_| Error::Bvh("more than 2^32 triangles".into()))?;
            Some(super::RayQueryScene::new(
                ctx,
                &triangles,
                count,
                bvh.alpha.triangles == 0,
            )?)
        } else {
            None
        };
        Ok(GpuScene {
            nodes: storage_buffer(ctx, "BVH nodes", &padded(nodes_from(&bvh.nodes, origin)), usage)?,
            triangles,
            shading: storage_buffer(ctx, "shading triangles", &shading.triangles, usage)?,
            materials: storage_buffer(ctx, "materials", &shading.materials, usage)?,
            textures: storage_buffer(ctx, "textures", &shading.textures, usage)?,
            texels: storage_buffer(ctx, "texels", &shading.texels, usage)?,
            alpha: storage_buffer(ctx, "alpha", &bvh.alpha.words, usage)?,
            alpha_triangles: bvh.alpha.triangles,
            diagonal: scene.bounds().diagonal(),
            origin,
            motion: None,
            ray_query,
        })
    }
}
