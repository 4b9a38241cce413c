//! Where a block's samples land: each sample in one pixel of its block, so that every sample can join
//! the history of the pixel it landed in (issue 50: "samples land on pixels").
//!
//! The paper spreads a block's `τ` samples uniformly over the whole `b × b` footprint and keeps only
//! their mean. fovea keeps the mean too (the fill reconstructs the frame from it), but each sample is
//! now placed in a chosen pixel of the block (uniformly jittered inside it), and the pixels are chosen
//! in an order stratified over space *and* frames: sample `s` of frame `t` is the block's sample number
//! `k = t · τ + s`, and sample number `k` lands in pixel `order(k mod b²)` of the block, where `order`
//! is the ordered-dithering (Bayer) order of a `b × b` square. Every run of `2^j` consecutive numbers
//! that starts at a multiple of `2^j` is spread evenly over the square (the first half of a 4 × 4 block
//! is a checkerboard, its first quarter one pixel of each 2 × 2 quadrant), so:
//!
//! - the paper's periphery (8 samples per 4 × 4 block) visits every pixel of its block in exactly two
//!   frames, each frame's 8 pixels a checkerboard;
//! - the intermediate ring (16 per 2 × 2 block) gives each of its 4 pixels exactly 4 samples a frame;
//! - a fovea pixel (`b = 1`) takes every sample of its block, as before.
//!
//! Each block's square is shifted by its own XOR offset (a digital shift, which keeps the stratification)
//! so that neighbouring blocks do not visit the same relative pixel in the same frame. A block clipped
//! by the image edge folds the positions that fall outside back into its clipped footprint. Block edges
//! that are not powers of two use a rank-1 lattice order of the `b²` pixels instead of Bayer's.
//!
//! Both hosts place samples and sum them per pixel with these functions: [`landing_pixel`] when a
//! sample's camera ray is generated, [`landing_pixel`] again when its value is added to its pixel.
use glam::Vec2;

use super::blocks::{block_extent, OwnedBlock};
use crate::rng::pcg4d;

/// The block's sample number of sample `sample` of frame `frame_index`: `frame_index · spp + sample`
/// (wrapping), so that consecutive frames continue the block's stratified order.
#[inline]
#[must_use]
pub fn block_sample_number(frame_index: u32, spp: u32, sample: u32) -> u32 {
    frame_index.wrapping_mul(spp).wrapping_add(sample)
}

/// `v`'s lowest `bits` bits in reverse order (a loop: the kernel has no bit-reverse intrinsic it can
/// count on).
#[inline]
#[must_use]
fn reverse_bits(v: u32, bits: u32) -> u32 {
    let mut r = 0u32;
    let mut j = 0u32;
    while j < bits {
        r |= ((v >> j) & 1) << (bits - 1 - j);
        j += 1;
    }
    r
}

/// `log2(b)` if `b` is a power of two, else `u32::MAX`.
#[inline]
#[must_use]
fn log2_of_power_of_two(b: u32) -> u32 {
    if b == 0 || b & (b - 1) != 0 {
        return u32::MAX;
    }
    let mut m = 0u32;
    while (1u32 << m) < b {
        m += 1;
    }
    m
}

/// The position of entry `i` (`< b²`) of the ordered-dithering order of a `b × b` square, `b = 2^m`: the
/// pixel whose Bayer matrix value is `i`. The Bayer value of (`x`, `y`) reverses the bits of the
/// interleave of `x ⊕ y` (even bits) and `y` (odd bits); this undoes it.
#[inline]
#[must_use]
pub fn bayer_position(i: u32, m: u32) -> [u32; 2] {
    let r = reverse_bits(i, 2 * m);
    let mut a = 0u32; // x ⊕ y
    let mut c = 0u32; // y
    let mut j = 0u32;
    while j < m {
        a |= ((r >> (2 * j)) & 1) << j;
        c |= ((r >> (2 * j + 1)) & 1) << j;
        j += 1;
    }
    [a ^ c, c]
}

/// Greatest common divisor.
#[inline]
#[must_use]
fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

/// The position of entry `i` (`< b²`) of a rank-1 lattice order of a `b × b` square, for block edges
/// that are not powers of two: entry `i` is pixel `(i · g) mod b²` in row-major order, `g` the number
/// nearest `0.618 b²` that is coprime with `b²` (so the order is a permutation whose consecutive
/// entries lie far apart). Squares of `2^16` pixels or more take the row-major order.
#[must_use]
pub fn lattice_position(i: u32, b: u32) -> [u32; 2] {
    let n = b * b;
    if n >= 1 << 16 {
        return [i % b, i / b];
    }
    let mut g = ((n as f32 * 0.618_034) as u32).max(1);
    while gcd(g, n) != 1 {
        g += 1;
    }
    // Both factors are below 2^16: the product fits.
    let j = (i % n) * g % n;
    [j % b, j / b]
}

/// The block's own offset of its landing order: a digital shift `(sx, sy)` in `[0, b)²` from the block's
/// origin, edge and the frame's seed.
#[inline]
#[must_use]
fn block_shift(block: &OwnedBlock, seed: u32) -> [u32; 2] {
    let h = pcg4d([
        block.origin[0],
        block.origin[1],
        block.size,
        seed ^ 0x1a4d_5eed,
    ]);
    let b = block.size.max(1);
    [h[0] % b, h[1] % b]
}

/// The pixel (image coordinates) of `block` that the block's sample number `number`
/// ([`block_sample_number`]) lands in, in a `width × height` image with random-number seed `seed`.
#[must_use]
pub fn landing_pixel(
    block: &OwnedBlock,
    width: u32,
    height: u32,
    seed: u32,
    number: u32,
) -> [u32; 2] {
    let b = block.size.max(1);
    if b == 1 {
        return block.origin;
    }
    let i = number % (b * b);
    let shift = block_shift(block, seed);
    let m = log2_of_power_of_two(b);
    let [x, y] = if m != u32::MAX {
        let p = bayer_position(i, m);
        [p[0] ^ shift[0], p[1] ^ shift[1]]
    } else {
        let p = lattice_position(i, b);
        [(p[0] + shift[0]) % b, (p[1] + shift[1]) % b]
    };
    // A block clipped by the image edge folds what falls outside into its footprint.
    let e = block_extent(block, width, height);
    [
        block.origin[0] + x % e[0].max(1),
        block.origin[1] + y % e[1].max(1),
    ]
}

/// A sample position uniform over pixel `pixel`, for `u` in [0, 1)²: the usual jitter within the
/// pixel a sample landed in.
#[inline]
#[must_use]
pub fn pixel_sample_position(pixel: [u32; 2], u: Vec2) -> Vec2 {
    Vec2::new(pixel[0] as f32 + u.x, pixel[1] as f32 + u.y)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::collections::HashSet;
    use std::vec::Vec;

    use super::*;

    fn block(origin: [u32; 2], size: u32) -> OwnedBlock {
        OwnedBlock {
            origin,
            size,
            region: 2,
        }
    }

    #[test]
    fn bayer_order_is_the_ordered_dithering_matrix() {
        // The 4 × 4 Bayer matrix, rows top to bottom.
        let matrix = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];
        for (y, row) in matrix.iter().enumerate() {
            for (x, &value) in row.iter().enumerate() {
                assert_eq!(bayer_position(value, 2), [x as u32, y as u32], "{value}");
            }
        }
        // 2 × 2 and 8 × 8: a permutation.
        for m in [1, 3] {
            let n = 1u32 << (2 * m);
            let set: HashSet<_> = (0..n).map(|i| bayer_position(i, m)).collect();
            assert_eq!(set.len(), n as usize);
            assert!(set.iter().all(|p| p[0] < 1 << m && p[1] < 1 << m));
        }
    }

    #[test]
    fn the_periphery_visits_every_pixel_of_its_block_in_two_frames_a_checkerboard_each() {
        let b = block([8, 4], 4);
        for frame in 0..6u32 {
            let pixels: HashSet<[u32; 2]> = (0..8)
                .map(|s| landing_pixel(&b, 64, 64, 7, block_sample_number(frame, 8, s)))
                .collect();
            // Eight distinct pixels, two in each 2 × 2 quadrant, one in each row and column pair.
            assert_eq!(pixels.len(), 8, "frame {frame}");
            for q in 0..4 {
                let (qx, qy) = (8 + 2 * (q % 2), 4 + 2 * (q / 2));
                let n = pixels
                    .iter()
                    .filter(|p| p[0] / 2 * 2 == qx && p[1] / 2 * 2 == qy)
                    .count();
                assert_eq!(n, 2, "frame {frame}, quadrant {q}");
            }
            // With the next frame: all sixteen.
            let next: HashSet<[u32; 2]> = (0..8)
                .map(|s| landing_pixel(&b, 64, 64, 7, block_sample_number(frame + 1, 8, s)))
                .collect();
            let both: HashSet<_> = pixels.union(&next).collect();
            assert_eq!(both.len(), 16, "frames {frame} and {}", frame + 1);
        }
    }

    #[test]
    fn the_intermediate_ring_gives_each_pixel_four_samples_a_frame() {
        let b = block([2, 6], 2);
        for frame in 0..3u32 {
            let mut count = [0u32; 4];
            for s in 0..16 {
                let p = landing_pixel(&b, 64, 64, 3, block_sample_number(frame, 16, s));
                count[((p[1] - 6) * 2 + (p[0] - 2)) as usize] += 1;
            }
            assert_eq!(count, [4; 4]);
        }
    }

    #[test]
    fn neighbouring_blocks_start_in_different_pixels() {
        let firsts: HashSet<[u32; 2]> = (0..16u32)
            .map(|i| {
                let b = block([4 * i, 0], 4);
                let p = landing_pixel(&b, 256, 64, 0, 0);
                [p[0] - b.origin[0], p[1]]
            })
            .collect();
        assert!(firsts.len() >= 6, "{firsts:?}");
    }

    #[test]
    fn clipped_and_odd_blocks_land_inside_their_footprint_and_cover_it() {
        // A 4 × 4 block clipped to 3 × 2 at the image's corner, and 3 × 3 and 6 × 6 blocks.
        for (b, w, h) in [
            (block([60, 62], 4), 63, 64),
            (block([3, 3], 3), 64, 64),
            (block([6, 0], 6), 64, 64),
        ] {
            let e = block_extent(&b, w, h);
            let mut seen = HashSet::new();
            for k in 0..(b.size * b.size * 2) {
                let p = landing_pixel(&b, w, h, 11, k);
                assert!(
                    p[0] >= b.origin[0]
                        && p[0] < b.origin[0] + e[0]
                        && p[1] >= b.origin[1]
                        && p[1] < b.origin[1] + e[1],
                    "{p:?} outside {b:?} {e:?}"
                );
                seen.insert(p);
            }
            assert_eq!(seen.len() as u32, e[0] * e[1], "{b:?}");
        }
        // The lattice order is a permutation.
        for b in [3u32, 5, 6, 12] {
            let set: HashSet<_> = (0..b * b).map(|i| lattice_position(i, b)).collect();
            assert_eq!(set.len() as u32, b * b, "{b}");
        }
    }

    #[test]
    fn a_fovea_pixel_takes_every_sample() {
        let b = block([5, 9], 1);
        let all: Vec<_> = (0..32).map(|k| landing_pixel(&b, 64, 64, 1, k)).collect();
        assert!(all.iter().all(|p| *p == [5, 9]));
    }
}
