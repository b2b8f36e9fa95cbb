//! The contract between the GPU passes ([`crate::gpu`]) and their CPU twins
//! ([`crate::reference`]): the uniform builders and constants a kernel shares with Rust,
//! one file per kernel family. Both sides take them from here and neither from the other;
//! the `#[repr(C)]` structs are in [`crate::contract::layout`] and the status words in
//! [`crate::contract::counters`]. Tests check the WGSL side of each constant with naga.

pub mod counters;
pub mod filter;
pub mod layout;
pub mod primary;
pub mod refine;
pub mod shade;
pub mod shadow;

/// Loop iterations a vector (or ray) runs per dispatch before it suspends (shadow
/// kernels) or stops and reports its pixels (primary kernels); below lavapipe's
/// 65,535-iteration loop limit with room for the kernels' other loops: the MFT shadow
/// kernel adds 16 (the samples below the horizon) and at most 64 each to read and to save
/// a stack of 64 (60,144 in all; its side-plane setup is unrolled, so shrinking loops
/// nowhere). A loop that ends early all the same is reported ([`crate::Error::LoopCut`]).
pub const ITERATION_BUDGET: u32 = 60_000;

/// Depth of every kernel's traversal stack (`STACK_SIZE` in the kernels); a BVH deeper
/// than this cannot be traced ([`crate::gpu::validate_for_gpu`]).
pub const STACK_SIZE: usize = 64;

/// Side of the square workgroups of the per-pixel kernels (one invocation per pixel):
/// the host dispatches `ceil(width / PIXEL_GROUP) × ceil(height / PIXEL_GROUP)` of them.
pub const PIXEL_GROUP: u32 = 8;

/// Invocations of the one-dimensional workgroups (the per-ray shadow kernel's rays, the
/// refinement's list slots).
pub const LINE_GROUP: u32 = 64;

/// The workgroup size each non-vector kernel declares (`@workgroup_size`), which the
/// host's dispatches assume (checked by a naga test).
pub const KERNEL_GROUPS: &[(&str, [u32; 3])] = &[
    ("filter", [PIXEL_GROUP, PIXEL_GROUP, 1]),
    ("gbuffer_from_depth", [PIXEL_GROUP, PIXEL_GROUP, 1]),
    ("gbuffer_from_position", [PIXEL_GROUP, PIXEL_GROUP, 1]),
    ("primary", [PIXEL_GROUP, PIXEL_GROUP, 1]),
    ("refine_gather", [PIXEL_GROUP, PIXEL_GROUP, 1]),
    ("refine_select", [PIXEL_GROUP, PIXEL_GROUP, 1]),
    ("shade", [PIXEL_GROUP, PIXEL_GROUP, 1]),
    ("visibility_to_texture", [PIXEL_GROUP, PIXEL_GROUP, 1]),
    ("visibility_values", [PIXEL_GROUP, PIXEL_GROUP, 1]),
    ("refine_resolve", [LINE_GROUP, 1, 1]),
    ("shadow_per_ray", [LINE_GROUP, 1, 1]),
];

#[cfg(test)]
pub(crate) mod tests {
    /// Every non-vector kernel's `@workgroup_size` is the one [`super::KERNEL_GROUPS`] gives
    /// it, so the host's dispatch arithmetic (in units of [`super::PIXEL_GROUP`] and
    /// [`super::LINE_GROUP`]) covers each pixel, ray and slot once.
    #[test]
    fn kernels_declare_the_workgroup_sizes_the_host_dispatches() {
        for &(kernel, size) in super::KERNEL_GROUPS {
            let module =
                naga::front::wgsl::parse_str(&crate::shaders::assemble(kernel, &[]).unwrap()).unwrap();
            let entry = module.entry_points.iter().find(|e| e.name == "main").unwrap();
            assert_eq!(entry.workgroup_size, size, "{kernel}");
        }
    }

    /// The value of WGSL constant `name` in `kernel` (assembled with `aliases`), if it has one.
    pub(crate) fn wgsl_constant_if_any(
        kernel: &str,
        aliases: &[(&str, &str)],
        name: &str,
    ) -> Option<naga::Literal> {
        let module =
            naga::front::wgsl::parse_str(&crate::shaders::assemble(kernel, aliases).unwrap()).unwrap();
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))?;
        match module.global_expressions[c.init] {
            naga::Expression::Literal(l) => Some(l),
            ref other => panic!("{kernel}: {name} = {other:?}"),
        }
    }

    /// [`wgsl_constant_if_any`], which must exist.
    pub(crate) fn wgsl_constant(kernel: &str, aliases: &[(&str, &str)], name: &str) -> naga::Literal {
        wgsl_constant_if_any(kernel, aliases, name).unwrap_or_else(|| panic!("{kernel}: no constant {name}"))
    }

    /// Every kernel variant that declares one of the shared constants declares the value
    /// Rust uses (the stack depth, the sky and full masks, the status word of loop cuts).
    #[test]
    fn every_kernel_declares_the_shared_constants_as_rust_does() {
        use naga::Literal::U32;
        let shared = [
            ("STACK_SIZE", super::STACK_SIZE as u32),
            ("MASK_SKY", super::shadow::MASK_SKY),
            ("MASK_FULL", super::shadow::MASK_FULL),
            ("WORD_LOOP_CUT", crate::contract::counters::WORD_LOOP_CUT as u32),
            ("WORD_STATUS", crate::contract::counters::WORD_STATUS as u32),
        ];
        let mut checked = 0;
        for &(kernel, variants) in crate::shaders::KERNELS {
            for &aliases in variants {
                for (name, value) in shared {
                    if let Some(v) = wgsl_constant_if_any(kernel, aliases, name) {
                        assert_eq!(v, U32(value), "{kernel} with {aliases:?}: {name}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(
            checked >= 20,
            "only {checked} constants found: the kernels' names changed?"
        );
    }
}
