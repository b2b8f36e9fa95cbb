//! Moving objects: a [`GpuScene`] made with [`GpuScene::with_motion`] keeps a CPU copy of
//! its BVH and its triangles in object space, so that [`GpuScene::set_transforms`] can
//! place instances anew between frames.
//!
//! Per call: the moved instances' triangles are transformed to world space, the BVH is
//! refitted bottom-up ([`Bvh::refit`]), and only the changed node and triangle ranges are
//! written to the GPU buffers (`queue.write_buffer`; the copies happen at the host's next
//! submission). Refitting keeps the tree's shape, so boxes grow as objects move away from
//! where the tree was built; when the tree's SAH cost exceeds
//! [`MotionSettings::rebuild_ratio`] × its cost right after the last build, the BVH is
//! rebuilt from scratch instead and uploaded whole.

use std::time::Instant;

use glam::{Mat3, Mat4, Vec3, Vec4};

use super::{GpuContext, GpuScene, storage_buffer, validate_for_gpu};
use crate::bvh::{BuildQuality, Bvh, BvhSettings};
use crate::contract::layout::{BvhNode, ShadingTriangle};
use crate::pass_inputs::ShadingData;
use crate::scene::Scene;
use crate::{Error, Result};

/// When to rebuild instead of refit, and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionSettings {
    /// Rebuild when the refitted tree's SAH cost exceeds this multiple of its cost right
    /// after the last build. Lower: traces stay fast, rebuilds are frequent; higher:
    /// cheap updates, slower traces as boxes overlap. 0 rebuilds on every update,
    /// `f64::INFINITY` never. 1.3 by default.
    ///
    /// A rigid object keeps its own subtree tight wherever it goes; only the few boxes
    /// above it grow. Measured on the default scene, moving the sphere (960 of its
    /// triangles) 6.4 m across and 2.5 m up raises the cost by 5 % only, so rigid motion
    /// rarely rebuilds; objects moving through each other's space or deforming do.
    pub rebuild_ratio: f64,
    /// Settings of rebuilds (the first BVH is the caller's). `Fast` quality by default:
    /// a rebuild happens within a frame.
    pub rebuild: BvhSettings,
}

impl Default for MotionSettings {
    fn default() -> Self {
        MotionSettings {
            rebuild_ratio: 1.3,
            rebuild: BvhSettings {
                quality: BuildQuality::Fast,
                ..BvhSettings::default()
            },
        }
    }
}

/// What one [`GpuScene::set_transforms`] call did and cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MotionUpdate {
    /// Triangles moved.
    pub triangles_moved: usize,
    /// The BVH was rebuilt from scratch (else refitted).
    pub rebuilt: bool,
    /// SAH cost of the tree after the update over its cost after the last build (1 right
    /// after a rebuild).
    pub sah_ratio: f64,
    /// CPU milliseconds transforming triangles and refitting (and rebuilding, if it did).
    pub bvh_ms: f64,
    /// CPU milliseconds in `queue.write_buffer` (staging the changed ranges).
    pub upload_ms: f64,
    /// Bytes written to the GPU buffers.
    pub bytes_uploaded: u64,
    /// `write_buffer` calls made.
    pub writes: u32,
}

/// The CPU copy that moving objects need.
#[derive(Debug)]
pub(super) struct Motion {
    settings: MotionSettings,
    /// The BVH exactly as on the GPU.
    bvh: Bvh,
    /// Per scene triangle: its instance, corners and shading normals in object space.
    instance_of: Vec<u32>,
    object_corners: Vec<[Vec3; 3]>,
    object_normals: Vec<[Vec3; 3]>,
    /// Per scene triangle, current: world corners and shading data.
    world_corners: Vec<[Vec3; 3]>,
    shading: Vec<ShadingTriangle>,
    /// Per instance: its scene triangles; its leaf-order slots in the current BVH; and
    /// whether its first transform could be inverted (object space known).
    triangles_of: Vec<Vec<u32>>,
    slots_of: Vec<Vec<u32>>,
    movable: Vec<bool>,
    transforms: Vec<Mat4>,
    sah_at_build: f64,
}

impl GpuScene {
    /// [`GpuScene::new`] plus what [`GpuScene::set_transforms`] needs: a CPU copy of the
    /// BVH, of the shading data and of every triangle in its instance's object space
    /// (about 200 bytes per triangle), and a node buffer large enough for any rebuild
    /// (`2·triangles − 1` nodes).
    pub fn with_motion(
        ctx: &GpuContext,
        scene: &Scene,
        bvh: &Bvh,
        settings: MotionSettings,
    ) -> Result<GpuScene> {
        let n_tris = scene.triangles.len();
        if bvh.triangles.len() != n_tris {
            return Err(Error::invalid(
                "GpuScene::with_motion",
                format!(
                    "the BVH holds {} triangles, the scene {n_tris}",
                    bvh.triangles.len()
                ),
            ));
        }
        let mut gpu = GpuScene::new(ctx, scene, bvh)?;
        let mut nodes = bvh.nodes.clone();
        nodes.resize(
            bvh.nodes
                .len()
                .max(2 * n_tris.saturating_sub(1) + 1)
                .max(super::scene_buffers::MIN_GPU_NODES),
            BvhNode::default(),
        );
        let nodes = super::scene_buffers::nodes_from(&nodes, gpu.origin);
        gpu.nodes = storage_buffer(ctx, "BVH nodes", &nodes, wgpu::BufferUsages::COPY_DST)?;

        let inverses: Vec<Option<Mat4>> = scene
            .instances
            .iter()
            .map(|i| {
                let inv = i.world_from_object.inverse();
                (i.world_from_object.determinant() != 0.0 && inv.is_finite()).then_some(inv)
            })
            .collect();
        let mut triangles_of = vec![Vec::new(); scene.instances.len()];
        let (mut object_corners, mut object_normals) =
            (Vec::with_capacity(n_tris), Vec::with_capacity(n_tris));
        for (s, t) in scene.triangles.iter().enumerate() {
            let instance = t.instance as usize;
            let (inv, to_object) = match inverses.get(instance).copied().flatten() {
                // Normals map to world space with the inverse transpose, so back with the transpose.
                Some(inv) => (
                    inv,
                    Mat3::from_mat4(scene.instances[instance].world_from_object).transpose(),
                ),
                None => (Mat4::IDENTITY, Mat3::IDENTITY),
            };
            if let Some(list) = triangles_of.get_mut(instance) {
                list.push(s as u32);
            }
            object_corners.push(t.positions.map(|p| inv.transform_point3(p)));
            object_normals.push(t.normals.map(|n| (to_object * n).normalize_or(n)));
        }
        let shading = ShadingData::new(scene, bvh)?;
        let mut by_scene = vec![ShadingTriangle::default(); n_tris];
        for (slot, t) in bvh.triangles.iter().enumerate() {
            by_scene[t.scene_index as usize] = shading.triangles[slot];
        }
        let mut motion = Motion {
            settings,
            bvh: bvh.clone(),
            instance_of: scene.triangles.iter().map(|t| t.instance).collect(),
            object_corners,
            object_normals,
            world_corners: scene.triangles.iter().map(|t| t.positions).collect(),
            shading: by_scene,
            slots_of: Vec::new(),
            movable: inverses.iter().map(Option::is_some).collect(),
            transforms: scene.instances.iter().map(|i| i.world_from_object).collect(),
            triangles_of,
            sah_at_build: bvh.sah_cost(),
        };
        motion.index_slots();
        gpu.motion = Some(Box::new(motion));
        Ok(gpu)
    }

    /// Places each `(instance, world_from_object)` of `moves` (indices into
    /// [`Scene::instances`]) and brings the GPU buffers up to date: refit, or rebuild when
    /// the tree degraded past [`MotionSettings::rebuild_ratio`]. The writes reach the GPU
    /// with the queue's next submission, before any work submitted after this call.
    ///
    /// Errors ([`Error::InvalidInput`], nothing changed): the scene was made with
    /// [`GpuScene::new`]; an instance index out of range, or whose first transform could not
    /// be inverted; a matrix that is not finite or not affine. A rebuild that exceeds the
    /// traversal stack gives [`Error::Bvh`] (the GPU buffers then keep the refitted tree).
    pub fn set_transforms(&mut self, queue: &wgpu::Queue, moves: &[(u32, Mat4)]) -> Result<MotionUpdate> {
        let what = "GpuScene::set_transforms";
        let motion = self.motion.as_deref_mut().ok_or_else(|| {
            Error::invalid(
                what,
                "the scene was uploaded with GpuScene::new, which keeps no CPU copy; \
                 use GpuScene::with_motion to move objects",
            )
        })?;
        for &(instance, m) in moves {
            let i = instance as usize;
            if i >= motion.movable.len() {
                return Err(Error::invalid(
                    what,
                    format!(
                        "instance {instance} does not exist (the scene has {})",
                        motion.movable.len()
                    ),
                ));
            }
            if !motion.movable[i] {
                return Err(Error::invalid(
                    what,
                    format!("instance {instance}'s first transform is singular: its object space is unknown"),
                ));
            }
            if !m.is_finite() || m.row(3) != Vec4::W {
                return Err(Error::invalid(
                    what,
                    format!("the matrix for instance {instance} is not a finite affine transform"),
                ));
            }
        }
        let start = Instant::now();
        let mut slots = Vec::new();
        for &(instance, m) in moves {
            motion.place(instance, m);
            slots.extend_from_slice(&motion.slots_of[instance as usize]);
        }
        let refit = motion.bvh.refit(&motion.world_corners, &slots);
        let sah_ratio = motion.bvh.sah_cost() / motion.sah_at_build;
        let mut update = MotionUpdate {
            triangles_moved: slots.len(),
            sah_ratio,
            ..Default::default()
        };
        let (node_ranges, tri_ranges) = if sah_ratio > motion.settings.rebuild_ratio {
            let bvh = Bvh::build_from_corners(&motion.world_corners, &motion.settings.rebuild)?;
            validate_for_gpu(&bvh)?;
            motion.sah_at_build = bvh.sah_cost();
            motion.bvh = bvh;
            motion.index_slots();
            update.rebuilt = true;
            update.sah_ratio = 1.0;
            // Everything changed: one range each.
            let whole = |n: usize| std::iter::once(0..n).collect::<Vec<_>>();
            (whole(motion.bvh.nodes.len()), whole(motion.bvh.triangles.len()))
        } else {
            (refit.nodes, refit.triangles)
        };
        update.bvh_ms = start.elapsed().as_secs_f64() * 1e3;

        let start = Instant::now();
        let mut write = |buffer: &wgpu::Buffer, offset: usize, bytes: &[u8]| {
            queue.write_buffer(buffer, offset as u64, bytes);
            update.bytes_uploaded += bytes.len() as u64;
            update.writes += 1;
        };
        let bvh = &motion.bvh;
        for r in node_ranges {
            write(
                &self.nodes,
                r.start * size_of::<BvhNode>(),
                bytemuck::cast_slice(&super::scene_buffers::nodes_from(&bvh.nodes[r], self.origin)),
            );
        }
        for r in tri_ranges {
            write(
                &self.triangles,
                r.start * size_of::<crate::contract::layout::BvhTriangle>(),
                bytemuck::cast_slice(&super::scene_buffers::triangles_from(
                    &bvh.triangles[r.clone()],
                    self.origin,
                )),
            );
            let shading: Vec<ShadingTriangle> = bvh.triangles[r.clone()]
                .iter()
                .map(|t| motion.shading[t.scene_index as usize])
                .collect();
            write(
                &self.shading,
                r.start * size_of::<ShadingTriangle>(),
                bytemuck::cast_slice(&shading),
            );
        }
        update.upload_ms = start.elapsed().as_secs_f64() * 1e3;
        // The ray-query structures are built again from the new corners and waited for
        // (their time: `RayQueryScene::build_ms`).
        if let Some(rq) = &mut self.ray_query {
            rq.build(queue, &self.triangles)?;
        }
        let root = bvh.nodes[0];
        self.diagonal = (root.bmax - root.bmin).length();
        Ok(update)
    }

    /// [`GpuScene::set_transforms`] for one instance.
    pub fn set_transform(
        &mut self,
        queue: &wgpu::Queue,
        instance: u32,
        world_from_object: Mat4,
    ) -> Result<MotionUpdate> {
        self.set_transforms(queue, &[(instance, world_from_object)])
    }

    /// The BVH as it is on the GPU (`None` for a scene made with [`GpuScene::new`]).
    pub fn cpu_bvh(&self) -> Option<&Bvh> {
        self.motion.as_deref().map(|m| &m.bvh)
    }

    /// Current world-space corners of every scene triangle, indexed like
    /// [`Scene::triangles`] (`None` for a scene made with [`GpuScene::new`]).
    pub fn world_corners(&self) -> Option<&[[Vec3; 3]]> {
        self.motion.as_deref().map(|m| m.world_corners.as_slice())
    }
}

impl Motion {
    /// Sets instance `instance`'s transform: world corners and shading normals of its triangles.
    fn place(&mut self, instance: u32, m: Mat4) {
        self.transforms[instance as usize] = m;
        let normal_matrix = Mat3::from_mat4(m).inverse().transpose();
        for &s in &self.triangles_of[instance as usize] {
            let s = s as usize;
            debug_assert_eq!(self.instance_of[s], instance);
            self.world_corners[s] = self.object_corners[s].map(|p| m.transform_point3(p));
            let [n0, n1, n2] = self.object_normals[s].map(|n| (normal_matrix * n).normalize_or(n));
            let sh = &mut self.shading[s];
            (sh.n0, sh.n1, sh.n2) = (n0, n1, n2);
        }
    }

    /// Rebuilds the per-instance lists of leaf-order slots after a (re)build.
    fn index_slots(&mut self) {
        self.slots_of = vec![Vec::new(); self.movable.len()];
        for (slot, t) in self.bvh.triangles.iter().enumerate() {
            if let Some(list) = self
                .slots_of
                .get_mut(self.instance_of[t.scene_index as usize] as usize)
            {
                list.push(slot as u32);
            }
        }
    }
}
