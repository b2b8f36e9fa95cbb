//! How the kernels' 16-wide vector is made from invocations (DESIGN.md), and which
//! variant an adapter runs; shared by the shadow and the primary multi-frusta kernels.

use super::AdapterSummary;
use crate::contract::groups::MAX_VEC16_PER_WG;
use crate::{Error, Result};

/// How the kernel's 16-wide vector is built from invocations (DESIGN.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VectorVariant {
    /// 16 lanes of a subgroup; needs subgroups of a fixed size that is a multiple of 16.
    Subgroup,
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
    pub fn choose(info: &AdapterSummary, forced: Option<VectorVariant>) -> Result<(VectorVariant, u32)> {
        let size = info.subgroup_min_size;
        let subgroup_ok = info.has_subgroups
            && info.subgroup_min_size == info.subgroup_max_size
            && size.is_multiple_of(16)
            && (16..=64).contains(&size);
        match forced {
            Some(VectorVariant::Workgroup) => Ok((VectorVariant::Workgroup, 1)),
            Some(VectorVariant::Workgroup4) => Ok((VectorVariant::Workgroup4, MAX_VEC16_PER_WG)),
            Some(VectorVariant::Subgroup) if !subgroup_ok => Err(Error::Gpu(format!(
                "the subgroup vector needs subgroups of one fixed size that is a multiple of 16; \
                 {} has {}subgroups of {}..{} lanes (on lavapipe set LP_NATIVE_VECTOR_WIDTH=512 \
                 for 16-wide subgroups, or use --vector workgroup)",
                info.name,
                if info.has_subgroups { "" } else { "no " },
                info.subgroup_min_size,
                info.subgroup_max_size
            ))),
            Some(VectorVariant::Subgroup) => Ok((VectorVariant::Subgroup, size / 16)),
            None if subgroup_ok => Ok((VectorVariant::Subgroup, size / 16)),
            None if info.device_type == wgpu::DeviceType::Cpu => Ok((VectorVariant::Workgroup, 1)),
            None => Ok((VectorVariant::Workgroup4, MAX_VEC16_PER_WG)),
        }
    }

    /// The kernel alias that selects this variant's implementation of `shared/vec16`.
    pub(crate) fn aliases(self) -> &'static [(&'static str, &'static str)] {
        match self {
            VectorVariant::Subgroup => &[("shared/vec16", "shared/vec16_subgroup")],
            VectorVariant::Workgroup | VectorVariant::Workgroup4 => {
                &[("shared/vec16", "shared/vec16_workgroup")]
            }
        }
    }
}
