//! Every struct the CPU and the GPU share, in one place (one concept; long because the
//! naga layout checks of every struct live beside them).
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

/// One triangle, 48 bytes (WGSL `BvhTriangle`): its three corners as the scene gives
/// them. Storing corners (not a corner and two edges, whose sum rounds) keeps the copies
/// of a vertex that several triangles share bit-identical, so the multi-frusta edge
/// functions of a shared edge are exactly negated and no ray slips between the two
/// triangles (`tests/cpu/shadow_mft.rs`, `tests/gpu/shadow_tracers.rs`: the closed room).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhTriangle {
    /// Corner 0 (bytes 0..12).
    pub v0: Vec3,
    /// Index of this triangle in [`crate::scene::Scene::triangles`] (bytes 12..16).
    pub scene_index: u32,
    /// Corner 1 (bytes 16..28).
    pub v1: Vec3,
    /// Where its [`AlphaTriangle`] is in the alpha words ([`crate::bvh::AlphaMasks`]),
    /// [`crate::contract::alpha::OPAQUE`] for a triangle that always blocks: the kernels
    /// look at this word only, so opaque triangles pay no other load (bytes 28..32).
    pub alpha: u32,
    /// Corner 2 (bytes 32..44).
    pub v2: Vec3,
    /// Unused (bytes 44..48).
    pub pad2: u32,
}

/// Shadow mask word of a pixel: all 16 rays blocked (bit j = ray j blocked).
pub const MASK_FULL: u32 = 0xffff;
/// Shadow mask bit that marks a pixel without geometry.
pub const MASK_SKY: u32 = 1 << 16;

/// Shadow-ray origins leave the surface by at least this many steps of f32 (ulps) at
/// the hit point's largest coordinate ([`crate::pass_inputs::shadow_ray_origin`]). A hit
/// point far from the origin is off its triangle's plane by the rounding of `eye + t·dir`
/// (up to a step per coordinate, √3 steps in distance) and the origin adds half a step per
/// coordinate (√3/2): at most ~2.6 steps, so 4 clear it. Measured
/// (`examples/far_from_origin.rs`, playground at 1e6): 2 steps still let a few rays
/// start behind their surface, 4 and 8 none; every step more loses contact shadows
/// within that distance. Near the origin the fixed offset is far larger (within 32 m
/// of it 4 ulps are at most 1.5e-5 m; Sponza's offset is 3.5e-3 m).
pub const ORIGIN_OFFSET_ULPS: f32 = 4.0;

/// One pixel of the G-buffer the primary pass writes and the shadow and
/// shade passes read, 64 bytes (WGSL `GBufferTexel` in `shaders/shared/layout.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GBufferTexel {
    /// Shadow-ray origin: the hit point moved off the surface along
    /// `geo_normal` by the scene's ray offset (bytes 0..12).
    pub origin: Vec3,
    /// Distance from the eye to the hit along the camera ray; 0 when the
    /// pixel sees no geometry (bytes 12..16).
    pub depth: f32,
    /// Unit shading normal, on the side facing the camera (bytes 16..28).
    pub normal: Vec3,
    /// Leaf-order index of the hit triangle; `u32::MAX` when none (bytes 28..32).
    pub triangle: u32,
    /// Unit geometric normal, on the side facing the camera (bytes 32..44).
    pub geo_normal: Vec3,
    /// Unused (bytes 44..48).
    pub pad0: u32,
    /// Linear RGB albedo (bytes 48..60).
    pub albedo: Vec3,
    /// Unused (bytes 60..64).
    pub pad1: u32,
}

impl GBufferTexel {
    /// [`GBufferTexel::triangle`] of a texel made from a host's rasterized G-buffer
    /// ([`crate::gpu::ShadowPass`]): a hit whose triangle is not known.
    pub const UNKNOWN_TRIANGLE: u32 = u32::MAX - 1;
    /// [`GBufferTexel::triangle`] of a texel whose camera ray hit nothing.
    pub const NO_TRIANGLE: u32 = u32::MAX;

    /// True when the camera ray hit geometry.
    pub fn is_hit(&self) -> bool {
        self.depth > 0.0
    }
}

/// Everything the shadow kernels need besides the G-buffer, the BVH and the
/// light points, 112 bytes (WGSL `ShadowParams`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ShadowParams {
    /// The light's corners in order `c, c+u, c+u+v, c+v` (xyz; w unused) (bytes 0..64).
    pub light_corners: [[f32; 4]; 4],
    /// `cross(edge_u, edge_v)`: the light emits to the side it points to (bytes 64..76).
    pub light_normal: Vec3,
    /// Shadow rays end at `t_max` (just short of the light sample at t = 1) (bytes 76..80).
    pub t_max: f32,
    /// Image width in pixels (bytes 80..84).
    pub width: u32,
    /// Image height in pixels (bytes 84..88).
    pub height: u32,
    /// First tile (x) of this dispatch; tiles are 4×4 pixels (bytes 88..92).
    pub tile_origin_x: u32,
    /// First tile (y) of this dispatch (bytes 92..96).
    pub tile_origin_y: u32,
    /// Tiles per row of this dispatch: the suspended-state slot of a tile is
    /// `ty·tiles_x + tx` relative to the dispatch (bytes 96..100).
    pub tiles_x: u32,
    /// 0: start every tile; 1: resume the suspended ones (bytes 100..104).
    pub resume: u32,
    /// Loop iterations a vector may run in one dispatch before it saves its
    /// state and stops (lavapipe ends loops after 65,535) (bytes 104..108).
    pub iteration_budget: u32,
    /// Tile rows of this dispatch (bytes 108..112).
    pub tiles_y: u32,
}

/// Shading data of one triangle, in the same (leaf) order as
/// [`BvhTriangle`], 80 bytes (WGSL `ShadingTriangle`): kept apart so traversal
/// never loads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ShadingTriangle {
    /// Unit shading normal at corner 0 (bytes 0..12).
    pub n0: Vec3,
    /// Index into the material buffer (bytes 12..16).
    pub material: u32,
    /// Unit shading normal at corner 1 (bytes 16..28).
    pub n1: Vec3,
    /// Unused (bytes 28..32).
    pub pad1: u32,
    /// Unit shading normal at corner 2 (bytes 32..44).
    pub n2: Vec3,
    /// Unused (bytes 44..48).
    pub pad2: u32,
    /// TEXCOORD_0 at corner 0 (bytes 48..56).
    pub uv0: glam::Vec2,
    /// TEXCOORD_0 at corner 1 (bytes 56..64).
    pub uv1: glam::Vec2,
    /// TEXCOORD_0 at corner 2 (bytes 64..72).
    pub uv2: glam::Vec2,
    /// Unused (bytes 72..80).
    pub pad3: [u32; 2],
}

/// One material as the primary pass reads it, 32 bytes (WGSL `GpuMaterial`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// Linear RGB base colour factor (bytes 0..12).
    pub base_color: Vec3,
    /// Index of the base colour texture in the texture table, `u32::MAX` for none (bytes 12..16).
    pub texture: u32,
    /// The base colour factor's alpha (bytes 16..20).
    pub alpha_factor: f32,
    /// A camera ray passes an alpha-tested triangle of this material where texel alpha ×
    /// `alpha_factor` is below this (bytes 20..24); the kernels read it only for triangles
    /// whose [`BvhTriangle::alpha`] is not [`crate::contract::alpha::OPAQUE`].
    pub alpha_cutoff: f32,
    /// Unused (bytes 24..32).
    pub pad: [u32; 2],
}

/// The texture coordinates of one alpha-tested triangle and its mask, 32 bytes (WGSL
/// `AlphaTriangle`), in the alpha words at [`BvhTriangle::alpha`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct AlphaTriangle {
    /// TEXCOORD_0 at corner 0 (bytes 0..8).
    pub uv0: glam::Vec2,
    /// TEXCOORD_0 at corner 1 (bytes 8..16).
    pub uv1: glam::Vec2,
    /// TEXCOORD_0 at corner 2 (bytes 16..24).
    pub uv2: glam::Vec2,
    /// Word offset of its [`AlphaMask`] in the alpha words (bytes 24..28).
    pub mask: u32,
    /// Unused (bytes 28..32).
    pub pad: u32,
}

/// One material's coverage, 16 bytes (WGSL `AlphaMask`): one bit per texel of its base
/// colour texture (row-major, row 0 at v = 0), set where texel alpha × factor ≥ cutoff,
/// i.e. where the surface is there and blocks rays.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct AlphaMask {
    /// Width in texels (bytes 0..4).
    pub width: u32,
    /// Height in texels (bytes 4..8).
    pub height: u32,
    /// Word offset of the first bit word in the alpha words (bytes 8..12).
    pub bits: u32,
    /// Unused (bytes 12..16).
    pub pad: u32,
}

/// Where one texture's texels are in the texel buffer, 16 bytes (WGSL `GpuTexture`).
/// Texels are linear RGBA `vec4<f32>`s, row-major, row 0 at the top (v = 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTexture {
    /// Index of the first texel (bytes 0..4).
    pub offset: u32,
    /// Width in texels (bytes 4..8).
    pub width: u32,
    /// Height in texels (bytes 8..12).
    pub height: u32,
    /// Unused (bytes 12..16).
    pub pad: u32,
}

/// The pinhole camera as the primary pass reads it, 80 bytes (WGSL `CameraParams`).
///
/// The ray through pixel `(x, y)` (centre `(x+½, y+½)`, row 0 at the top) is
/// `eye + t·(forward + sx·right + sy·up)` with `sx = 2(x+½)/width − 1` and
/// `sy = 1 − 2(y+½)/height`; `right` and `up` are pre-scaled by the field of view.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CameraParams {
    /// Eye position (bytes 0..12).
    pub eye: Vec3,
    /// Image width in pixels (bytes 12..16).
    pub width: u32,
    /// Unit view direction (bytes 16..28).
    pub forward: Vec3,
    /// Image height in pixels (bytes 28..32).
    pub height: u32,
    /// Right vector times `tan(fov_y/2)·aspect` (bytes 32..44).
    pub right: Vec3,
    /// Distance by which shadow-ray origins leave the surface (bytes 44..48).
    pub ray_offset: f32,
    /// Up vector times `tan(fov_y/2)` (bytes 48..60).
    pub up: Vec3,
    /// Unused (bytes 60..64).
    pub pad: u32,
    /// Width of the whole image the projection is for (bytes 64..68); `width` and
    /// `height` are those of the tile this dispatch writes.
    pub image_width: u32,
    /// Height of the whole image (bytes 68..72).
    pub image_height: u32,
    /// Column of the tile's left edge in the whole image (bytes 72..76).
    pub origin_x: u32,
    /// Row of the tile's top edge in the whole image (bytes 76..80).
    pub origin_y: u32,
}

/// The light as the shade pass sees it, 48 bytes (WGSL `ShadeParams`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ShadeParams {
    /// Centre of the quad light (bytes 0..12).
    pub light_center: Vec3,
    /// Area of the light (bytes 12..16).
    pub light_area: f32,
    /// Unit normal of the emitting side (bytes 16..28).
    pub light_normal: Vec3,
    /// Image width in pixels (bytes 28..32).
    pub width: u32,
    /// Emitted radiance, linear RGB (colour × intensity) (bytes 32..44).
    pub radiance: Vec3,
    /// Image height in pixels (bytes 44..48).
    pub height: u32,
}

/// How the refinement lays its listed pixels out as a sample image for the shadow
/// tracer, 16 bytes (WGSL `RefineParams` in `shaders/shared/refine.wgsl`). Each 4×4 tile
/// (row-major, `tiles_x` per row) holds `16 / sets` listed pixels: slot `first_slot + e`
/// goes to tile `e / (16 / sets)`, block `j = e mod (16 / sets)`, and tile pixel
/// `t = x + 4·y` (which traces sample set `t`) is a copy of its G-buffer texel when
/// `t / sets == j`. So a pixel traces sets `j·sets .. (j + 1)·sets` (all 16 when `sets`
/// is 16); tile pixels past the last slot are sky.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct RefineParams {
    /// Tiles per row of the sample image, which is `4 · tiles_x` pixels wide (bytes 0..4).
    pub tiles_x: u32,
    /// List slot of tile 0 (bytes 4..8).
    pub first_slot: u32,
    /// Listed pixels in this sample image (bytes 8..12); the image is
    /// `4 · ceil(tiles / tiles_x)` pixels high, `tiles = ceil(slots / (16 / sets))`.
    pub slots: u32,
    /// Sample sets each listed pixel traces, a power of two ≤ 16 (bytes 12..16).
    pub sets: u32,
}

impl RefineParams {
    /// Listed pixels per tile: [`crate::contract::refine::pixels_per_tile`] of `sets`.
    pub fn pixels_per_tile(&self) -> u32 {
        crate::contract::refine::pixels_per_tile(self.sets)
    }

    /// Width and height of the sample image in pixels.
    pub fn image_size(&self) -> (u32, u32) {
        let tiles = self.slots.div_ceil(self.pixels_per_tile());
        (4 * self.tiles_x, 4 * tiles.div_ceil(self.tiles_x.max(1)))
    }
}

/// How the embedded shadow pass reads a host's G-buffer textures, 112 bytes
/// (WGSL `SurfaceParams` in `shaders/shared/surface.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SurfaceParams {
    /// Inverse of the host's `projection × view`, then moved by −`eye`, columns (bytes
    /// 0..64): takes `(ndc_x, ndc_y, depth, 1)` back to homogeneous coordinates relative
    /// to the eye. Relative, the matrix holds no large translation for a scene far from
    /// the origin (its f32 rounding would move every point there by several f32 steps).
    pub clip_to_eye: [[f32; 4]; 4],
    /// Camera position, world space (bytes 64..76).
    pub eye: Vec3,
    /// Distance by which shadow-ray origins leave the surface (bytes 76..80).
    pub ray_offset: f32,
    /// Image width in pixels (bytes 80..84).
    pub width: u32,
    /// Image height in pixels (bytes 84..88).
    pub height: u32,
    /// Depth texels equal to this value see no geometry: the depth buffer's clear value,
    /// 1 for a standard projection, 0 for reversed Z (bytes 88..92).
    pub background_depth: f32,
    /// 1: the geometric-normal binding holds the host's geometric normals; 0: it repeats
    /// the shading normals, which then serve as geometric normals too (bytes 92..96).
    pub has_geo_normal: u32,
    /// [`crate::gpu::GpuScene::origin`]: the texels' ray origins are relative to it, as
    /// the scene's BVH is (bytes 96..108).
    pub origin: Vec3,
    /// How the normal textures store a normal (bytes 108..112): [`NORMALS_SIGNED`] or
    /// [`NORMALS_BIASED`] ([`crate::gpu::NormalEncoding`]).
    pub normal_encoding: u32,
}

/// [`SurfaceParams::normal_encoding`]: the texels are the normal's components.
pub const NORMALS_SIGNED: u32 = 0;
/// [`SurfaceParams::normal_encoding`]: the texels are `n · ½ + ½` (a unorm texture holding
/// signed components, as Bevy's normal prepass writes them).
pub const NORMALS_BIASED: u32 = 1;

/// An image size for the per-pixel kernels, 16 bytes (WGSL `ImageSize`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ImageSize {
    /// Width in pixels (bytes 0..4).
    pub width: u32,
    /// Height in pixels (bytes 4..8).
    pub height: u32,
    /// Unused (bytes 8..12).
    pub pad0: u32,
    /// Unused (bytes 12..16).
    pub pad1: u32,
}

const _: () = assert!(size_of::<SurfaceParams>() == 112);
const _: () = assert!(size_of::<ImageSize>() == 16);
const _: () = assert!(size_of::<ShadeParams>() == 48);
const _: () = assert!(size_of::<ShadingTriangle>() == 80);
const _: () = assert!(size_of::<GpuTexture>() == 16);
const _: () = assert!(size_of::<GpuMaterial>() == 32);
const _: () = assert!(size_of::<AlphaTriangle>() == 32);
const _: () = assert!(size_of::<AlphaMask>() == 16);
const _: () = assert!(size_of::<CameraParams>() == 80);
const _: () = assert!(size_of::<BvhNode>() == 32);
const _: () = assert!(size_of::<BvhTriangle>() == 48);
const _: () = assert!(size_of::<GBufferTexel>() == 64);
const _: () = assert!(size_of::<ShadowParams>() == 112);

impl BvhNode {
    /// True for a leaf (it holds triangles).
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// WGSL source of the BVH structs.
pub const BVH_WGSL: &str = include_str!("../../shaders/shared/bvh.wgsl");
/// WGSL source of the per-frame structs (G-buffer, shadow parameters).
pub const LAYOUT_WGSL: &str = include_str!("../../shaders/shared/layout.wgsl");
/// WGSL source of the embedded pass's structs; it imports [`LAYOUT_WGSL`], so the
/// layout tests parse the two together.
pub const SURFACE_WGSL: &str = include_str!("../../shaders/shared/surface.wgsl");

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
                v1,
                alpha,
                v2,
                pad2
            }),
        );
    }

    #[test]
    fn gbuffer_texel_layout_matches_wgsl() {
        check(
            LAYOUT_WGSL,
            "GBufferTexel",
            size_of::<GBufferTexel>(),
            fields!(GBufferTexel {
                origin,
                depth,
                normal,
                triangle,
                geo_normal,
                pad0,
                albedo,
                pad1
            }),
        );
    }

    #[test]
    fn shadow_params_layout_matches_wgsl() {
        check(
            LAYOUT_WGSL,
            "ShadowParams",
            size_of::<ShadowParams>(),
            fields!(ShadowParams {
                light_corners,
                light_normal,
                t_max,
                width,
                height,
                tile_origin_x,
                tile_origin_y,
                tiles_x,
                resume,
                iteration_budget,
                tiles_y
            }),
        );
    }

    #[test]
    fn shading_layouts_match_wgsl() {
        check(
            LAYOUT_WGSL,
            "ShadingTriangle",
            size_of::<ShadingTriangle>(),
            fields!(ShadingTriangle {
                n0,
                material,
                n1,
                pad1,
                n2,
                pad2,
                uv0,
                uv1,
                uv2,
                pad3
            }),
        );
        check(
            LAYOUT_WGSL,
            "GpuMaterial",
            size_of::<GpuMaterial>(),
            fields!(GpuMaterial {
                base_color,
                texture,
                alpha_factor,
                alpha_cutoff,
                pad
            }),
        );
        check(
            LAYOUT_WGSL,
            "AlphaTriangle",
            size_of::<AlphaTriangle>(),
            fields!(AlphaTriangle {
                uv0,
                uv1,
                uv2,
                mask,
                pad
            }),
        );
        check(
            LAYOUT_WGSL,
            "AlphaMask",
            size_of::<AlphaMask>(),
            fields!(AlphaMask {
                width,
                height,
                bits,
                pad
            }),
        );
        check(
            LAYOUT_WGSL,
            "GpuTexture",
            size_of::<GpuTexture>(),
            fields!(GpuTexture {
                offset,
                width,
                height,
                pad
            }),
        );
        check(
            LAYOUT_WGSL,
            "CameraParams",
            size_of::<CameraParams>(),
            fields!(CameraParams {
                eye,
                width,
                forward,
                height,
                right,
                ray_offset,
                up,
                pad,
                image_width,
                image_height,
                origin_x,
                origin_y
            }),
        );
    }

    #[test]
    fn shade_params_layout_matches_wgsl() {
        check(
            LAYOUT_WGSL,
            "ShadeParams",
            size_of::<ShadeParams>(),
            fields!(ShadeParams {
                light_center,
                light_area,
                light_normal,
                width,
                radiance,
                height
            }),
        );
    }

    #[test]
    fn refine_params_layout_matches_wgsl() {
        let source = crate::shaders::assemble("shared/refine", &[]).expect("refine module assembles");
        check(
            &source,
            "RefineParams",
            size_of::<RefineParams>(),
            fields!(RefineParams {
                tiles_x,
                first_slot,
                slots,
                sets
            }),
        );
    }

    #[test]
    fn surface_layouts_match_wgsl() {
        let source = crate::shaders::assemble("shared/surface", &[]).expect("surface module assembles");
        check(
            &source,
            "SurfaceParams",
            size_of::<SurfaceParams>(),
            fields!(SurfaceParams {
                clip_to_eye,
                eye,
                ray_offset,
                width,
                height,
                background_depth,
                has_geo_normal,
                origin,
                normal_encoding
            }),
        );
        check(
            &source,
            "ImageSize",
            size_of::<ImageSize>(),
            fields!(ImageSize {
                width,
                height,
                pad0,
                pad1
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
