//! The contract between the GPU passes ([`crate::gpu`]) and their CPU twins
//! ([`crate::reference`]): everything a kernel shares with Rust. Both sides take it from
//! here and neither from the other. One file per shared WGSL module (`alpha`, `bvh`, `counters`,
//! `groups`, `intersect`, `layout` — the `#[repr(C)]` structs —, `suspend`, and
//! `filter` for `shared/filter_window`), one per kernel family for the uniform builders and
//! the kernels' own constants (`primary`, `refine`, `shade`, `shadow`). Naga tests check
//! the structs' layouts ([`layout`]) and every WGSL constant of every kernel variant
//! against its Rust value (below).

pub mod alpha;
pub mod bvh;
pub mod counters;
pub mod filter;
pub mod groups;
pub mod intersect;
pub mod layout;
pub mod primary;
pub mod refine;
pub mod shade;
pub mod shadow;
pub mod suspend;

/// Loop iterations a vector (or ray) runs per dispatch before it suspends (shadow
/// kernels) or stops and reports its pixels (primary kernels); below lavapipe's
/// 65,535-iteration loop limit with room for the kernels' other loops: the MFT shadow
/// kernel adds at most 64 each to read and to save a stack of 64 (60,128 in all; its
/// per-sample setup and its side planes are unrolled, so setting up and shrinking loop
/// nowhere). A loop that ends early all the same is reported ([`crate::Error::LoopCut`]).
pub const ITERATION_BUDGET: u32 = 60_000;

#[cfg(test)]
mod tests {
    /// Every WGSL constant whose value Rust also uses, with Rust's value: one per shared
    /// WGSL module's file of this module, then the kernels' own.
    fn rust_values() -> Vec<(&'static str, naga::Literal)> {
        use super::*;
        use naga::Literal::{F32, U32};
        let u = |v: usize| U32(v as u32);
        vec![
            // shared/alpha
            ("ALPHA_OPAQUE", U32(alpha::OPAQUE)),
            // shared/bvh, shared/bvh_vec16
            ("STACK_SIZE", u(bvh::STACK_SIZE)),
            ("NODE_WORDS", u(bvh::NODE_WORDS)),
            ("TRIANGLE_WORDS", u(bvh::TRIANGLE_WORDS)),
            // shared/counters
            ("WORD_STATUS", u(counters::WORD_STATUS)),
            ("WORD_NODES_VISITED", u(counters::WORD_NODES_VISITED)),
            ("WORD_BOX_TESTS", u(counters::WORD_BOX_TESTS)),
            ("WORD_TRIANGLES_ACCESSED", u(counters::WORD_TRIANGLES_ACCESSED)),
            (
                "WORD_TRIANGLES_AFTER_CULLING",
                u(counters::WORD_TRIANGLES_AFTER_CULLING),
            ),
            ("WORD_TRIANGLE_TESTS", u(counters::WORD_TRIANGLE_TESTS)),
            ("WORD_LOOP_CUT", u(counters::WORD_LOOP_CUT)),
            // shared/filter_window, filter
            ("FULL_WINDOW", U32(filter::FULL_WINDOW)),
            (
                "FILTER_PIXELS_PER_INVOCATION",
                U32(filter::FILTER_PIXELS_PER_INVOCATION),
            ),
            // shared/groups
            ("PIXEL_GROUP", U32(groups::PIXEL_GROUP)),
            ("LINE_GROUP", U32(groups::LINE_GROUP)),
            ("MAX_VEC16_PER_WG", U32(groups::MAX_VEC16_PER_WG)),
            // shared/intersect
            ("BOX_EXIT_SCALE", F32(intersect::BOX_EXIT_SCALE)),
            // shared/layout, shared/surface
            ("MASK_FULL", U32(layout::MASK_FULL)),
            ("MASK_SKY", U32(layout::MASK_SKY)),
            ("ORIGIN_OFFSET_ULPS", F32(layout::ORIGIN_OFFSET_ULPS)),
            ("UNKNOWN_TRIANGLE", U32(layout::GBufferTexel::UNKNOWN_TRIANGLE)),
            ("NORMALS_BIASED", U32(layout::NORMALS_BIASED)),
            // shared/suspend
            ("ST_STATUS", u(suspend::ST_STATUS)),
            ("ST_LANES", u(suspend::ST_LANES)),
            ("ST_STACK_NODE", u(suspend::ST_STACK_NODE)),
            ("ST_STACK_MASK", u(suspend::ST_STACK_MASK)),
            ("STATUS_SUSPENDED", U32(suspend::STATUS_SUSPENDED)),
            ("STACK_COUNT_SHIFT", U32(suspend::STACK_COUNT_SHIFT)),
            // primary_mft
            ("DEPTH_SLACK", F32(primary::DEPTH_SLACK)),
            ("T_NONE", F32(primary::T_NONE)),
            ("NO_TRIANGLE", U32(layout::GBufferTexel::NO_TRIANGLE)),
            // shade
            ("PI", F32(std::f32::consts::PI)),
            // shadow_mft
            ("STATE_WORDS", u(shadow::STATE_WORDS)),
            ("ST_CAND", u(shadow::ST_CAND)),
            ("ST_LEAF_MASK", u(shadow::ST_LEAF_MASK)),
            ("ST_PENDING", u(shadow::ST_PENDING)),
            ("ST_SHRUNK", u(shadow::ST_SHRUNK)),
            ("SHRINK_FLAG", U32(shadow::SHRINK_FLAG)),
            ("SHRINK_MARGIN", F32(shadow::SHRINK_MARGIN)),
            ("BOUNDS_PAD", F32(shadow::BOUNDS_PAD)),
            ("LIGHT_SAMPLES", u(crate::sampling::SAMPLES)),
            // shadow_packet
            ("PACKET_STATE_WORDS", u(shadow::PACKET_STATE_WORDS)),
        ]
    }

    /// WGSL constants no Rust code uses, and why.
    const WGSL_ONLY: &[(&str, &str)] = &[
        (
            "TESTED",
            "shadow_mft's flag on a leaf test's result word; the twin returns a pair",
        ),
        (
            "VEC16_LANE_WORDS",
            "which shared/vec16 implementation was imported; Rust picks it by alias",
        ),
        (
            "VEC16_WG_SIZE",
            "the workgroup vector's 16 invocations; the host reads it from the variant",
        ),
    ];

    /// Each constant of each kernel variant (its own and its imports') is either Rust's
    /// value of the same name or listed as WGSL-only, and each of Rust's values is declared
    /// by some kernel: a constant changed on one side, or a new one shared without a
    /// Rust twin, fails here naming the kernel.
    #[test]
    fn every_wgsl_constant_has_rusts_value_in_every_kernel_variant() {
        let rust = rust_values();
        let mut seen = std::collections::BTreeSet::new();
        for &(kernel, variants) in crate::shaders::KERNELS {
            for &aliases in variants {
                let wgsl = crate::shaders::assemble(kernel, aliases).unwrap();
                let module = naga::front::wgsl::parse_str(&wgsl).unwrap();
                for (_, c) in module.constants.iter() {
                    let Some(name) = c.name.as_deref() else { continue };
                    let naga::Expression::Literal(value) = module.global_expressions[c.init] else {
                        panic!("{kernel}: {name} is not a literal")
                    };
                    if let Some(&(_, expected)) = rust.iter().find(|(n, _)| *n == name) {
                        assert_eq!(value, expected, "{kernel} with {aliases:?}: {name}");
                        seen.insert(name.to_string());
                    } else {
                        assert!(
                            WGSL_ONLY.iter().any(|(n, _)| *n == name),
                            "{kernel}: constant {name} is neither in rust_values() nor in WGSL_ONLY"
                        );
                    }
                }
            }
        }
        for (name, _) in &rust {
            assert!(seen.contains(*name), "no kernel declares {name}");
        }
    }
}
