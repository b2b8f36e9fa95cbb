//! Helpers shared by the integration tests: a deterministic random generator
//! and random triangle soups.
#![allow(dead_code)] // each test binary uses a different subset

use glam::Vec3;

/// PCG32 (O'Neill): small, deterministic, good enough for test inputs.
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        let mut r = Rng(seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407));
        r.next_u32();
        r
    }

    /// Next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// Uniform in the box [lo, hi).
    pub fn in_box(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }

    /// Uniform direction on the unit sphere.
    pub fn direction(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// `n` random triangles with corners in the unit cube, each at most `size` across.
pub fn random_soup(rng: &mut Rng, n: usize, size: f32) -> Vec<[Vec3; 3]> {
    (0..n)
        .map(|_| {
            let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
            [c, c + rng.direction() * size, c + rng.direction() * size]
        })
        .collect()
}

/// A flat `n`×`n` grid of quads (2 triangles each) in the y = 0 plane over [0, 1]².
pub fn flat_grid(n: usize) -> Vec<[Vec3; 3]> {
    let mut out = Vec::new();
    let s = 1.0 / n as f32;
    for i in 0..n {
        for j in 0..n {
            let p = |a: usize, b: usize| Vec3::new(a as f32 * s, 0.0, b as f32 * s);
            out.push([p(i, j), p(i, j + 1), p(i + 1, j)]);
            out.push([p(i + 1, j), p(i, j + 1), p(i + 1, j + 1)]);
        }
    }
    out
}
