//! How the kernels' 16-wide vector is made from invocations (DESIGN.md), and which
//! variant an adapter runs; shared by the shadow and the primary multi-frusta kernels.

use super::AdapterSummary;
use crate::contract::groups::MAX_VEC16_PER_WG;
use crate::{Error, Result};

/// How the kernel's 16-wide vector is built from invocations (DESIGN.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VectorVariant {
    /// 16 lanes of a subgroup; needs subgroups of a fixed size that is a multiple of 16.
    /// Lanes share BVH words by broadcasts.
    Subgroup,
    /// As [`VectorVariant::Subgroup`], but with one vector per subgroup the lanes share
    /// BVH words by reductions (`shared/vec16_subgroup`'s `VEC16_WORDS_BY_REDUCTION`):
    /// the choice for lavapipe from Mesa 24.3 on (see [`VectorVariant::choose`]).
    SubgroupReduce,
    /// A 16-invocation workgroup exchanging through workgroup memory; works everywhere.
    /// The choice for a CPU (lavapipe), which runs a workgroup as a loop over its
    /// invocations.
    Workgroup,
    /// Four vectors in a 64-invocation workgroup, otherwise as [`VectorVariant::Workgroup`]
    /// (the same kernels): the choice for a GPU without fixed 16k-wide subgroups, whose
    /// 32- or 64-wide warps a 16-invocation workgroup would fill a half or a quarter of.
    Workgroup4,
}

impl std::fmt::Display for VectorVariant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            VectorVariant::Subgroup => "subgroup",
            VectorVariant::SubgroupReduce => "subgroup-reduce",
            VectorVariant::Workgroup => "workgroup",
            VectorVariant::Workgroup4 => "workgroup4",
        })
    }
}

impl VectorVariant {
    /// The variant for an adapter: `forced` if given (an error when the adapter cannot run it),
    /// else subgroups when they are a fixed multiple of 16 wide, else workgroups of one
    /// vector on a CPU and of four elsewhere. Returns the variant and the number of
    /// vectors per workgroup (the kernels' `VEC16_PER_WG`).
    ///
    /// Subgroups share words by reductions on lavapipe from Mesa 24.3 on and by broadcasts
    /// elsewhere (`reductions_share_words_faster`); both give the same bits.
    pub fn choose(info: &AdapterSummary, forced: Option<VectorVariant>) -> Result<(VectorVariant, u32)> {
        let size = info.subgroup_min_size;
        let subgroup_ok = info.has_subgroups
            && info.subgroup_min_size == info.subgroup_max_size
            && size.is_multiple_of(16)
            && (16..=64).contains(&size);
        match forced {
            Some(VectorVariant::Workgroup) => Ok((VectorVariant::Workgroup, 1)),
            Some(VectorVariant::Workgroup4) => Ok((VectorVariant::Workgroup4, MAX_VEC16_PER_WG)),
            Some(v @ (VectorVariant::Subgroup | VectorVariant::SubgroupReduce)) if !subgroup_ok => {
                Err(Error::Gpu(format!(
                    "the {v} vector needs subgroups of one fixed size that is a multiple of 16; \
                 {} has {}subgroups of {}..{} lanes (on lavapipe set LP_NATIVE_VECTOR_WIDTH=512 \
                 for 16-wide subgroups, or use --vector workgroup)",
                    info.name,
                    if info.has_subgroups { "" } else { "no " },
                    info.subgroup_min_size,
                    info.subgroup_max_size
                )))
            }
            Some(v @ (VectorVariant::Subgroup | VectorVariant::SubgroupReduce)) => Ok((v, size / 16)),
            None if subgroup_ok && reductions_share_words_faster(info) => {
                Ok((VectorVariant::SubgroupReduce, size / 16))
            }
            None if subgroup_ok => Ok((VectorVariant::Subgroup, size / 16)),
            None if info.device_type == wgpu::DeviceType::Cpu => Ok((VectorVariant::Workgroup, 1)),
            None => Ok((VectorVariant::Workgroup4, MAX_VEC16_PER_WG)),
        }
    }

    /// The kernel alias that selects this variant's implementation of `shared/vec16`.
    pub(crate) fn aliases(self) -> &'static [(&'static str, &'static str)] {
        match self {
            VectorVariant::Subgroup | VectorVariant::SubgroupReduce => {
                &[("shared/vec16", "shared/vec16_subgroup")]
            }
            VectorVariant::Workgroup | VectorVariant::Workgroup4 => {
                &[("shared/vec16", "shared/vec16_workgroup")]
            }
        }
    }

    /// Whether the variant's vector lives in one subgroup (needs `Features::SUBGROUP`).
    pub fn uses_subgroups(self) -> bool {
        matches!(self, VectorVariant::Subgroup | VectorVariant::SubgroupReduce)
    }

    /// The kernels' override constants for this variant with `per_wg` vectors per
    /// workgroup: `VEC16_PER_WG`, and for subgroups `VEC16_WORDS_BY_REDUCTION`.
    pub(crate) fn constants(self, per_wg: u32) -> Vec<(&'static str, f64)> {
        let mut c = vec![("VEC16_PER_WG", f64::from(per_wg))];
        if self.uses_subgroups() {
            let reduce = self == VectorVariant::SubgroupReduce;
            c.push(("VEC16_WORDS_BY_REDUCTION", f64::from(u8::from(reduce))));
        }
        c
    }
}

/// Whether lanes of a subgroup vector share words faster by reductions than by broadcasts:
/// on lavapipe from Mesa 24.3 on. naga writes `subgroupBroadcast` as a SPIR-V shuffle, which
/// lavapipe runs at 16 lanes as a loop over the lanes; since Mesa 24.3 its reductions are
/// unrolled at compile time (commit dfa314e805e, "lavapipe: Implement clustered
/// reductions"). Measured (Sponza atrium, 1024², MFT shadow pass): reductions 2.0× (AVX-512
/// code) and 4.0× (AVX2 code) faster on Mesa 25.0.7, 1.5–2.3× slower on Mesa 22.3.6. Mesa
/// 23.0–24.2 were not measured; nor were GPUs, which keep broadcasts.
pub fn reductions_share_words_faster(info: &AdapterSummary) -> bool {
    info.driver == "llvmpipe" && mesa_version(&info.driver_info).is_some_and(|v| v >= (24, 3))
}

/// The major and minor version in a Mesa driver string such as
/// `Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)`.
fn mesa_version(driver_info: &str) -> Option<(u32, u32)> {
    let rest = &driver_info[driver_info.find("Mesa ")? + 5..];
    let mut parts = rest.split(|c: char| !c.is_ascii_digit());
    let major = parts.next()?.parse().ok()?;
    let minor = parts.next()?.parse().ok()?;
    Some((major, minor))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mesa_version_reads_the_driver_strings_of_both_lavapipes() {
        assert_eq!(mesa_version("Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)"), Some((25, 0)));
        assert_eq!(mesa_version("Mesa 22.3.6 (LLVM 15.0.6)"), Some((22, 3)));
        assert_eq!(mesa_version("Mesa 24.3.0-devel (git-1234)"), Some((24, 3)));
        assert_eq!(mesa_version("NVIDIA 550.54"), None);
        assert_eq!(mesa_version("Mesa 25"), None);
        assert_eq!(mesa_version("Mesa "), None);
    }

    fn lavapipe(driver_info: &str, subgroup_size: u32) -> AdapterSummary {
        AdapterSummary {
            name: "llvmpipe (LLVM 15.0.6, 512 bits)".into(),
            backend: wgpu::Backend::Vulkan,
            device_type: wgpu::DeviceType::Cpu,
            driver: "llvmpipe".into(),
            driver_info: driver_info.into(),
            subgroup_min_size: subgroup_size,
            subgroup_max_size: subgroup_size,
            has_subgroups: true,
            has_timestamps: true,
            max_storage_buffer_binding_size: 1 << 30,
            max_compute_workgroups_per_dimension: 65535,
        }
    }

    #[test]
    fn lavapipe_gets_reductions_from_mesa_24_3_and_broadcasts_before() {
        let choose = |info: &str, size| VectorVariant::choose(&lavapipe(info, size), None).unwrap();
        let new = "Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)";
        assert_eq!(choose(new, 16), (VectorVariant::SubgroupReduce, 1));
        assert_eq!(choose("Mesa 24.3.1", 16), (VectorVariant::SubgroupReduce, 1));
        assert_eq!(choose("Mesa 24.2.8", 16), (VectorVariant::Subgroup, 1));
        assert_eq!(
            choose("Mesa 22.3.6 (LLVM 15.0.6)", 16),
            (VectorVariant::Subgroup, 1)
        );
        // 8-wide subgroups cannot hold a vector; forcing still works where they can.
        assert_eq!(choose(new, 8), (VectorVariant::Workgroup, 1));
        let forced = VectorVariant::choose(&lavapipe(new, 16), Some(VectorVariant::Subgroup));
        assert_eq!(forced.unwrap(), (VectorVariant::Subgroup, 1));
        assert!(VectorVariant::choose(&lavapipe(new, 8), Some(VectorVariant::SubgroupReduce)).is_err());
    }
}
