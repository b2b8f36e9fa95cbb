//! What a shadow pass is built with: the tracer (multi-frusta tracing or one of the
//! baselines it is measured against), the MFT kernel's leaf mode, and the options
//! ([`TracerOptions`]) that hold them with the vector variant, counters and shrinking.

use std::fmt;
use std::str::FromStr;

use super::VectorVariant;

/// Rays per pixel of [`Tracer::Reference`] unless asked otherwise.
pub const DEFAULT_REFERENCE_RAYS: u32 = 256;

/// A shadow tracer. All of them trace the same rays for the same pixel (but
/// [`Tracer::Reference`]) and give the same masks as the CPU oracle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Tracer {
    /// Multi-frusta tracing: one 16-wide vector per 4×4 tile, lane = a pixel's
    /// frustum of 16 rays (`shaders/shadow_mft.wgsl`).
    #[default]
    Mft,
    /// The paper's baseline: one 16-wide vector per pixel, lane = one of its 16
    /// rays, shared traversal with per-ray slab tests (`shaders/shadow_packet.wgsl`).
    Packet,
    /// The usual GPU compute tracer: every invocation traces one ray alone
    /// (`shaders/shadow_per_ray.wgsl`).
    PerRay,
    /// The driver's own ray tracing: every invocation traces one ray with a ray query
    /// against a BLAS/TLAS the driver built (`shaders/shadow_ray_query.wgsl`); needs a
    /// device made with [`super::GpuOptions::ray_query`].
    RayQuery,
    /// The quality yardstick: `rays` per pixel, to the same `rays` Hammersley
    /// points of the light for every pixel, traced per ray; no filter. The
    /// pixel's mask word holds the number of blocked rays instead of bits.
    Reference {
        /// Rays per pixel (1..=65,535).
        rays: u32,
    },
}

impl Tracer {
    /// Pixels per side of the square a vector (or invocation group) works on:
    /// the unit of the pass's chunks and suspended state.
    pub fn unit(self) -> u32 {
        match self {
            Tracer::Mft => 4,
            _ => 1,
        }
    }

    /// Rays traced per pixel.
    pub fn rays_per_pixel(self) -> u32 {
        match self {
            Tracer::Reference { rays } => rays,
            _ => 16,
        }
    }

    /// The kernel file under `shaders/`.
    pub fn kernel(self) -> &'static str {
        match self {
            Tracer::Mft => "shadow_mft",
            Tracer::Packet => "shadow_packet",
            Tracer::PerRay | Tracer::Reference { .. } => "shadow_per_ray",
            Tracer::RayQuery => "shadow_ray_query",
        }
    }

    /// Whether the kernel is built on the 16-wide vector (and so has a vector variant).
    pub fn uses_vector(self) -> bool {
        matches!(self, Tracer::Mft | Tracer::Packet)
    }
}

impl fmt::Display for Tracer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Tracer::Mft => f.write_str("mft"),
            Tracer::Packet => f.write_str("packet"),
            Tracer::PerRay => f.write_str("per-ray"),
            Tracer::RayQuery => f.write_str("ray-query"),
            Tracer::Reference { rays } if *rays == DEFAULT_REFERENCE_RAYS => f.write_str("reference"),
            Tracer::Reference { rays } => write!(f, "reference:{rays}"),
        }
    }
}

/// Parses `mft`, `packet`, `per-ray`, `ray-query`, `reference` or `reference:N`.
impl FromStr for Tracer {
    type Err = String;

    fn from_str(s: &str) -> Result<Tracer, String> {
        match s {
            "mft" => Ok(Tracer::Mft),
            "packet" => Ok(Tracer::Packet),
            "per-ray" => Ok(Tracer::PerRay),
            "ray-query" => Ok(Tracer::RayQuery),
            "reference" => Ok(Tracer::Reference {
                rays: DEFAULT_REFERENCE_RAYS,
            }),
            _ => match s.strip_prefix("reference:").map(str::parse::<u32>) {
                Some(Ok(rays)) if (1..=65_535).contains(&rays) => Ok(Tracer::Reference { rays }),
                Some(_) => Err(format!("`{s}`: reference rays must be a number in 1..=65535")),
                None => Err(format!(
                    "unknown tracer `{s}`; expected mft, packet, per-ray, ray-query, reference or reference:N"
                )),
            },
        }
    }
}

/// How the kernel spends the vector's 16 lanes on a leaf triangle (DESIGN.md, "MFT in
/// WGSL"). Both give the same masks bit for bit; only the speed differs.
///
/// `PerLane` is the default because it is the faster one on lavapipe, by 1.2–2.2×.
/// Shadow pass, GPU ms, min / median of 3 runs (Mrays/s at the median), 256×256,
/// `penumbra render`, Mesa 22.3.6 lavapipe on 2 AVX-512 cores (measured before the per-lane
/// form took two triangles per loop step, which made it faster still):
///
/// | scene, vector                          | per-lane          | transposed        |
/// |----------------------------------------|-------------------|-------------------|
/// | Sponza atrium (1.01 M rays), subgroup  | 378 / 415 (2.44)  | 898 / 903 (1.12)  |
/// | lattice (0.67 M rays), subgroup        | 205 / 205 (3.25)  | 247 / 252 (2.64)  |
/// | Sponza atrium, workgroup               | 3053 / 3442 (0.29)| 6783 / 6976 (0.15)|
/// | lattice, workgroup                     | 1163 / 1187 (0.56)| 1798 / 1829 (0.36)|
///
/// (subgroup: `LP_NATIVE_VECTOR_WIDTH=512`, 16-wide subgroups; workgroup: the default
/// 8-wide build.) Lavapipe loads memory one lane at a time, so the transposed form
/// pays two gathers (an origin, a light point) per surviving frustum where the per-lane
/// form reuses the samples' light coordinates held in registers; and its ballots cost barriers in the
/// workgroup vector. On a GPU, whose loads and ballots are cheap, the balance may differ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LeafMode {
    /// Lane `j` culls the triangle against its own frustum and, if it survives, tests the
    /// frustum's 16 rays itself (unrolled): no cross-lane traffic, up to two triangles per
    /// loop step.
    #[default]
    PerLane,
    /// The paper's form: lane `j` only culls; then for each frustum `f` that survives (a
    /// ballot, bit-scanned lowest first, in an inner loop whose every pass counts towards
    /// the iteration budget) lane `i` tests ray `i` of `f`, from `f`'s origin in workgroup
    /// memory, and a ballot of the hits is OR-ed into `f`'s mask.
    Transposed,
}

impl std::fmt::Display for LeafMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LeafMode::PerLane => "per-lane",
            LeafMode::Transposed => "transposed",
        })
    }
}

/// What a shadow tracer is built with besides the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TracerOptions {
    /// The tracer.
    pub tracer: Tracer,
    /// Force a vector variant, or `None` for the adapter's best (vector tracers only).
    pub variant: Option<VectorVariant>,
    /// How the MFT kernel's leaves use the lanes.
    pub leaf_mode: LeafMode,
    /// Count work as Table 1 does (MFT and packet; see [`crate::contract::counters::Counters`]). Off, the kernels
    /// are compiled without the counting code.
    pub counters: bool,
    /// MFT: shrink frusta to their own samples at the start and after leaves that
    /// blocked rays (the paper's "CR", §5.3; see
    /// [`crate::reference::shadow_mft::Frustum::shrink_to`]). Same masks, fewer triangle
    /// tests, a little more work per leaf. On by default: on Sponza's atrium at
    /// 1024×1024 it cuts the triangle tests 11× and the shadow pass takes 0.3×
    /// the time (`penumbra bench --without-cr`).
    pub shrink: bool,
}

impl Default for TracerOptions {
    fn default() -> TracerOptions {
        TracerOptions {
            tracer: Tracer::default(),
            variant: None,
            leaf_mode: LeafMode::default(),
            counters: false,
            shrink: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for t in [
            Tracer::Mft,
            Tracer::Packet,
            Tracer::PerRay,
            Tracer::RayQuery,
            Tracer::Reference { rays: 256 },
            Tracer::Reference { rays: 64 },
        ] {
            assert_eq!(t.to_string().parse::<Tracer>(), Ok(t));
        }
        assert!("reference:0".parse::<Tracer>().is_err());
        assert!("frusta".parse::<Tracer>().unwrap_err().contains("unknown tracer"));
    }
}
