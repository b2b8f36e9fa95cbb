//! The scene as the driver's own acceleration structures, for the ray-query tracer
//! ([`super::Tracer::RayQuery`]): one BLAS over the scene's BVH triangle buffer, which
//! it reads as a vertex buffer (each 48-byte `BvhTriangle` holds its three corners at
//! bytes 0, 16 and 32, so the buffer is three `Float32x3` vertices per triangle at a
//! 16-byte stride: nothing is copied), and a TLAS with that BLAS as its one instance,
//! untransformed. The driver builds both (on lavapipe, on the CPU) and traverses them.

use std::time::Instant;

use crate::{Error, Result};

/// The rows of the identity as a TLAS instance's 3×4 row-major transform.
const IDENTITY: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
/// Bytes from one corner to the next in a `BvhTriangle` buffer.
const CORNER_STRIDE: u64 = 16;

/// A scene's BLAS and TLAS on one device (made by [`super::GpuScene::new`] when the
/// device has [`wgpu::Features::EXPERIMENTAL_RAY_QUERY`]).
#[derive(Debug)]
pub struct RayQueryScene {
    device: wgpu::Device,
    /// The scene's triangles; `None` for a scene without any (the TLAS then has no instance).
    blas: Option<(wgpu::Blas, wgpu::BlasTriangleGeometrySizeDescriptor)>,
    /// What the ray-query kernel binds.
    pub tlas: wgpu::Tlas,
    /// Wall-clock milliseconds of the last build of both structures, from recording to
    /// the device's finishing it.
    pub build_ms: f64,
}

impl RayQueryScene {
    /// Builds the structures over the first `count` triangles of `triangles` (an
    /// `array<BvhTriangle>` made with [`wgpu::BufferUsages::BLAS_INPUT`]) and waits for them.
    /// `opaque`: no triangle is alpha-tested, so the geometry is marked opaque and a query
    /// never stops at a candidate; else every hit is a candidate the kernel decides.
    pub(crate) fn new(
        ctx: &super::GpuContext,
        triangles: &wgpu::Buffer,
        count: u32,
        opaque: bool,
    ) -> Result<RayQueryScene> {
        let flags = wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE;
        let vertex_count = count.checked_mul(3).ok_or_else(|| {
            Error::Gpu(format!(
                "ray queries: {count} triangles are too many for one BLAS"
            ))
        })?;
        let blas = (count > 0).then(|| {
            let size = wgpu::BlasTriangleGeometrySizeDescriptor {
                vertex_format: wgpu::VertexFormat::Float32x3,
                vertex_count,
                index_format: None,
                index_count: None,
                flags: if opaque {
                    wgpu::AccelerationStructureGeometryFlags::OPAQUE
                } else {
                    wgpu::AccelerationStructureGeometryFlags::empty()
                },
            };
            let blas = ctx.device.create_blas(
                &wgpu::CreateBlasDescriptor {
                    label: Some("scene BLAS"),
                    flags,
                    update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                },
                wgpu::BlasGeometrySizeDescriptors::Triangles {
                    descriptors: vec![size.clone()],
                },
            );
            (blas, size)
        });
        let tlas = ctx.device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some("scene TLAS"),
            max_instances: 1,
            flags,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        let mut scene = RayQueryScene {
            device: ctx.device.clone(),
            blas,
            tlas,
            build_ms: 0.0,
        };
        if let Some((blas, _)) = &scene.blas {
            scene.tlas[0] = Some(wgpu::TlasInstance::new(blas, IDENTITY, 0, 0xff));
        }
        ctx.capture_errors("ray queries: building the BLAS and TLAS", || {
            scene.build(&ctx.queue, triangles)
        })??;
        Ok(scene)
    }

    /// Builds both structures again from `triangles` (after [`super::GpuScene::set_transforms`]
    /// wrote new corners: the writes reach the device before this submission) and waits.
    pub(crate) fn build(&mut self, queue: &wgpu::Queue, triangles: &wgpu::Buffer) -> Result<()> {
        let start = Instant::now();
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("ray-query structures"),
            });
        let entries: Vec<wgpu::BlasBuildEntry<'_>> = self
            .blas
            .iter()
            .map(|(blas, size)| wgpu::BlasBuildEntry {
                blas,
                geometry: wgpu::BlasGeometries::TriangleGeometries(vec![wgpu::BlasTriangleGeometry {
                    size,
                    vertex_buffer: triangles,
                    first_vertex: 0,
                    vertex_stride: CORNER_STRIDE,
                    index_buffer: None,
                    first_index: None,
                    transform_buffer: None,
                    transform_buffer_offset: None,
                }]),
            })
            .collect();
        encoder.build_acceleration_structures(&entries, std::iter::once(&self.tlas));
        let index = queue.submit([encoder.finish()]);
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| Error::Gpu(format!("ray queries: waiting for the BLAS and TLAS: {e}")))?;
        self.build_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }
}
