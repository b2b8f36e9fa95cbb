//! Workgroup sizes of the non-vector kernels (`shaders/shared/groups.wgsl`): the host
//! dispatches in these units, and each kernel declares its `@workgroup_size` in them.

/// Side of the square workgroups of the per-pixel kernels (one invocation per pixel):
/// the host dispatches `ceil(width / PIXEL_GROUP) × ceil(height / PIXEL_GROUP)` of them.
pub const PIXEL_GROUP: u32 = 8;

/// Invocations of the one-dimensional workgroups (the per-ray and ray-query shadow kernels' rays, the
/// refinement's list slots, the self-test's nodes).
pub const LINE_GROUP: u32 = 64;

/// Most 16-wide vectors one workgroup of the workgroup vector variant holds
/// (`shaders/shared/vec16_workgroup.wgsl`, which sizes its exchange slots by it; the
/// host's `VEC16_PER_WG` never exceeds it): 4, a 64-invocation workgroup.
pub const MAX_VEC16_PER_WG: u32 = 4;

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
    ("gpu_selftest", [LINE_GROUP, 1, 1]),
    ("refine_resolve", [LINE_GROUP, 1, 1]),
    ("shadow_per_ray", [LINE_GROUP, 1, 1]),
    ("shadow_ray_query", [LINE_GROUP, 1, 1]),
];

#[cfg(test)]
mod tests {
    /// Every non-vector kernel's `@workgroup_size` is the one [`super::KERNEL_GROUPS`] gives
    /// it, so the host's dispatch arithmetic (in units of [`super::PIXEL_GROUP`] and
    /// [`super::LINE_GROUP`]) covers each pixel, ray and slot once; and every kernel is
    /// either listed or a 16-wide vector kernel (whose size the vector variant sets).
    #[test]
    fn kernels_declare_the_workgroup_sizes_the_host_dispatches() {
        const VECTOR_KERNELS: [&str; 3] = ["primary_mft", "shadow_mft", "shadow_packet"];
        for &(kernel, _) in crate::shaders::KERNELS {
            assert!(
                super::KERNEL_GROUPS.iter().any(|&(k, _)| k == kernel) || VECTOR_KERNELS.contains(&kernel),
                "{kernel} is neither in KERNEL_GROUPS nor a vector kernel"
            );
        }
        for &(kernel, size) in super::KERNEL_GROUPS {
            let module =
                naga::front::wgsl::parse_str(&crate::shaders::assemble(kernel, &[]).unwrap()).unwrap();
            let entry = module.entry_points.iter().find(|e| e.name == "main").unwrap();
            assert_eq!(entry.workgroup_size, size, "{kernel}");
        }
    }
}
