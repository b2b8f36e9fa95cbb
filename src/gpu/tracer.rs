//! Which shadow tracer a pass runs: multi-frusta tracing or one of the baselines
//! it is measured against.

use std::fmt;
use std::str::FromStr;

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
            Tracer::Reference { rays } if *rays == DEFAULT_REFERENCE_RAYS => f.write_str("reference"),
            Tracer::Reference { rays } => write!(f, "reference:{rays}"),
        }
    }
}

/// Parses `mft`, `packet`, `per-ray`, `reference` or `reference:N`.
impl FromStr for Tracer {
    type Err = String;

    fn from_str(s: &str) -> Result<Tracer, String> {
        match s {
            "mft" => Ok(Tracer::Mft),
            "packet" => Ok(Tracer::Packet),
            "per-ray" => Ok(Tracer::PerRay),
            "reference" => Ok(Tracer::Reference {
                rays: DEFAULT_REFERENCE_RAYS,
            }),
            _ => match s.strip_prefix("reference:").map(str::parse::<u32>) {
                Some(Ok(rays)) if (1..=65_535).contains(&rays) => Ok(Tracer::Reference { rays }),
                Some(_) => Err(format!("`{s}`: reference rays must be a number in 1..=65535")),
                None => Err(format!(
                    "unknown tracer `{s}`; expected mft, packet, per-ray, reference or reference:N"
                )),
            },
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
            Tracer::Reference { rays: 256 },
            Tracer::Reference { rays: 64 },
        ] {
            assert_eq!(t.to_string().parse::<Tracer>(), Ok(t));
        }
        assert!("reference:0".parse::<Tracer>().is_err());
        assert!("frusta".parse::<Tracer>().unwrap_err().contains("unknown tracer"));
    }
}
