//! Where a visibility image's error against exact visibility lies, for
//! `penumbra quality`: each pixel with geometry falls in one [`Region`] — a
//! geometric edge inside its filter window (the filter's own
//! [`same_surface`] test), a sharp shadow transition, other
//! penumbra, or plain light or umbra — and [`error_by_region`] gives each
//! region's RMSE and share of the squared error. The regions are those the
//! discontinuity filter treats differently, so the table says which of its
//! tests (geometry, visibility) the remaining error comes from.

use crate::contract::filter::FilterParams;
use crate::contract::layout::GBufferTexel;
use crate::reference::filter::same_surface;

/// Exact visibility within this of 0 or 1 counts as umbra or fully lit.
const FLAT_EPSILON: f32 = 1e-4;

/// A shadow transition is sharp when exact visibility changes by more than
/// this across the filter's 5×5 window: the penumbra is at most a few pixels
/// wide (contact shadows, thin occluders), narrower than the window averages.
pub const SHARP_RANGE: f32 = 0.5;

/// The class of a pixel with geometry, by what its filter window sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Region {
    /// A neighbour in the 5×5 window has no geometry, or a depth or normal the
    /// filter rejects (silhouettes, creases): fewer neighbours are averaged.
    GeometricEdge,
    /// No geometric edge, and exact visibility changes by more than
    /// [`SHARP_RANGE`] across the window.
    SharpTransition,
    /// No geometric edge, a gentler change, and the pixel sees part of the light.
    Penumbra,
    /// No geometric edge, a gentler change, and the pixel sees all or none of the light.
    LitOrUmbra,
}

impl Region {
    /// Every region, in the order of the enum.
    pub const ALL: [Region; 4] = [
        Region::GeometricEdge,
        Region::SharpTransition,
        Region::Penumbra,
        Region::LitOrUmbra,
    ];

    /// Short name for tables and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Region::GeometricEdge => "geometric edge",
            Region::SharpTransition => "sharp transition",
            Region::Penumbra => "penumbra",
            Region::LitOrUmbra => "lit or umbra",
        }
    }
}

/// The region of every pixel of a `width × height` image, row-major; `None`
/// for pixels without geometry (depth ≤ 0). The geometric test is the
/// filter's (`params` depth and normal tolerances, same 5×5 window).
///
/// # Panics
///
/// If `gbuffer` or `exact` does not hold `width · height` values (a caller bug).
pub fn classify_pixels(
    gbuffer: &[GBufferTexel],
    exact: &[f32],
    width: u32,
    height: u32,
    params: &FilterParams,
) -> Vec<Option<Region>> {
    let (w, h) = (width as i32, height as i32);
    let n = width as usize * height as usize;
    assert!(
        gbuffer.len() == n && exact.len() == n,
        "classify_pixels: {width}×{height} needs {n} texels and values, got {} and {}",
        gbuffer.len(),
        exact.len()
    );
    let mut regions = Vec::with_capacity(n);
    for y in 0..h {
        for x in 0..w {
            let c = &gbuffer[(y * w + x) as usize];
            if c.depth <= 0.0 {
                regions.push(None);
                continue;
            }
            let mut edge = false;
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for ny in (y - 2).max(0)..=(y + 2).min(h - 1) {
                for nx in (x - 2).max(0)..=(x + 2).min(w - 1) {
                    let ix = (ny * w + nx) as usize;
                    let t = &gbuffer[ix];
                    edge |= !same_surface(params, c.depth, c.normal.to_array(), t.depth, t.normal.to_array());
                    lo = lo.min(exact[ix]);
                    hi = hi.max(exact[ix]);
                }
            }
            let v = exact[(y * w + x) as usize];
            regions.push(Some(if edge {
                Region::GeometricEdge
            } else if hi - lo > SHARP_RANGE {
                Region::SharpTransition
            } else if v > FLAT_EPSILON && v < 1.0 - FLAT_EPSILON {
                Region::Penumbra
            } else {
                Region::LitOrUmbra
            }));
        }
    }
    regions
}

/// One region's part of an image's error.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RegionError {
    /// The region's name ([`Region::name`]).
    pub region: &'static str,
    /// Fraction of the compared pixels in this region.
    pub pixel_share: f64,
    /// RMSE over the region's pixels (0 when it has none).
    pub rmse: f64,
    /// The region's share of the image's summed squared error (0 when the image is exact).
    pub error_share: f64,
}

/// Each [`Region`]'s RMSE and share of the squared error of `test` against
/// `exact`, over the pixels whose region is `Some`.
///
/// # Panics
///
/// If the three slices differ in length (a caller bug).
pub fn error_by_region(test: &[f32], exact: &[f32], regions: &[Option<Region>]) -> Vec<RegionError> {
    assert!(
        test.len() == exact.len() && exact.len() == regions.len(),
        "error_by_region: {} values, {} exact values, {} regions",
        test.len(),
        exact.len(),
        regions.len()
    );
    let mut squared = [0.0f64; Region::ALL.len()];
    let mut count = [0usize; Region::ALL.len()];
    for ((&t, &e), r) in test.iter().zip(exact).zip(regions) {
        if let Some(r) = r {
            let d = f64::from(t) - f64::from(e);
            squared[*r as usize] += d * d;
            count[*r as usize] += 1;
        }
    }
    let total_squared: f64 = squared.iter().sum();
    let total_count: usize = count.iter().sum();
    Region::ALL
        .iter()
        .map(|&r| {
            let (s, c) = (squared[r as usize], count[r as usize]);
            RegionError {
                region: r.name(),
                pixel_share: if total_count == 0 {
                    0.0
                } else {
                    c as f64 / total_count as f64
                },
                rmse: if c == 0 { 0.0 } else { (s / c as f64).sqrt() },
                error_share: if total_squared == 0.0 {
                    0.0
                } else {
                    s / total_squared
                },
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use bytemuck::Zeroable;
    use glam::Vec3;

    fn texel(depth: f32, normal: Vec3) -> GBufferTexel {
        GBufferTexel {
            depth,
            normal,
            ..GBufferTexel::zeroed()
        }
    }

    /// An 8×8 plane facing +z at depth 1, except what `edit` changes.
    fn plane(edit: impl Fn(usize, usize, &mut GBufferTexel)) -> Vec<GBufferTexel> {
        let mut g = vec![texel(1.0, Vec3::Z); 64];
        for y in 0..8 {
            for x in 0..8 {
                edit(x, y, &mut g[y * 8 + x]);
            }
        }
        g
    }

    #[test]
    fn plain_plane_is_lit_umbra_or_penumbra_by_its_value() {
        let g = plane(|_, _, _| {});
        let mut exact = vec![1.0f32; 64];
        exact[0] = 0.0;
        exact[63] = 0.7;
        let r = classify_pixels(&g, &exact, 8, 8, &FilterParams::new(8, 8));
        assert_eq!(
            r[0],
            Some(Region::SharpTransition),
            "1 next to 0 is a sharp change"
        );
        assert_eq!(r[63], Some(Region::Penumbra));
        assert_eq!(r[36], Some(Region::LitOrUmbra));
    }

    #[test]
    fn depth_step_marks_the_pixels_within_two_of_it() {
        // Columns 4.. are twice as far: columns 2..=5 see the step in their window.
        let g = plane(|x, _, t| {
            if x >= 4 {
                t.depth = 2.0;
            }
        });
        let exact = vec![0.5f32; 64];
        let r = classify_pixels(&g, &exact, 8, 8, &FilterParams::new(8, 8));
        for x in 0..8 {
            let want = if (2..=5).contains(&x) {
                Region::GeometricEdge
            } else {
                Region::Penumbra
            };
            assert_eq!(r[3 * 8 + x], Some(want), "column {x}");
        }
    }

    #[test]
    fn sky_pixels_have_no_region_and_mark_their_neighbours_as_edges() {
        let g = plane(|x, y, t| {
            if (x, y) == (0, 0) {
                t.depth = 0.0;
            }
        });
        let exact = vec![1.0f32; 64];
        let r = classify_pixels(&g, &exact, 8, 8, &FilterParams::new(8, 8));
        assert_eq!(r[0], None);
        assert_eq!(r[2 * 8 + 2], Some(Region::GeometricEdge));
        assert_eq!(r[3 * 8 + 3], Some(Region::LitOrUmbra));
    }

    #[test]
    fn crease_is_an_edge() {
        let g = plane(|_, y, t| {
            if y >= 4 {
                t.normal = Vec3::Y;
            }
        });
        let exact = vec![1.0f32; 64];
        let r = classify_pixels(&g, &exact, 8, 8, &FilterParams::new(8, 8));
        assert_eq!(r[2 * 8], Some(Region::GeometricEdge));
        assert_eq!(r[8], Some(Region::LitOrUmbra));
    }

    #[test]
    fn shares_and_rmse_by_hand() {
        let regions = [
            Some(Region::Penumbra),
            Some(Region::Penumbra),
            Some(Region::GeometricEdge),
            None,
        ];
        let exact = [0.5, 0.5, 1.0, 0.0];
        let test = [0.6, 0.5, 0.8, 1.0]; // the sky pixel's error does not count
        let e = error_by_region(&test, &exact, &regions);
        let by = |name| e.iter().find(|r| r.region == name).unwrap();
        let pen = by("penumbra");
        let edge = by("geometric edge");
        // Squared errors 0.01 and 0.04 (in f32 inputs, so compare loosely).
        assert!((pen.error_share - 0.2).abs() < 1e-6, "{pen:?}");
        assert!((edge.error_share - 0.8).abs() < 1e-6, "{edge:?}");
        assert!((pen.rmse - (0.01f64 / 2.0).sqrt()).abs() < 1e-6);
        assert!((edge.rmse - 0.2).abs() < 1e-6);
        assert!((pen.pixel_share - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!(by("lit or umbra").rmse, 0.0);
        let sum: f64 = e.iter().map(|r| r.error_share).sum();
        assert!((sum - 1.0).abs() < 1e-12);
    }

    #[test]
    fn exact_image_has_no_error_anywhere() {
        let regions = [Some(Region::Penumbra); 3];
        let v = [0.1, 0.2, 0.3];
        assert!(
            error_by_region(&v, &v, &regions)
                .iter()
                .all(|r| r.error_share == 0.0 && r.rmse == 0.0)
        );
    }
}
