//! Small deterministic random-number generators shared by core's unit tests (test builds only), and the
//! chi-square goodness-of-fit harness for samplers ([`chi2`]).
extern crate std;

use glam::{Vec2, Vec3};
use std::vec::Vec;

use crate::scene::{triangle_lane, TriangleBlock, TrianglePositions, BLOCK_LANE_CUTOUT};

pub(crate) mod chi2;

/// Calls `f` with rays that stress a slab test: origins at extreme coordinates and every direction
/// whose components are drawn from zeros of both signs, denormals, ±1 and huge values (used by the 4-wide
/// and the 8-wide node tests).
pub(crate) fn for_each_slab_stress_ray(mut f: impl FnMut(crate::geometry::Ray)) {
    let components = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        1e-30,
        -1e-30,
        1e-40,
        -1e-40,
        1e30,
        -1e30,
        f32::MAX,
        -f32::MAX,
    ];
    let origins = [
        Vec3::ZERO,
        Vec3::splat(f32::MAX),
        Vec3::splat(-f32::MAX),
        Vec3::new(f32::MAX, -f32::MAX, 0.0),
        Vec3::new(1e30, -3.0, 7.0),
    ];
    for origin in origins {
        for &x in &components {
            for &y in &components {
                for &z in &components {
                    f(crate::geometry::Ray::new(origin, Vec3::new(x, y, z)));
                }
            }
        }
    }
}

/// SplitMix64 (Steele, Lea, Flood 2014).
pub(crate) struct SplitMix64(pub u64);

impl SplitMix64 {
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub(crate) fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in [lo, hi).
    pub(crate) fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.uniform()
    }

    /// Uniform in the cube [-h, h)³ (x, y, z drawn in that order).
    pub(crate) fn in_cube(&mut self, h: f32) -> Vec3 {
        let x = self.range(-h, h);
        let y = self.range(-h, h);
        Vec3::new(x, y, self.range(-h, h))
    }

    /// A uniformly distributed unit vector (rejection sampling in the unit ball).
    pub(crate) fn unit_vector(&mut self) -> Vec3 {
        loop {
            let v = self.in_cube(1.0);
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / crate::math::float::sqrt(l);
            }
        }
    }
}

/// Triangles packed one per block, each in lane 0: the blocks and the `GeometryArrays::triangle_lanes` that
/// name them (the layout of a BVH whose leaves hold one triangle each, so a leaf word `leaf_slot(i, 1)`
/// names triangle `i`). `cut_out` lists the triangles whose material has an alpha cut-out.
pub(crate) fn one_triangle_per_block(
    triangles: &[TrianglePositions],
    cut_out: &[u32],
) -> (Vec<TriangleBlock>, Vec<u32>) {
    let blocks = triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let flag = if cut_out.contains(&(i as u32)) {
                BLOCK_LANE_CUTOUT
            } else {
                0
            };
            let mut block = TriangleBlock::EMPTY;
            block.set_lane(0, t, i as u32 | flag);
            block
        })
        .collect();
    let lanes = (0..triangles.len() as u32)
        .map(|i| triangle_lane(i, 0))
        .collect();
    (blocks, lanes)
}

/// xorshift32 (Marsaglia 2003) mapped to [0, 1).
pub(crate) struct XorShift32(pub u32);

impl XorShift32 {
    pub(crate) fn next(&mut self) -> f32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        (x >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    pub(crate) fn vec2(&mut self) -> Vec2 {
        Vec2::new(self.next(), self.next())
    }

    pub(crate) fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}
