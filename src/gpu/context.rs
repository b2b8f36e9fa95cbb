//! Adapter choice and device creation.

use std::fmt;

use crate::{Error, Result};

/// Environment variable that picks the adapter when [`GpuOptions::adapter`] is `None`.
pub const ADAPTER_ENV: &str = "PENUMBRA_ADAPTER";

/// Environment variable Mesa's lavapipe reads when its driver loads: the width in bits of
/// its SIMD vectors, which sets its subgroup size (256, the default: 8 lanes; 512: 16).
pub const LAVAPIPE_VECTOR_WIDTH_ENV: &str = "LP_NATIVE_VECTOR_WIDTH";

/// Environment variable that names the folder of Mesa's on-disk shader cache (Mesa makes its
/// cache folders inside it).
pub const SHADER_CACHE_DIR_ENV: &str = "MESA_SHADER_CACHE_DIR";

/// The folder for Mesa's shader cache that a process with [`LAVAPIPE_VECTOR_WIDTH_ENV`] set
/// and [`SHADER_CACHE_DIR_ENV`] unset should use: `penumbra-lavapipe-<width>` in the user's
/// cache folder (`$XDG_CACHE_HOME`, else `$HOME/.cache`, where Mesa keeps its own); `None`
/// otherwise, or where neither variable names a folder.
///
/// Why: Mesa 25.0 lavapipe compiles one function per texture and kind of texel fetch and
/// keeps it in the shader cache under a key without the vector width. A process at another
/// width then calls a cached function compiled for the wrong one: `textureLoad` returns
/// wrong texels (16 lanes after 8) or the process dies with SIGSEGV (8 after 16). Measured
/// with Mesa 25.0.7 (LLVM 15); Mesa 22.3 compiles texel fetches inline and is not affected.
/// One cache folder per width keeps them apart.
pub fn lavapipe_shader_cache_dir() -> Option<std::path::PathBuf> {
    let set = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    let width = set(LAVAPIPE_VECTOR_WIDTH_ENV)?;
    if set(SHADER_CACHE_DIR_ENV).is_some() {
        return None;
    }
    let root = match set("XDG_CACHE_HOME") {
        Some(dir) => std::path::PathBuf::from(dir),
        None => std::path::PathBuf::from(set("HOME")?).join(".cache"),
    };
    let width = width.to_string_lossy();
    Some(root.join(format!("penumbra-lavapipe-{width}")))
}

/// Environment variable that turns off Mesa's device-selection layer
/// (`VK_LAYER_MESA_device_select`, an implicit Vulkan layer).
pub const NO_DEVICE_SELECT_ENV: &str = "NODEVICE_SELECT";

/// Sets three driver defaults for this process where the user has not set them, and returns
/// the names of the variables it set:
///
/// - [`LAVAPIPE_VECTOR_WIDTH_ENV`]` = 512`: 16-wide lavapipe subgroups. At the default 8
///   lanes the kernels' 16-wide vector cannot live in one subgroup and falls back to the
///   workgroup vector, several times slower (README "Performance"); 16 lanes work on AVX2
///   as on AVX-512 CPUs (LLVM splits the vectors). Other drivers ignore it.
/// - [`NO_DEVICE_SELECT_ENV`]` = 1` when there is no `XDG_RUNTIME_DIR` (a headless
///   machine) and the user has not asked Mesa for a device (`MESA_VK_DEVICE_SELECT`): the
///   device-selection layer connects to a Wayland display while listing devices, and there
///   libwayland prints "error: XDG_RUNTIME_DIR is invalid or not set in the environment."
///   twice; penumbra picks its adapter itself ([`GpuOptions`]), so the layer has nothing to do.
/// - [`SHADER_CACHE_DIR_ENV`] = [`lavapipe_shader_cache_dir`] when the vector width is set
///   (by the user or here): a shader cache of its own for each lavapipe width.
///
/// # Safety
///
/// It sets process environment variables ([`std::env::set_var`]): call it first thing in
/// `main`, while no other thread runs, and before the first Vulkan instance is created
/// (the driver and the loader read them when they load, once per process).
pub unsafe fn set_driver_defaults() -> Vec<&'static str> {
    // SAFETY: passed on from the caller.
    unsafe { set_defaults(true) }
}

/// [`set_driver_defaults`] for a process that also draws with the GPU (a host application
/// such as the `embed` example): only [`NO_DEVICE_SELECT_ENV`]. Lavapipe stays at its
/// default 8 lanes (the shadow pass then runs the workgroup vector), because lavapipe's
/// rasterizer crashes at 512-bit vectors on some CPUs: a single draw of a full-screen
/// triangle with a constant colour into an `Rgba8Unorm` target dies in
/// `llvm::ConstantVector::ConstantVector` (Mesa 22.3.6, SIGSEGV) or with a bus error
/// (Mesa 25.0.7) while the driver compiles it, on a 2-core Intel Xeon with AVX-512
/// (LLVM 15); at 256 bits it draws. Compute work is not affected.
///
/// # Safety
///
/// As [`set_driver_defaults`].
pub unsafe fn set_driver_defaults_for_drawing() -> Vec<&'static str> {
    // SAFETY: passed on from the caller.
    unsafe { set_defaults(false) }
}

/// Sets the defaults; the vector width only when `vector_width`.
unsafe fn set_defaults(vector_width: bool) -> Vec<&'static str> {
    let unset = |name: &str| std::env::var_os(name).is_none_or(|v| v.is_empty());
    let mut set = Vec::new();
    if vector_width && unset(LAVAPIPE_VECTOR_WIDTH_ENV) {
        set.push((LAVAPIPE_VECTOR_WIDTH_ENV, "512"));
    }
    if unset("XDG_RUNTIME_DIR") && unset("MESA_VK_DEVICE_SELECT") && unset(NO_DEVICE_SELECT_ENV) {
        set.push((NO_DEVICE_SELECT_ENV, "1"));
    }
    for &(name, value) in &set {
        // SAFETY: the caller of the public functions guarantees that no other thread runs.
        unsafe { std::env::set_var(name, value) };
    }
    let mut names: Vec<&'static str> = set.into_iter().map(|(name, _)| name).collect();
    if let Some(dir) = lavapipe_shader_cache_dir() {
        // Mesa makes its folders inside this one but not the folder itself. Where it cannot be
        // made, Mesa runs without a cache (slower to start, still right).
        let _ = std::fs::create_dir_all(&dir);
        // SAFETY: as above.
        unsafe { std::env::set_var(SHADER_CACHE_DIR_ENV, dir) };
        names.push(SHADER_CACHE_DIR_ENV);
    }
    names
}

/// How to choose the GPU.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// The adapter to use: an index into the enumerated list or a case-insensitive part of
    /// its name. `None`: the env var [`ADAPTER_ENV`], else the best one found.
    pub adapter: Option<String>,
    /// Create the device with ray queries ([`wgpu::Features::EXPERIMENTAL_RAY_QUERY`], for
    /// [`crate::gpu::Tracer::RayQuery`]); [`Error::RayQueryUnsupported`] when the adapter
    /// has none. Off by default: scenes then build no acceleration structures.
    pub ray_query: bool,
}

/// What the chosen adapter is and can do, in one printable line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterSummary {
    /// Adapter name, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub name: String,
    /// Graphics API wgpu drives it through.
    pub backend: wgpu::Backend,
    /// Discrete, integrated, virtual, CPU or other.
    pub device_type: wgpu::DeviceType,
    /// Driver name.
    pub driver: String,
    /// Driver version and details.
    pub driver_info: String,
    /// Smallest subgroup size the adapter may use.
    pub subgroup_min_size: u32,
    /// Largest subgroup size the adapter may use.
    pub subgroup_max_size: u32,
    /// The device was created with [`wgpu::Features::SUBGROUP`].
    pub has_subgroups: bool,
    /// The device was created with [`wgpu::Features::TIMESTAMP_QUERY`].
    pub has_timestamps: bool,
    /// Largest storage-buffer binding, in bytes.
    pub max_storage_buffer_binding_size: u64,
    /// Largest dispatch size in each dimension, in workgroups.
    pub max_compute_workgroups_per_dimension: u32,
}

impl AdapterSummary {
    /// The summary of `device`'s adapter and of the features and limits it was created with.
    pub fn of(device: &wgpu::Device) -> AdapterSummary {
        let adapter_info = device.adapter_info();
        let features = device.features();
        let limits = device.limits();
        AdapterSummary {
            name: adapter_info.name,
            backend: adapter_info.backend,
            device_type: adapter_info.device_type,
            driver: adapter_info.driver,
            driver_info: adapter_info.driver_info,
            subgroup_min_size: adapter_info.subgroup_min_size,
            subgroup_max_size: adapter_info.subgroup_max_size,
            has_subgroups: features.contains(wgpu::Features::SUBGROUP),
            has_timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            max_storage_buffer_binding_size: limits.max_storage_buffer_binding_size,
            max_compute_workgroups_per_dimension: limits.max_compute_workgroups_per_dimension,
        }
    }
}

impl fmt::Display for AdapterSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} — {:?}, {:?}, driver {} {}, ",
            self.name, self.backend, self.device_type, self.driver, self.driver_info
        )?;
        if self.has_subgroups {
            write!(
                f,
                "subgroups {}..{}",
                self.subgroup_min_size, self.subgroup_max_size
            )?;
        } else {
            f.write_str("subgroups no")?;
        }
        let timestamps = if self.has_timestamps { "yes" } else { "no" };
        write!(f, ", timestamps {timestamps}")
    }
}

/// Everything needed to run compute work: the wgpu objects plus a summary of the adapter.
#[derive(Debug)]
pub struct GpuContext {
    /// The wgpu instance the adapter came from (`None` for a host's device, see
    /// [`GpuContext::from_device`]).
    pub instance: Option<wgpu::Instance>,
    /// The chosen adapter (`None` for a host's device).
    pub adapter: Option<wgpu::Adapter>,
    /// The device, created with the adapter's own limits.
    pub device: wgpu::Device,
    /// The device's queue.
    pub queue: wgpu::Queue,
    /// What the adapter is and which optional features the device has.
    pub info: AdapterSummary,
}

impl GpuContext {
    /// Chooses an adapter (see [`GpuOptions`]) and creates a device on it.
    ///
    /// Vulkan adapters come first (lavapipe in tests and CI); other backends are used when
    /// Vulkan has none. `SUBGROUP` and `TIMESTAMP_QUERY` are enabled where offered.
    pub fn new(opts: &GpuOptions) -> Result<GpuContext> {
        let wanted = match &opts.adapter {
            Some(w) => Some(w.clone()),
            None => std::env::var(ADAPTER_ENV).ok().filter(|w| !w.trim().is_empty()),
        };
        // The other backends are asked only when Vulkan has no adapter or one is named: the
        // GL backend probes for a Wayland display, and on a headless machine libwayland
        // prints "error: XDG_RUNTIME_DIR is invalid or not set" twice, although the
        // renderer never presents.
        let first = match wanted {
            Some(_) => wgpu::Backends::all(),
            None => wgpu::Backends::VULKAN,
        };
        let mut instance = new_instance(first);
        let mut adapters = enumerate(&instance, first);
        if adapters.is_empty() && first != wgpu::Backends::all() {
            instance = new_instance(wgpu::Backends::all());
            adapters = enumerate(&instance, wgpu::Backends::all());
        }
        let adapter = match wanted {
            Some(wanted) => pick_named(&adapters, &wanted)?,
            None => pick_auto(&adapters)?,
        };

        let offered = adapter.features();
        let mut required_features = offered & (wgpu::Features::SUBGROUP | wgpu::Features::TIMESTAMP_QUERY);
        if opts.ray_query {
            if !offered.contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY) {
                let info = adapter.get_info();
                return Err(ray_queries_missing(&info.name, &info.driver, &info.driver_info));
            }
            required_features |= wgpu::Features::EXPERIMENTAL_RAY_QUERY;
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("penumbra"),
            required_features,
            // The adapter's own limits, not the WebGPU defaults: scenes need big storage buffers.
            required_limits: adapter.limits(),
            // SAFETY: the only experimental feature is ray queries, asked for by
            // `opts.ray_query`; penumbra uses them only as wgpu's ray-tracing spec describes
            // (BLAS built before the TLAS that holds it, both before the kernel binds it).
            experimental_features: if opts.ray_query {
                unsafe { wgpu::ExperimentalFeatures::enabled() }
            } else {
                wgpu::ExperimentalFeatures::disabled()
            },
            ..Default::default()
        }))
        .map_err(|e| Error::Device(e.to_string()))?;

        let info = AdapterSummary::of(&device);
        Ok(GpuContext {
            instance: Some(instance),
            adapter: Some(adapter),
            device,
            queue,
            info,
        })
    }

    /// A context around a device the caller already has (an application embedding
    /// penumbra): `device` and `queue` are shared handles, so the caller keeps using them.
    pub fn from_device(device: &wgpu::Device, queue: &wgpu::Queue) -> GpuContext {
        GpuContext {
            instance: None,
            adapter: None,
            info: AdapterSummary::of(device),
            device: device.clone(),
            queue: queue.clone(),
        }
    }

    /// Runs `f` inside validation and out-of-memory error scopes, turning an error that wgpu
    /// reports into [`Error::Gpu`] (prefixed with `what`) instead of the default handler's panic.
    pub fn capture_errors<R>(&self, what: &str, f: impl FnOnce() -> R) -> Result<R> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = f();
        // Scopes are a stack: the inner one pops first.
        let validation_error = pollster::block_on(validation.pop());
        let oom_error = pollster::block_on(oom.pop());
        match validation_error.or(oom_error) {
            None => Ok(value),
            Some(e) => Err(Error::Gpu(format!("{what}: {e}"))),
        }
    }
}

/// [`Error::RayQueryUnsupported`] for the adapter `name` and its driver.
pub(super) fn ray_queries_missing(name: &str, driver: &str, driver_info: &str) -> Error {
    Error::RayQueryUnsupported {
        adapter: name.to_owned(),
        driver: format!("{driver} {driver_info}"),
    }
}

/// An instance of `backends`, without window-system support (the renderer never presents);
/// WGPU_DEBUG / WGPU_VALIDATION and backend options still come from the environment.
fn new_instance(backends: wgpu::Backends) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle().with_env();
    desc.backends = backends;
    wgpu::Instance::new(desc)
}

/// The adapters of `backends`, Vulkan ones first, each group in the order the backend
/// reports them.
fn enumerate(instance: &wgpu::Instance, backends: wgpu::Backends) -> Vec<wgpu::Adapter> {
    let mut adapters = pollster::block_on(instance.enumerate_adapters(backends & wgpu::Backends::VULKAN));
    let others = backends - wgpu::Backends::VULKAN;
    if !others.is_empty() {
        adapters.extend(pollster::block_on(instance.enumerate_adapters(others)));
    }
    adapters
}

/// One line per adapter, as listed in [`Error::AdapterNotFound`].
fn describe(adapters: &[wgpu::Adapter]) -> Vec<String> {
    adapters
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let info = a.get_info();
            format!("{i}: {} ({:?}, {:?})", info.name, info.backend, info.device_type)
        })
        .collect()
}

/// The adapter `wanted` names: an index into `adapters`, else the first whose name contains it.
fn pick_named(adapters: &[wgpu::Adapter], wanted: &str) -> Result<wgpu::Adapter> {
    let key = wanted.trim();
    let found = match key.parse::<usize>() {
        Ok(index) => adapters.get(index),
        Err(_) => {
            let key = key.to_lowercase();
            adapters
                .iter()
                .find(|a| a.get_info().name.to_lowercase().contains(&key))
        }
    };
    found.cloned().ok_or_else(|| Error::AdapterNotFound {
        wanted: wanted.to_owned(),
        available: describe(adapters),
    })
}

/// The best adapter: Vulkan before other backends, then discrete > integrated > virtual > CPU.
fn pick_auto(adapters: &[wgpu::Adapter]) -> Result<wgpu::Adapter> {
    let rank = |a: &wgpu::Adapter| {
        let info = a.get_info();
        let type_rank = match info.device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        (info.backend != wgpu::Backend::Vulkan, type_rank)
    };
    // min_by_key keeps the first of equals, so enumeration order breaks ties.
    adapters
        .iter()
        .min_by_key(|a| rank(a))
        .cloned()
        .ok_or_else(|| Error::NoAdapter {
            tried: backend_names(wgpu::Instance::enabled_backend_features()),
        })
}

/// `Vulkan, Metal, ...` for the backends in `backends`.
fn backend_names(backends: wgpu::Backends) -> String {
    let names: Vec<String> = wgpu::Backend::ALL
        .into_iter()
        .filter(|&b| backends.contains(b.into()))
        .map(|b| format!("{b:?}"))
        .collect();
    if names.is_empty() {
        "no backends (wgpu was built without any)".to_owned()
    } else {
        names.join(", ")
    }
}
