//! Alpha-tested triangles (glTF `MASK` and `BLEND` materials) as rays see them: one
//! coverage bit per texel of each such material, one record of texture coordinates per
//! such triangle, all in one buffer of 32-bit words that the shadow kernels bind as
//! `alpha` (`shaders/shared/alpha.wgsl`). A triangle's [`BvhTriangle::alpha`] is its
//! record's offset, or [`OPAQUE`]: a material whose every texel is covered (or an
//! untextured one whose factor reaches the cutoff) flags nothing, so its triangles cost
//! what any opaque one does.

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use glam::Vec2;

use crate::Result;
use crate::contract::alpha::{HEADER_WORDS, OPAQUE, texel_index};
use crate::contract::layout::{AlphaMask, AlphaTriangle, BvhTriangle};
use crate::pass_inputs::{alpha_cutoff, decode_rgba8, texel_alpha};
use crate::scene::{AlphaMode, Scene};

/// The alpha words of a BVH: [`HEADER_WORDS`] unused words, then each masked material's
/// [`AlphaMask`] and its bits, then one [`AlphaTriangle`] per flagged triangle in leaf
/// order.
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaMasks {
    /// The words as the kernels read them.
    pub words: Vec<u32>,
    /// Triangles flagged (those whose [`BvhTriangle::alpha`] is not [`OPAQUE`]).
    pub triangles: usize,
}

impl Default for AlphaMasks {
    /// No alpha-tested triangle.
    fn default() -> Self {
        AlphaMasks {
            words: vec![0; HEADER_WORDS],
            triangles: 0,
        }
    }
}

impl AlphaMasks {
    /// Makes the masks of `scene`'s alpha-tested materials and flags `triangles` (leaf order,
    /// [`BvhTriangle::scene_index`] into `scene`) that use one. Decodes only the textures of
    /// such materials; an unreadable one is an error naming the scene and the image.
    pub fn build(scene: &Scene, triangles: &mut [BvhTriangle]) -> Result<AlphaMasks> {
        let mut words = vec![0u32; HEADER_WORDS];
        let mut decoded: HashMap<u32, image::RgbaImage> = HashMap::new();
        // Per material: the word offset of its mask, or None when rays never pass it.
        let mut mask_of = Vec::with_capacity(scene.materials.len());
        for m in &scene.materials {
            if m.alpha_mode == AlphaMode::Opaque {
                mask_of.push(None);
                continue;
            }
            let (factor, cutoff) = (m.base_color_factor[3], alpha_cutoff(m));
            let (width, height, covered): (u32, u32, Vec<bool>) = match m.base_color_texture {
                None => (1, 1, vec![factor >= cutoff]),
                Some(i) => {
                    let image = match decoded.entry(i) {
                        Entry::Occupied(e) => e.into_mut(),
                        Entry::Vacant(e) => e.insert(decode_rgba8(scene, i as usize)?),
                    };
                    let covered = image
                        .pixels()
                        .map(|p| texel_alpha(p[3]) * factor >= cutoff)
                        .collect();
                    (image.width(), image.height(), covered)
                }
            };
            if covered.iter().all(|&c| c) {
                mask_of.push(None);
                continue;
            }
            let at = words.len() as u32;
            let header = AlphaMask {
                width,
                height,
                bits: at + (size_of::<AlphaMask>() / 4) as u32,
                pad: 0,
            };
            words.extend_from_slice(bytemuck::cast_slice(&[header]));
            let mut bits = vec![0u32; covered.len().div_ceil(32)];
            for (i, _) in covered.iter().enumerate().filter(|(_, c)| **c) {
                bits[i / 32] |= 1 << (i % 32);
            }
            words.extend(bits);
            mask_of.push(Some(at));
        }
        let mut flagged = 0;
        for t in triangles.iter_mut() {
            let s = &scene.triangles[t.scene_index as usize];
            t.alpha = OPAQUE;
            if let Some(Some(mask)) = mask_of.get(s.material as usize) {
                t.alpha = words.len() as u32;
                let record = AlphaTriangle {
                    uv0: s.uvs[0],
                    uv1: s.uvs[1],
                    uv2: s.uvs[2],
                    mask: *mask,
                    pad: 0,
                };
                words.extend_from_slice(bytemuck::cast_slice(&[record]));
                flagged += 1;
            }
        }
        Ok(AlphaMasks {
            words,
            triangles: flagged,
        })
    }

    /// Whether a ray passes `tri` where it hits it with barycentric weights `w` (corners
    /// 0, 1, 2): only a flagged triangle can be absent there, where its mask's texel
    /// nearest to the interpolated texture coordinate is not covered. Twin of
    /// `alpha_passes` (`shaders/shared/alpha.wgsl`) and of the primary kernels'
    /// `passes_alpha`, which read the same texels through the materials.
    pub fn passes(&self, tri: &BvhTriangle, w: [f32; 3]) -> bool {
        self.passes_record(tri.alpha, w)
    }

    /// [`AlphaMasks::passes`] for the triangle whose [`BvhTriangle::alpha`] is `record`.
    pub fn passes_record(&self, record: u32, w: [f32; 3]) -> bool {
        if record == OPAQUE {
            return false;
        }
        let r = record as usize;
        let record: &AlphaTriangle = bytemuck::from_bytes(bytemuck::cast_slice(&self.words[r..r + 8]));
        let m = record.mask as usize;
        let mask: &AlphaMask = bytemuck::from_bytes(bytemuck::cast_slice(&self.words[m..m + 4]));
        let uv: Vec2 = record.uv0 * w[0] + record.uv1 * w[1] + record.uv2 * w[2];
        let i = texel_index(mask.width, mask.height, uv) as usize;
        self.words[mask.bits as usize + i / 32] & (1 << (i % 32)) == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, SceneTriangle};
    use glam::Vec3;

    fn scene_with(materials: Vec<Material>) -> Scene {
        let tri = |material| SceneTriangle {
            positions: [Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: [Vec3::Z; 3],
            uvs: [Vec2::ZERO, Vec2::X, Vec2::Y],
            material,
            instance: 0,
        };
        Scene {
            source: "test.gltf".into(),
            triangles: (0..materials.len() as u32).map(tri).collect(),
            materials,
            images: Vec::new(),
            instances: Vec::new(),
            camera: None,
            warnings: Default::default(),
        }
    }

    #[test]
    fn untextured_materials_flag_only_what_rays_pass() {
        let mask = |mode, alpha, cutoff| Material {
            alpha_mode: mode,
            base_color_factor: [1.0, 1.0, 1.0, alpha],
            alpha_cutoff: cutoff,
            ..Material::default()
        };
        let scene = scene_with(vec![
            mask(AlphaMode::Opaque, 0.0, 0.5),
            mask(AlphaMode::Mask, 0.6, 0.5),
            mask(AlphaMode::Mask, 0.4, 0.5),
            mask(AlphaMode::Blend, 0.06, 0.9),
            mask(AlphaMode::Blend, 0.04, 0.0),
        ]);
        let mut tris: Vec<BvhTriangle> = (0..5)
            .map(|i| BvhTriangle {
                scene_index: i,
                ..Default::default()
            })
            .collect();
        let masks = AlphaMasks::build(&scene, &mut tris).unwrap();
        let passes: Vec<bool> = tris.iter().map(|t| masks.passes(t, [0.3, 0.3, 0.4])).collect();
        // Opaque ignores alpha; MASK compares with its cutoff; BLEND with 0.05, not its cutoff.
        assert_eq!(passes, [false, false, true, false, true]);
        assert_eq!(masks.triangles, 2, "only the triangles rays can pass are flagged");
        assert_eq!(tris[0].alpha, OPAQUE);
        assert_eq!(tris[1].alpha, OPAQUE);
    }
}
