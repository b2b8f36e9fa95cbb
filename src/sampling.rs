//! Light samples: 256 points of a (0,2)-sequence split into 16 interleaved sets
//! of 16, so that every 4×4 pixel window sees all 256 (Kollig & Keller 2002).
//!
//! The points are the 256-point Hammersley set, `(i + ½)/256` against the
//! base-2 radical inverse of `i` (also + ½/256), all exact in f32: a (0,8,2)-net,
//! every box of area 1/256 whose sides are powers of two holding one point.
//! Point `i` belongs to the set of the pixel whose code is `L·i` over GF(2)
//! ([`SET_CODE_COLUMNS`]: the 8 columns of the 4×8 matrix `L`; two code bits
//! give `x mod 4` and two `y mod 4`, each through a Gray code). Each set is an
//! affine subspace of the bits of `i`, and `L` is chosen so that
//! - every set is a (0,4,2)-net: one point in each 1/16 column, 1/16 row and
//!   cell of the 4×4, 2×8 and 8×2 grids, so a pixel's 16 rays are stratified;
//! - every row of four pixels (`y mod 4` fixed) and every column of four
//!   (`x mod 4` fixed) holds a (0,6,2)-net of 64 points together. That is
//!   what the filter averages where a silhouette, a crease or a shadow edge
//!   cuts its window down to a strip of pixels: 64 stratified points rather
//!   than four sets that may crowd the same parts of the light.
//!
//! No `L` makes the pairs of neighbouring pixels 32-point nets as well (an
//! exhaustive search finds none); of the 2,304 that satisfy the two rules
//! above, this one has the lowest error, summed over single pixels, pairs,
//! triples, rows, columns, 2×2 and 3×3 blocks, when estimating the visible
//! part of the light behind 3,000 random straight edges, wedges and bars. Against
//! the earlier split `16·j + ((9·j + k) mod 16)` (a Latin hypercube per set, no
//! rule for groups), on 3,000 other such occluders: single pixels +3 %, rows
//! −12 %, columns −28 %, 3×3 blocks −13 % RMSE. The plain split `{16·j + k}`
//! would put a whole set into one 1/16 strip of the light and give striped
//! penumbrae (DESIGN.md).

use glam::{Vec2, Vec3};

use crate::scene::view::QuadLight;

/// Number of sample sets (one per pixel of a 4×4 tile).
pub const SETS: usize = 16;
/// Samples per set: shadow rays per pixel.
pub const SAMPLES_PER_SET: usize = 16;
/// All samples: what a 4×4 window sees together.
pub const SAMPLES: usize = SETS * SAMPLES_PER_SET;

/// Base-2 radical inverse of an 8-bit index, as a fraction of 256.
fn radical_inverse_8(i: u32) -> u32 {
    (i as u8).reverse_bits() as u32
}

/// The 256 Hammersley points in [0, 1)², cell-centred.
pub fn hammersley_256() -> [Vec2; SAMPLES] {
    std::array::from_fn(|i| {
        let i = i as u32;
        Vec2::new(
            (i as f32 + 0.5) / 256.0,
            (radical_inverse_8(i) as f32 + 0.5) / 256.0,
        )
    })
}

/// Columns of the 4×8 matrix `L` over GF(2): bit `b` of point `i` adds
/// `SET_CODE_COLUMNS[b]` (by xor) to the point's set code. Code bits 0 and 1 are
/// the Gray code of `x mod 4` (high bit first), bits 2 and 3 that of `y mod 4`.
pub const SET_CODE_COLUMNS: [u8; 8] = [0xd, 0x6, 0x9, 0x7, 0xd, 0xb, 0x5, 0xa];

/// The set (`x mod 4 + 4·(y mod 4)`) that point `i` of [`hammersley_256`] belongs to.
pub fn point_set(i: usize) -> usize {
    let code = (0..8)
        .filter(|b| (i >> b) & 1 == 1)
        .fold(0u8, |code, b| code ^ SET_CODE_COLUMNS[b]);
    // Gray code (two bits, high first) to residue: 00 → 0, 01 → 1, 11 → 2, 10 → 3.
    let residue = |hi: u8, lo: u8| [0, 1, 3, 2][usize::from(hi << 1 | lo)];
    let x = residue(code & 1, (code >> 1) & 1);
    let y = residue((code >> 2) & 1, (code >> 3) & 1);
    x + 4 * y
}

/// Indices into [`hammersley_256`] of every set's points, in increasing index:
/// `set_indices()[k][j]` is sample `j` of set `k`. One pass over the points.
pub fn set_indices() -> [[usize; SAMPLES_PER_SET]; SETS] {
    let mut sets = [[0; SAMPLES_PER_SET]; SETS];
    let mut filled = [0; SETS];
    for i in 0..SAMPLES {
        let k = point_set(i);
        // Every set holds exactly SAMPLES_PER_SET points (tested): an overflow is a bug.
        sets[k][filled[k]] = i;
        filled[k] += 1;
    }
    sets
}

/// The sample set a pixel uses: `(x mod 4) + 4·(y mod 4)`.
pub fn pixel_set(x: u32, y: u32) -> usize {
    ((x % 4) + 4 * (y % 4)) as usize
}

/// The unit-square points of every set: `sets()[k][j]` is sample `j` of set `k`.
pub fn sets() -> [[Vec2; SAMPLES_PER_SET]; SETS] {
    let points = hammersley_256();
    set_indices().map(|set| set.map(|i| points[i]))
}

/// World-space light sample points in set order (`[k·16 + j]` = sample `j` of
/// set `k`), as the shadow kernels read them; computed once on the CPU so the
/// GPU and the CPU oracle trace to bit-identical points.
pub fn light_points(light: &QuadLight) -> Vec<Vec3> {
    sets()
        .iter()
        .flatten()
        .map(|p| light.corner + p.x * light.edge_u + p.y * light.edge_v)
        .collect()
}

/// `n` Hammersley points in [0, 1)² for the reference tracer, cell-centred:
/// `((i + ½)/n, φ₂(i) + ½/n)` with `φ₂` the base-2 radical inverse, the `v`
/// coordinate kept below 1. Every column of width 1/n holds one point, and for
/// `n` a power of two every row of height 1/n too.
pub fn hammersley(n: u32) -> Vec<Vec2> {
    let n_f = n as f32;
    (0..n)
        .map(|i| {
            let radical = i.reverse_bits() as f64 / 4_294_967_296.0;
            let v = (radical + 0.5 / f64::from(n)).min(1.0 - 0.5 / f64::from(n));
            Vec2::new((i as f32 + 0.5) / n_f, v as f32)
        })
        .collect()
}

/// World-space points of [`hammersley`]`(n)` on the light: the reference tracer's
/// `n` rays per pixel go to these same points from every pixel.
pub fn reference_light_points(light: &QuadLight, n: u32) -> Vec<Vec3> {
    hammersley(n)
        .iter()
        .map(|p| light.corner + p.x * light.edge_u + p.y * light.edge_v)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_points_are_stratified_and_inside() {
        for n in [1, 7, 64, 256] {
            let points = hammersley(n);
            let mut cols = vec![0; n as usize];
            for p in &points {
                assert!(p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 1.0, "{p} outside");
                cols[(p.x * n as f32) as usize] += 1;
            }
            assert!(
                cols.iter().all(|&c| c == 1),
                "n = {n}: a column without exactly one point"
            );
        }
        let mut rows = [0; 64];
        for p in hammersley(64) {
            rows[(p.y * 64.0) as usize] += 1;
        }
        assert!(rows.iter().all(|&c| c == 1));
    }

    /// Whether `points` (2^m of them) form a (0,m,2)-net: one point in every box
    /// `[i/2^a, (i+1)/2^a) × [j/2^b, (j+1)/2^b)` with `a + b = m`.
    fn is_net(points: &[Vec2]) -> bool {
        let m = points.len().trailing_zeros();
        assert_eq!(points.len(), 1 << m);
        (0..=m).all(|a| {
            let (nx, ny) = (1usize << a, 1usize << (m - a));
            let mut cells = vec![0; nx * ny];
            for p in points {
                cells[(p.x * nx as f32) as usize * ny + (p.y * ny as f32) as usize] += 1;
            }
            cells.iter().all(|&c| c == 1)
        })
    }

    #[test]
    fn sets_partition_the_points() {
        let mut seen = [false; SAMPLES];
        for (k, set) in set_indices().iter().enumerate() {
            for &i in set {
                assert_eq!(point_set(i), k);
                assert!(!seen[i], "point {i} in two sets");
                seen[i] = true;
            }
        }
    }

    #[test]
    fn all_points_form_a_net() {
        assert!(is_net(&hammersley_256()));
    }

    #[test]
    fn every_set_is_a_net() {
        for (k, set) in sets().iter().enumerate() {
            assert!(is_net(set), "set {k} is not a (0,4,2)-net");
        }
    }

    #[test]
    fn every_row_and_column_of_four_pixels_is_a_net() {
        let sets = sets();
        let group = |pixels: &mut dyn Iterator<Item = (u32, u32)>| -> Vec<Vec2> {
            pixels.flat_map(|(x, y)| sets[pixel_set(x, y)]).collect()
        };
        for r in 0..4 {
            let row = group(&mut (0..4).map(|x| (x, r)));
            assert!(is_net(&row), "row {r} is not a (0,6,2)-net");
            let column = group(&mut (0..4).map(|y| (r, y)));
            assert!(is_net(&column), "column {r} is not a (0,6,2)-net");
        }
    }

    #[test]
    fn earlier_splits_fail_the_group_rule() {
        let points = hammersley_256();
        // The strided split puts a set into one 1/16 strip.
        let strided: Vec<Vec2> = (0..16).map(|j| points[16 * j]).collect();
        assert!(!is_net(&strided));
        // The previous split's sets were nets, but its rows were not.
        let old = |k: usize| (0..16).map(move |j| points[16 * j + (9 * j + k) % 16]);
        assert!(is_net(&old(0).collect::<Vec<_>>()));
        assert!(!is_net(&(0..4).flat_map(old).collect::<Vec<_>>()));
    }

    #[test]
    fn every_4x4_window_sees_all_sets() {
        for (x0, y0) in [(0, 0), (1, 2), (3, 3), (6, 1)] {
            let mut seen = [false; SETS];
            for y in y0..y0 + 4 {
                for x in x0..x0 + 4 {
                    seen[pixel_set(x, y)] = true;
                }
            }
            assert!(seen.iter().all(|&s| s));
        }
    }

    #[test]
    fn points_are_exact_and_inside() {
        for p in hammersley_256() {
            assert!(p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 1.0);
            assert_eq!(
                (p * 512.0).fract(),
                Vec2::ZERO,
                "multiples of 1/512: exact in f32"
            );
        }
    }
}
