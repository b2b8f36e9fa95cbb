//! Every struct the CPU and the GPU share, in one place.
//!
//! Each is `#[repr(C)]` + [`bytemuck::Pod`] with a compile-time size check; its
//! WGSL twin in `shaders/shared/` has the same name and member names, and a
//! test parses the WGSL with naga and compares sizes and member offsets.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// One node of the flattened BVH, 32 bytes (WGSL `BvhNode` in `shaders/shared/bvh.wgsl`).
///
/// Inner node (`count == 0`): the children are nodes `first` and `first + 1`,
/// adjacent so one 64-byte read brings both boxes. Leaf (`count > 0`): the
/// triangles `first .. first + count` of [`crate::bvh::Bvh::triangles`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// Box minimum (bytes 0..12).
    pub bmin: Vec3,
    /// First child node (inner) or first triangle (leaf) (bytes 12..16).
    pub first: u32,
    /// Box maximum (bytes 16..28).
    pub bmax: Vec3,
    /// Number of triangles; 0 marks an inner node (bytes 28..32).
    pub count: u32,
}

/// One triangle in the form the intersection test reads, 48 bytes
/// (WGSL `BvhTriangle`): corner `v0` and edges `e1 = v1 - v0`, `e2 = v2 - v0`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhTriangle {
    /// Corner 0 (bytes 0..12).
    pub v0: Vec3,
    /// Index of this triangle in [`crate::scene::Scene::triangles`] (bytes 12..16).
    pub scene_index: u32,
    /// Corner 1 − corner 0 (bytes 16..28).
    pub e1: Vec3,
    /// Unused (bytes 28..32).
    pub pad1: u32,
    /// Corner 2 − corner 0 (bytes 32..44).
    pub e2: Vec3,
    /// Unused (bytes 44..48).
    pub pad2: u32,
}

const _: () = assert!(size_of::<BvhNode>() == 32);
const _: () = assert!(size_of::<BvhTriangle>() == 48);

impl BvhNode {
    /// True for a leaf (it holds triangles).
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// WGSL source of the BVH structs.
pub const BVH_WGSL: &str = include_str!("../shaders/shared/bvh.wgsl");

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::offset_of;

    /// Size and `(member, offset)` list of the WGSL struct `name` as naga lays it out.
    fn wgsl_layout(source: &str, name: &str) -> (u32, Vec<(String, u32)>) {
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|e| panic!("WGSL does not parse:\n{}", e.emit_to_string(source)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("WGSL does not validate: {e:?}"));
        let ty = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no struct {name} in the WGSL"))
            .1;
        match &ty.inner {
            naga::TypeInner::Struct { members, span } => (
                *span,
                members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                    .collect(),
            ),
            other => panic!("{name} is not a struct: {other:?}"),
        }
    }

    fn check(source: &str, name: &str, rust_size: usize, rust_fields: &[(&str, usize)]) {
        let (size, fields) = wgsl_layout(source, name);
        assert_eq!(
            size as usize, rust_size,
            "{name}: WGSL size {size}, Rust size {rust_size}"
        );
        let rust: Vec<(String, u32)> = rust_fields
            .iter()
            .map(|&(n, o)| (n.to_owned(), o as u32))
            .collect();
        assert_eq!(
            fields, rust,
            "{name}: WGSL members (left) differ from Rust fields (right)"
        );
    }

    macro_rules! fields {
        ($ty:ty { $($f:ident),* }) => { &[$((stringify!($f), offset_of!($ty, $f))),*] };
    }

    #[test]
    fn bvh_node_layout_matches_wgsl() {
        check(
            BVH_WGSL,
            "BvhNode",
            size_of::<BvhNode>(),
            fields!(BvhNode {
                bmin,
                first,
                bmax,
                count
            }),
        );
    }

    #[test]
    fn bvh_triangle_layout_matches_wgsl() {
        check(
            BVH_WGSL,
            "BvhTriangle",
            size_of::<BvhTriangle>(),
            fields!(BvhTriangle {
                v0,
                scene_index,
                e1,
                pad1,
                e2,
                pad2
            }),
        );
    }

    #[test]
    fn layout_check_catches_a_mismatch() {
        // The check itself must be able to fail: a WGSL twin with swapped members.
        let wrong = "struct BvhNode { bmin: vec3<f32>, count: u32, bmax: vec3<f32>, first: u32 }";
        let result = std::panic::catch_unwind(|| {
            check(
                wrong,
                "BvhNode",
                size_of::<BvhNode>(),
                fields!(BvhNode {
                    bmin,
                    first,
                    bmax,
                    count
                }),
            )
        });
        assert!(result.is_err());
    }
}
