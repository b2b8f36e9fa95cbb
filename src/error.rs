//! The library's one error type.

use std::path::PathBuf;

/// Everything that can go wrong in penumbra that a caller cannot rule out
/// beforehand: bad input files, bad views, missing GPU features.
///
/// Each variant names the file (or thing) at fault and what is wrong with it,
/// so the CLI can print `error: {err}` and stop.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene file could not be read or understood.
    #[error("{path}: {message}")]
    Scene {
        /// The glTF/GLB file (or the buffer/image it references).
        path: PathBuf,
        /// What is wrong, in words.
        message: String,
    },
    /// A view file (camera + light) could not be read or understood.
    #[error("{path}: {message}")]
    View {
        /// The view file.
        path: PathBuf,
        /// What is wrong, in words.
        message: String,
    },
    /// The BVH could not be built (for example: the scene has no triangles).
    #[error("BVH: {0}")]
    Bvh(String),
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// No GPU adapter was found on any backend wgpu was built with.
    #[error(
        "no GPU adapter found (tried: {tried}); install a Vulkan driver; \
         with no GPU: apt-get install mesa-vulkan-drivers"
    )]
    NoAdapter {
        /// The backends that were asked for adapters, e.g. `Vulkan, Metal, Dx12`.
        tried: String,
    },
    /// The adapter asked for (option or `PENUMBRA_ADAPTER`) matches none of those present.
    #[error(
        "no GPU adapter matches \"{wanted}\" (set by the adapter option or PENUMBRA_ADAPTER); \
         give an index or part of a name from the adapters available: {}",
        if available.is_empty() { "none".to_owned() } else { available.join("; ") }
    )]
    AdapterNotFound {
        /// What was asked for.
        wanted: String,
        /// Every adapter present, as `index: name (backend, type)`.
        available: Vec<String>,
    },
    /// The adapter refused to create a device.
    #[error(
        "could not create a GPU device: {0}; update the driver or pick another adapter with PENUMBRA_ADAPTER"
    )]
    Device(String),
    /// A GPU buffer would exceed the adapter's size limit for one storage-buffer binding.
    #[error(
        "GPU buffer `{what}` needs {bytes} bytes, more than this adapter's limit of {limit} bytes per \
         storage buffer; use a smaller scene or image, or an adapter with a larger limit"
    )]
    BufferTooLarge {
        /// Which buffer (its label).
        what: String,
        /// The size it needs.
        bytes: u64,
        /// The adapter's limit.
        limit: u64,
    },
    /// A host's device lacks features or limits that a pass needs (see
    /// [`crate::gpu::ShadowPass::required_features`] and
    /// [`crate::gpu::ShadowPass::required_limits`]).
    #[error(
        "the GPU device cannot run {what}: it lacks {}; create the device with at least \
         ShadowPass::required_features() and ShadowPass::required_limits()",
        missing.join(", ")
    )]
    DeviceUnsupported {
        /// The pass that cannot run, e.g. `the embedded shadow pass`.
        what: String,
        /// Each missing feature or too-small limit, e.g. `max_storage_buffers_per_shader_stage 4 (needs 8)`.
        missing: Vec<String>,
    },
    /// Ray queries were asked for ([`crate::gpu::GpuOptions::ray_query`]) on an adapter
    /// without them.
    #[error(
        "ray queries are missing: adapter `{adapter}`, driver `{driver}`, does not offer wgpu's \
         EXPERIMENTAL_RAY_QUERY (Vulkan VK_KHR_ray_query; Mesa 25 lavapipe and GPUs with ray \
         tracing have it, Mesa 22 lavapipe does not); choose another tracer or adapter"
    )]
    RayQueryUnsupported {
        /// The adapter's name.
        adapter: String,
        /// Its driver and version.
        driver: String,
    },
    /// Something a caller passed in does not fit the call: a texture of the wrong size,
    /// format or usage, an instance index that does not exist.
    #[error("{what}: {message}")]
    InvalidInput {
        /// The call or argument, e.g. `ShadowInputs::normal`.
        what: String,
        /// What is wrong, in words.
        message: String,
    },
    /// A number passed in is outside what the call accepts: an image side of 0, a leaf
    /// size, a ray count, an iteration budget.
    #[error("{what} = {value}: {expected}")]
    InvalidValue {
        /// The setting or argument, e.g. `FrameSettings::width` or `--spp`.
        what: String,
        /// The value at fault, as given.
        value: String,
        /// What it must be, in words.
        expected: String,
    },
    /// A kernel's loop ended before it finished, suspended or ran out of its budget: the
    /// driver ended it (lavapipe ends an invocation's loops after 65,535 iterations), so
    /// the pass's results are incomplete. Only an iteration budget above the driver's
    /// limit lets this happen; the pass reports it instead of returning those results.
    #[error(
        "{pass}: the driver ended the loops of {count} {units} before they finished (lavapipe \
         ends an invocation's loops after 65,535 iterations); the iteration budget {budget} is \
         more than this driver runs — lower it"
    )]
    LoopCut {
        /// The pass, e.g. `shadow pass (mft)`.
        pass: String,
        /// How many vectors, rays or pixels were cut short.
        count: u64,
        /// What `count` counts, e.g. `tiles`.
        units: String,
        /// The iteration budget the pass ran with.
        budget: u32,
    },
    /// An image needs a per-pixel GPU buffer larger than one storage-buffer
    /// binding of the adapter (checked before anything is allocated).
    #[error(
        "image {width}x{height} needs a {bytes}-byte `{what}` buffer, more than this adapter's \
         limit of {limit} bytes per storage buffer; the largest image of this shape that fits is \
         {largest_width}x{largest_height} (render smaller, or use an adapter with a larger limit)"
    )]
    ImageTooLarge {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// The largest buffer (its label).
        what: String,
        /// Its size in bytes.
        bytes: u64,
        /// The adapter's limit in bytes.
        limit: u64,
        /// Width of the largest image of about the same aspect ratio that fits.
        largest_width: u32,
        /// Its height.
        largest_height: u32,
    },
    /// Any other GPU failure: a validation error, a failed buffer mapping, a lost device.
    #[error("GPU error: {0}")]
    Gpu(String),
    /// An image could not be written or read back: unsupported extension,
    /// pixel count not matching the size, or the encoder/decoder failed.
    #[error("{path}: {message}")]
    Output {
        /// The image file.
        path: PathBuf,
        /// What is wrong, in words.
        message: String,
    },
    /// Two images that must be the same size are not.
    #[error(
        "{} is {}×{} but {} is {}×{}: images must be the same size to compare",
        a.display(), a_size.0, a_size.1, b.display(), b_size.0, b_size.1
    )]
    ImageSizeMismatch {
        /// The first image.
        a: PathBuf,
        /// Its width and height.
        a_size: (u32, u32),
        /// The second image.
        b: PathBuf,
        /// Its width and height.
        b_size: (u32, u32),
    },
    /// A CPU computation (the exact visibility reference) ran out of the time it was given.
    #[error(
        "{what}: not finished within the time budget of {budget_s:.1} s ({done} of {total} pixels done); \
         use a smaller image or scene, or a larger budget"
    )]
    TimeBudget {
        /// What was being computed.
        what: String,
        /// The budget, in seconds.
        budget_s: f64,
        /// Pixels finished when the budget ran out.
        done: usize,
        /// Pixels asked for.
        total: usize,
    },
}

impl Error {
    /// A scene error for `path`.
    pub fn scene(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Scene {
            path: path.into(),
            message: message.into(),
        }
    }

    /// An [`Error::InvalidInput`] about `what`.
    pub fn invalid(what: impl Into<String>, message: impl Into<String>) -> Self {
        Error::InvalidInput {
            what: what.into(),
            message: message.into(),
        }
    }

    /// An [`Error::InvalidValue`]: `what` = `value` is not `expected`.
    pub fn value(
        what: impl Into<String>,
        value: impl std::fmt::Display,
        expected: impl Into<String>,
    ) -> Self {
        Error::InvalidValue {
            what: what.into(),
            value: value.to_string(),
            expected: expected.into(),
        }
    }

    /// A view error for `path`.
    pub fn view(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::View {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// `Result` with penumbra's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
