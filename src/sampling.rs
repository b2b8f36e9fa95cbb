//! Light samples: 256 points of a (0,2)-sequence split into 16 interleaved sets
//! of 16, so that every 4×4 pixel window sees all 256 (Kollig & Keller 2002).
//!
//! The points are the 256-point Hammersley set, `(i + ½)/256` against the
//! base-2 radical inverse of `i` (also + ½/256), all exact in f32. Set `k`
//! holds points `16·j + ((9·j + k) mod 16)` for `j = 0..16`: its `u`
//! coordinates fall one in each sixteenth of [0, 1), and because the radical
//! inverse's top four bits are the reversed low bits `(9j + k) mod 16` (a
//! permutation of 0..16, 9 being odd), so do its `v` coordinates — every set
//! is a Latin hypercube over the light. The plain split `{16·j + k}` would put
//! a whole set into one 1/16 strip of the light and give striped penumbrae
//! (DESIGN.md). DESIGN.md suggested `j xor k`; measured, its set 9 has two
//! points only 0.27 grid cells (of 16) apart, while `(9j + k) mod 16` keeps
//! every pair of every set at least 2.75 cells apart (the best of the
//! `(a·j + k)` and `(a·j + c) xor k` families).

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

/// Index into [`hammersley_256`] of sample `j` of set `k`.
pub fn sample_index(set: usize, j: usize) -> usize {
    16 * j + (9 * j + set) % 16
}

/// The sample set a pixel uses: `(x mod 4) + 4·(y mod 4)`.
pub fn pixel_set(x: u32, y: u32) -> usize {
    ((x % 4) + 4 * (y % 4)) as usize
}

/// The unit-square points of every set: `sets()[k][j]` is sample `j` of set `k`.
pub fn sets() -> [[Vec2; SAMPLES_PER_SET]; SETS] {
    let points = hammersley_256();
    std::array::from_fn(|k| std::array::from_fn(|j| points[sample_index(k, j)]))
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

    /// Whether each set has one point in every 1/16 column and every 1/16 row.
    fn is_latin(set: &[Vec2]) -> bool {
        let mut cols = [0; 16];
        let mut rows = [0; 16];
        for p in set {
            cols[(p.x * 16.0) as usize] += 1;
            rows[(p.y * 16.0) as usize] += 1;
        }
        cols.iter().chain(rows.iter()).all(|&c| c == 1)
    }

    #[test]
    fn sets_partition_the_points() {
        let mut seen = [false; SAMPLES];
        for k in 0..SETS {
            for j in 0..SAMPLES_PER_SET {
                let i = sample_index(k, j);
                assert!(!seen[i], "point {i} in two sets");
                seen[i] = true;
            }
        }
    }

    #[test]
    fn every_set_is_well_spread() {
        for (k, set) in sets().iter().enumerate() {
            assert!(is_latin(set), "set {k} is not one-per-row-and-column");
            // No two points of a set closer than 2.5 cells of the 16×16 grid (measured: ≥ 2.75).
            let min_dist = set
                .iter()
                .enumerate()
                .flat_map(|(a, p)| set[a + 1..].iter().map(move |q| p.distance(*q)))
                .fold(f32::INFINITY, f32::min);
            assert!(min_dist > 2.5 / 16.0, "set {k}: two points {min_dist} apart");
        }
    }

    #[test]
    fn xor_split_is_caught_by_the_distance_test() {
        let points = hammersley_256();
        let set9: Vec<Vec2> = (0..16).map(|j| points[16 * j + (j ^ 9)]).collect();
        assert!(is_latin(&set9));
        let close = set9
            .iter()
            .enumerate()
            .flat_map(|(a, p)| set9[a + 1..].iter().map(move |q| p.distance(*q)))
            .fold(f32::INFINITY, f32::min);
        assert!(close < 0.5 / 16.0);
    }

    #[test]
    fn strided_split_is_caught() {
        // The split DESIGN.md warns about must fail the spread test.
        let points = hammersley_256();
        let strided: Vec<Vec2> = (0..16).map(|j| points[16 * j]).collect();
        assert!(!is_latin(&strided));
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
