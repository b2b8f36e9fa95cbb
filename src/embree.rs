//! Embree 3 on the CPU as a peer of the GPU tracers (cargo feature `embree`, which links
//! the system's `libembree3`; Debian: `apt-get install libembree-dev`): the same 16 shadow
//! rays per pixel as `packet` and `per-ray` (the pixel's interleaved set, the same origin,
//! direction and extent, the same rules for rays below the horizon or behind the light),
//! traced as one `rtcOccluded16` packet per pixel on all cores, into the same 16-bit masks.
//! Nothing here shares the kernels' arithmetic, so it is also an independent oracle; for
//! alpha-tested triangles an occlusion filter asks [`crate::bvh::AlphaMasks::passes_record`]
//! at Embree's own hit (the mask lookup is shared, the ray–triangle test is Embree's).
//!
//! Only the dozen functions and three structs needed are bound, from Embree 3.13's
//! headers (`rtcore_*.h`); the struct layouts are those of its default build
//! (`RTC_MAX_INSTANCE_LEVEL_COUNT` 1, `RTC_MIN_WIDTH` 0), as Debian ships it.

use std::ffi::{c_char, c_int, c_uint, c_void};
use std::time::Instant;

use glam::Vec3;

use crate::bvh::Bvh;
use crate::contract::layout::{GBufferTexel, MASK_FULL, MASK_SKY, ShadowParams};
use crate::reference::shadow_per_ray::initial_mask;
use crate::sampling::{SAMPLES_PER_SET, pixel_set};
use crate::scene::view::QuadLight;
use crate::{Error, Result};

type RtcDevice = *mut c_void;
type RtcScene = *mut c_void;
type RtcGeometry = *mut c_void;

/// `RTCRay16`: 16 rays, structure of arrays, 64-byte aligned.
#[repr(C, align(64))]
struct RtcRay16 {
    org_x: [f32; 16],
    org_y: [f32; 16],
    org_z: [f32; 16],
    tnear: [f32; 16],
    dir_x: [f32; 16],
    dir_y: [f32; 16],
    dir_z: [f32; 16],
    time: [f32; 16],
    tfar: [f32; 16],
    mask: [c_uint; 16],
    id: [c_uint; 16],
    flags: [c_uint; 16],
}

/// The packet's valid mask (-1: trace the ray, 0: skip it); Embree needs it 64-byte aligned.
#[repr(C, align(64))]
struct Valid16([c_int; 16]);

/// `RTCIntersectContext` with one instance level and no minimum width.
#[repr(C)]
struct RtcIntersectContext {
    flags: c_uint,
    filter: *const c_void,
    inst_id: [c_uint; 1],
}

const RTC_GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
const RTC_BUFFER_TYPE_INDEX: c_uint = 0;
const RTC_BUFFER_TYPE_VERTEX: c_uint = 1;
const RTC_FORMAT_UINT3: c_uint = 0x5003;
const RTC_FORMAT_FLOAT3: c_uint = 0x9003;
const RTC_SCENE_FLAG_ROBUST: c_uint = 1 << 2;
const RTC_BUILD_QUALITY_HIGH: c_uint = 2;
const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: c_uint = 1;
const RTC_INVALID_GEOMETRY_ID: c_uint = c_uint::MAX;

#[link(name = "embree3")]
unsafe extern "C" {
    fn rtcNewDevice(config: *const c_char) -> RtcDevice;
    fn rtcReleaseDevice(device: RtcDevice);
    fn rtcGetDeviceError(device: RtcDevice) -> c_uint;
    fn rtcNewScene(device: RtcDevice) -> RtcScene;
    fn rtcSetSceneFlags(scene: RtcScene, flags: c_uint);
    fn rtcSetSceneBuildQuality(scene: RtcScene, quality: c_uint);
    fn rtcCommitScene(scene: RtcScene);
    fn rtcReleaseScene(scene: RtcScene);
    fn rtcNewGeometry(device: RtcDevice, kind: c_uint) -> RtcGeometry;
    fn rtcSetNewGeometryBuffer(
        geometry: RtcGeometry,
        kind: c_uint,
        slot: c_uint,
        format: c_uint,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;
    fn rtcCommitGeometry(geometry: RtcGeometry);
    fn rtcAttachGeometry(scene: RtcScene, geometry: RtcGeometry) -> c_uint;
    fn rtcReleaseGeometry(geometry: RtcGeometry);
    fn rtcSetGeometryOccludedFilterFunction(geometry: RtcGeometry, filter: Option<RtcFilterFunctionN>);
    fn rtcSetGeometryUserData(geometry: RtcGeometry, ptr: *mut c_void);
    fn rtcOccluded16(
        valid: *const Valid16,
        scene: RtcScene,
        context: *mut RtcIntersectContext,
        ray: *mut RtcRay16,
    );
}

/// `RTCFilterFunctionNArguments` (Embree 3).
#[repr(C)]
struct RtcFilterFunctionNArguments {
    valid: *mut c_int,
    geometry_user_ptr: *mut c_void,
    context: *const RtcIntersectContext,
    ray: *mut c_void,
    hit: *const c_void,
    n: c_uint,
}

type RtcFilterFunctionN = unsafe extern "C" fn(args: *const RtcFilterFunctionNArguments);

/// What the occlusion filter reads: each triangle's [`crate::contract::layout::BvhTriangle::alpha`]
/// (by Embree's primitive ID, which is the leaf-order index) and the masks.
struct AlphaFilter {
    records: Vec<u32>,
    masks: crate::bvh::AlphaMasks,
}

/// Embree's occlusion filter: rejects the hits where the triangle's alpha mask lets the
/// ray pass. `RTCHitN` is structure-of-arrays: `Ng_x, Ng_y, Ng_z, u, v, primID, …`, each
/// `N` wide; `u` and `v` weigh corners 1 and 2 (Embree's triangle is `(1-u-v)·v0 + u·v1 + v·v2`).
unsafe extern "C" fn alpha_filter(args: *const RtcFilterFunctionNArguments) {
    // SAFETY: Embree passes valid arguments for `n` lanes and the user pointer it was
    // given, an `AlphaFilter` that the `EmbreeScene` keeps alive.
    unsafe {
        let args = &*args;
        let n = args.n as usize;
        let filter = &*(args.geometry_user_ptr as *const AlphaFilter);
        let floats = args.hit as *const f32;
        let ints = args.hit as *const c_uint;
        for i in 0..n {
            let valid = args.valid.add(i);
            if *valid == 0 {
                continue;
            }
            let (u, v) = (*floats.add(3 * n + i), *floats.add(4 * n + i));
            let prim = *ints.add(5 * n + i) as usize;
            if filter
                .masks
                .passes_record(filter.records[prim], [1.0 - u - v, u, v])
            {
                *valid = 0;
            }
        }
    }
}

/// The environment variable whose value [`EmbreeScene::new`] passes to `rtcNewDevice` as
/// Embree's device config (empty when unset: Embree's defaults, the best ISA of the CPU
/// and all its cores), e.g. `isa=avx2` to run the AVX2 kernels on an AVX-512 machine.
pub const EMBREE_CONFIG_VAR: &str = "PENUMBRA_EMBREE_CONFIG";

/// An Embree device and a committed scene of a BVH's triangles (the same corners, in the
/// same leaf order, as the GPU reads).
pub struct EmbreeScene {
    device: RtcDevice,
    scene: RtcScene,
    /// The occlusion filter's data when the scene has alpha-tested triangles (boxed: Embree
    /// holds its address).
    alpha: Option<Box<AlphaFilter>>,
    /// Milliseconds Embree took to build its own BVH (`rtcCommitScene`).
    pub build_ms: f64,
}

// SAFETY: a committed Embree scene may be traced from any number of threads at once
// (Embree's documented contract for rtcIntersect/rtcOccluded); nothing here mutates it.
unsafe impl Sync for EmbreeScene {}
// SAFETY: the handles may move between threads; Embree objects are reference counted.
unsafe impl Send for EmbreeScene {}

impl EmbreeScene {
    /// Builds Embree's BVH over `bvh`'s triangles (robust mode: Embree's watertight
    /// triangle test; high build quality).
    pub fn new(bvh: &Bvh) -> Result<EmbreeScene> {
        let n = bvh.triangles.len();
        if n == 0 {
            return Err(Error::invalid("Embree scene", "the scene has no triangles"));
        }
        // Embree's device config (e.g. `isa=avx2,threads=2`), so that it can run with the
        // instruction set or the threads of another machine. Unset or not Unicode: none.
        let config = std::env::var(EMBREE_CONFIG_VAR).unwrap_or_default();
        let config = std::ffi::CString::new(config)
            .map_err(|_| Error::invalid(EMBREE_CONFIG_VAR, "holds a NUL byte"))?;
        // SAFETY: every pointer passed is either a NUL-terminated string that outlives the
        // call or returned by Embree for exactly the size written; errors are checked below.
        unsafe {
            let device = rtcNewDevice(config.as_ptr());
            if device.is_null() {
                let message = match config.to_str() {
                    Ok("") | Err(_) => "rtcNewDevice failed".to_string(),
                    Ok(c) => {
                        format!("rtcNewDevice failed with the device config {c:?} of {EMBREE_CONFIG_VAR}")
                    }
                };
                return Err(Error::invalid("Embree", message));
            }
            let scene = rtcNewScene(device);
            let alpha = (bvh.alpha.triangles > 0).then(|| {
                Box::new(AlphaFilter {
                    records: bvh.triangles.iter().map(|t| t.alpha).collect(),
                    masks: bvh.alpha.clone(),
                })
            });
            let mut out = EmbreeScene {
                device,
                scene,
                alpha,
                build_ms: 0.0,
            };
            rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
            rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
            let geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
            let vertices =
                rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, 3 * n)
                    as *mut f32;
            let indices = rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, n)
                as *mut u32;
            if vertices.is_null() || indices.is_null() {
                rtcReleaseGeometry(geometry);
                return Err(out.error("allocating the triangle buffers"));
            }
            let vertices = std::slice::from_raw_parts_mut(vertices, 9 * n);
            let indices = std::slice::from_raw_parts_mut(indices, 3 * n);
            for (i, t) in bvh.triangles.iter().enumerate() {
                for (k, corner) in [t.v0, t.v1, t.v2].iter().enumerate() {
                    vertices[9 * i + 3 * k..9 * i + 3 * k + 3].copy_from_slice(&corner.to_array());
                    indices[3 * i + k] = (3 * i + k) as u32;
                }
            }
            if let Some(alpha) = &out.alpha {
                rtcSetGeometryUserData(geometry, &**alpha as *const AlphaFilter as *mut c_void);
                rtcSetGeometryOccludedFilterFunction(geometry, Some(alpha_filter));
            }
            rtcCommitGeometry(geometry);
            rtcAttachGeometry(scene, geometry);
            rtcReleaseGeometry(geometry);
            let start = Instant::now();
            rtcCommitScene(scene);
            let build_ms = start.elapsed().as_secs_f64() * 1e3;
            // `out` owns the handles (its Drop releases them): update it, do not copy them out.
            out.build_ms = build_ms;
            match rtcGetDeviceError(device) {
                0 => Ok(out),
                _ => Err(out.error("building the scene")),
            }
        }
    }

    fn error(&self, what: &str) -> Error {
        // SAFETY: the device is alive while self is.
        let code = unsafe { rtcGetDeviceError(self.device) };
        Error::invalid("Embree", format!("{what} failed (RTCError {code})"))
    }

    /// One pixel's mask: [`initial_mask`]'s rays (below the horizon, behind the light) are
    /// blocked without tracing, the others go to their light sample in one occlusion
    /// packet, `t` in `[0, params.t_max]`.
    pub fn pixel_mask(
        &self,
        texel: &GBufferTexel,
        set: usize,
        light_points: &[Vec3],
        params: &ShadowParams,
    ) -> u32 {
        let mut mask = initial_mask(texel, set, light_points, params);
        if mask & MASK_SKY != 0 || mask & MASK_FULL == MASK_FULL {
            return mask;
        }
        let o = texel.origin;
        let mut ray = RtcRay16 {
            org_x: [o.x; 16],
            org_y: [o.y; 16],
            org_z: [o.z; 16],
            tnear: [0.0; 16],
            dir_x: [0.0; 16],
            dir_y: [0.0; 16],
            dir_z: [0.0; 16],
            time: [0.0; 16],
            tfar: [params.t_max; 16],
            mask: [c_uint::MAX; 16],
            id: [0; 16],
            flags: [0; 16],
        };
        let mut valid = Valid16([0; 16]);
        for j in 0..SAMPLES_PER_SET {
            let d = light_points[set * SAMPLES_PER_SET + j] - o;
            ray.dir_x[j] = d.x;
            ray.dir_y[j] = d.y;
            ray.dir_z[j] = d.z;
            ray.id[j] = j as c_uint;
            valid.0[j] = if mask & (1 << j) == 0 { -1 } else { 0 };
        }
        let mut context = RtcIntersectContext {
            flags: RTC_INTERSECT_CONTEXT_FLAG_COHERENT,
            filter: std::ptr::null(),
            inst_id: [RTC_INVALID_GEOMETRY_ID],
        };
        // SAFETY: `ray` and `valid` are 64-byte aligned (Embree's requirement for 16-wide
        // packets), the scene is committed.
        unsafe { rtcOccluded16(&valid, self.scene, &mut context, &mut ray) };
        for j in 0..SAMPLES_PER_SET {
            // An occluded ray's tfar is set to -inf.
            if valid.0[j] != 0 && ray.tfar[j] == f32::NEG_INFINITY {
                mask |= 1 << j;
            }
        }
        mask
    }

    /// Masks of a whole G-buffer (row-major), rows spread over all cores.
    pub fn masks(&self, gbuffer: &[GBufferTexel], light_points: &[Vec3], params: &ShadowParams) -> Vec<u32> {
        crate::reference::parallel::per_texel(gbuffer, params, |x, y, texel| {
            self.pixel_mask(texel, pixel_set(x, y), light_points, params)
        })
    }
}

impl EmbreeScene {
    /// The masks of a renderer's G-buffer for [`crate::gpu::Renderer::render_with_cpu_shadows`]:
    /// `gbuffer` is `width`×`height` and relative to `origin` ([`crate::gpu::GpuScene::origin`]),
    /// `light` in world space, as this scene's BVH is.
    pub fn frame_masks(
        &self,
        light: &QuadLight,
        origin: Vec3,
        gbuffer: &[GBufferTexel],
        width: u32,
        height: u32,
    ) -> Vec<u32> {
        // A scene near the world's origin is not moved (GpuScene::origin is zero): no copy.
        let world: std::borrow::Cow<[GBufferTexel]> = if origin == Vec3::ZERO {
            gbuffer.into()
        } else {
            gbuffer
                .iter()
                .map(|t| GBufferTexel {
                    origin: t.origin + origin,
                    ..*t
                })
                .collect()
        };
        let params = crate::contract::shadow::shadow_params(light, width, height);
        self.masks(&world, &crate::sampling::light_points(light), &params)
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: both handles came from Embree and are released once.
        unsafe {
            rtcReleaseScene(self.scene);
            rtcReleaseDevice(self.device);
        }
    }
}
