//! Block ownership: which block of which region renders each pixel (Mohanto et al. 2023, sections 3.2-3.3).
//!
//! The paper renders the fovea per pixel and the outer regions in `n × n` and `m × m` pixel blocks, and
//! decides by a "bound check" against the radii where each region renders. fovea makes that decision per
//! block, by the block's *centre*, on three nested grids aligned to the image origin (block sizes
//! `b_f | b_i | b_p`, checked by [`FoveationParams::validate`]):
//!
//! 1. a periphery-size block (origin a multiple of `b_p`) whose centre lies in the periphery is one
//!    periphery block;
//! 2. otherwise each of its intermediate-size sub-blocks whose centre lies outside the fovea (`d > r_f`)
//!    is one intermediate block;
//! 3. otherwise each of that sub-block's fovea-size sub-blocks is one fovea block.
//!
//! Every pixel therefore belongs to exactly one block: no gaps and no double writes, whatever the gaze
//! and radii. The nesting can only make a block *finer* than its centre asks for (an intermediate-size
//! sub-block whose centre is in the periphery stays intermediate when its periphery-size parent's centre is
//! not in the periphery; a fovea-size block may have its centre anywhere), never coarser, so no part of
//! the image gets fewer samples than the region of its block centre prescribes.
//!
//! Blocks at the right and bottom image edges are clipped to the image, but the ownership decision still
//! uses the centre of the full aligned square (which may lie outside the image); only the footprint
//! ([`block_extent`]) and the sample positions ([`block_sample_position`]) are clipped.
use glam::Vec2;

use super::regions::{
    region_of_point, FoveationParams, REGION_FOVEA, REGION_INTERMEDIATE, REGION_PERIPHERY,
};

/// One block of the foveated image: its top-left pixel, its (unclipped) edge length and its region.
/// Also the GPU's block-list element (16 bytes, [`crate::kernel_abi::BINDING_BLOCKS`]), so the host and
/// the kernel share this one type.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct OwnedBlock {
    /// Top-left pixel; a multiple of `size` in both axes.
    pub origin: [u32; 2],
    /// Edge length of the aligned square in pixels (`block_size[region]`).
    pub size: u32,
    /// [`REGION_FOVEA`], [`REGION_INTERMEDIATE`] or [`REGION_PERIPHERY`].
    pub region: u32,
}

/// Centre of the aligned `size × size` square with top-left pixel (`x0`, `y0`).
#[inline]
#[must_use]
fn square_centre(x0: u32, y0: u32, size: u32) -> Vec2 {
    let half = 0.5 * size as f32;
    Vec2::new(x0 as f32 + half, y0 as f32 + half)
}

/// Whether the periphery-grid square at (`x0`, `y0`) is one periphery block (rule 1).
#[inline]
#[must_use]
fn is_periphery_block(x0: u32, y0: u32, params: &FoveationParams) -> bool {
    region_of_point(square_centre(x0, y0, params.block_size[2]), params) == REGION_PERIPHERY
}

/// Whether the intermediate-grid square at (`x0`, `y0`), inside a square that is not a periphery block, is
/// one intermediate block (rule 2: its centre lies outside the fovea).
#[inline]
#[must_use]
fn is_intermediate_block(x0: u32, y0: u32, params: &FoveationParams) -> bool {
    region_of_point(square_centre(x0, y0, params.block_size[1]), params) != REGION_FOVEA
}

/// The block that owns pixel (`x`, `y`). Needs valid parameters ([`FoveationParams::validate`]).
///
/// A host or kernel enumerates every block exactly once as "each pixel `p` with
/// `owning_block(p).origin == p`".
#[must_use]
pub fn owning_block(x: u32, y: u32, params: &FoveationParams) -> OwnedBlock {
    let bp = params.block_size[2];
    let (px, py) = (x / bp * bp, y / bp * bp);
    if is_periphery_block(px, py, params) {
        return OwnedBlock {
            region: REGION_PERIPHERY,
            size: bp,
            origin: [px, py],
        };
    }
    let bi = params.block_size[1];
    let (ix, iy) = (x / bi * bi, y / bi * bi);
    if is_intermediate_block(ix, iy, params) {
        return OwnedBlock {
            region: REGION_INTERMEDIATE,
            size: bi,
            origin: [ix, iy],
        };
    }
    let bf = params.block_size[0];
    OwnedBlock {
        region: REGION_FOVEA,
        size: bf,
        origin: [x / bf * bf, y / bf * bf],
    }
}

/// Centre of the block's full aligned square (the point its region was decided by; may lie outside the
/// image for clipped blocks).
#[inline]
#[must_use]
pub fn block_centre(block: &OwnedBlock) -> Vec2 {
    square_centre(block.origin[0], block.origin[1], block.size)
}

/// Width and height in pixels of the block's footprint clipped to a `width × height` image.
#[inline]
#[must_use]
pub fn block_extent(block: &OwnedBlock, width: u32, height: u32) -> [u32; 2] {
    // `max` then subtract: `saturating_sub` is not available in rust-gpu.
    let room_x = width.max(block.origin[0]) - block.origin[0];
    let room_y = height.max(block.origin[1]) - block.origin[1];
    [block.size.min(room_x), block.size.min(room_y)]
}

/// A sample position uniform over the block's clipped footprint, for `u` in [0, 1)²: the paper's subpixel
/// jitter, spread over the whole block (for a 1×1 block it is the usual jitter within the pixel). For `u`
/// just below 1, float rounding can land exactly on the footprint's far edge (a set of measure zero).
#[inline]
#[must_use]
pub fn block_sample_position(block: &OwnedBlock, width: u32, height: u32, u: Vec2) -> Vec2 {
    let e = block_extent(block, width, height);
    Vec2::new(
        block.origin[0] as f32 + u.x * e[0] as f32,
        block.origin[1] as f32 + u.y * e[1] as f32,
    )
}

/// Primary samples the block takes: `spp[region]` (eq. 1: `τ` samples per block, clipped or not).
#[inline]
#[must_use]
pub fn samples_in_block(block: &OwnedBlock, params: &FoveationParams) -> u32 {
    params.spp[block.region as usize]
}

/// The samples of a block that a part of a split render takes (`fovea render --samples first..end`):
/// sample indices `first..end` clipped to the block's `spp`, as `[first, end]` (empty, `first == end`,
/// where the block has no sample in the range). The parts of a split tile each block's `0..spp`
/// exactly when their ranges tile `0..` the largest `spp`.
#[inline]
#[must_use]
pub fn block_sample_range(spp: u32, first: u32, end: u32) -> [u32; 2] {
    let end = end.min(spp);
    [first.min(end), end]
}

/// Visits every block of a `width × height` image whose origin lies in rows `first_row..end_row`, once,
/// in the order the grids nest: each periphery-grid square left to right, then (unless it is one periphery
/// block) its intermediate-grid squares, then (unless each is one intermediate block) their fovea-grid
/// squares. `first_row` must be a multiple of the periphery block size (`b_p`), so the rows split into
/// bands that share no block; `end_row` is clamped to `height`.
///
/// This is the one walk over a frame's blocks: the CPU host renders each band's blocks with it, the
/// Vulkan host lists them for its dispatches, and [`count_blocks`]/[`count_samples`] count them. It
/// calls [`owning_block`]'s two rules once per candidate square rather than once per pixel.
/// Host-side (a generic closure); the kernel finds its blocks in the list the host wrote.
pub fn for_each_block_in_rows(
    width: u32,
    height: u32,
    first_row: u32,
    end_row: u32,
    params: &FoveationParams,
    mut visit: impl FnMut(OwnedBlock),
) {
    let [bf, bi, bp] = [
        params.block_size[0].max(1),
        params.block_size[1].max(1),
        params.block_size[2].max(1),
    ];
    let end_row = end_row.min(height);
    let mut py = first_row;
    while py < end_row {
        let mut px = 0;
        while px < width {
            if is_periphery_block(px, py, params) {
                visit(OwnedBlock {
                    origin: [px, py],
                    size: bp,
                    region: REGION_PERIPHERY,
                });
            } else {
                let mut iy = py;
                while iy < (py + bp).min(height) {
                    let mut ix = px;
                    while ix < (px + bp).min(width) {
                        if is_intermediate_block(ix, iy, params) {
                            visit(OwnedBlock {
                                origin: [ix, iy],
                                size: bi,
                                region: REGION_INTERMEDIATE,
                            });
                        } else {
                            let mut fy = iy;
                            while fy < (iy + bi).min(height) {
                                let mut fx = ix;
                                while fx < (ix + bi).min(width) {
                                    visit(OwnedBlock {
                                        origin: [fx, fy],
                                        size: bf,
                                        region: REGION_FOVEA,
                                    });
                                    fx += bf;
                                }
                                fy += bf;
                            }
                        }
                        ix += bi;
                    }
                    iy += bi;
                }
            }
            px += bp;
        }
        py += bp;
    }
}

/// [`for_each_block_in_rows`] over the whole image.
pub fn for_each_block(
    width: u32,
    height: u32,
    params: &FoveationParams,
    visit: impl FnMut(OwnedBlock),
) {
    for_each_block_in_rows(width, height, 0, height, params, visit);
}

/// Adds 1 (`per_block == false`) or the block's samples to `counts[region]` for every block.
fn accumulate_blocks(
    width: u32,
    height: u32,
    params: &FoveationParams,
    per_block: bool,
) -> [u64; 3] {
    let mut counts = [0u64; 3];
    for_each_block(width, height, params, |block| {
        let region = block.region as usize;
        counts[region] += if per_block {
            1
        } else {
            u64::from(params.spp[region])
        };
    });
    counts
}

/// Primary samples per region of a `width × height` image (host helper; the ideal speed-up over uniform
/// rendering is `width · height · spp_uniform / sum`).
#[must_use]
pub fn count_samples(width: u32, height: u32, params: &FoveationParams) -> [u64; 3] {
    accumulate_blocks(width, height, params, false)
}

/// Blocks per region of a `width × height` image (host helper).
#[must_use]
pub fn count_blocks(width: u32, height: u32, params: &FoveationParams) -> [u64; 3] {
    accumulate_blocks(width, height, params, true)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec;
    use std::vec::Vec;

    use super::*;
    use crate::foveation::regions::FOVEATION_OK;

    #[test]
    fn sample_ranges_that_tile_the_largest_spp_tile_every_block() {
        // Ranges 0..5, 5..11, 11..32 of a frame whose largest spp is 32, for blocks of 32, 16, 8, 1, 0.
        let ranges = [[0, 5], [5, 11], [11, 32]];
        for spp in [32, 16, 8, 5, 1, 0] {
            let parts: Vec<[u32; 2]> = ranges
                .iter()
                .map(|r| block_sample_range(spp, r[0], r[1]))
                .collect();
            let mut next = 0;
            for [first, end] in parts {
                assert!(first <= end, "{spp}: {first}..{end}");
                if first < end {
                    assert_eq!(first, next, "{spp}: parts meet without gap or overlap");
                    next = end;
                }
            }
            assert_eq!(next, spp, "{spp}: the parts cover the block's samples");
        }
        assert_eq!(
            block_sample_range(8, 16, 32),
            [8, 8],
            "empty past the block's spp"
        );
    }

    /// Many parameter sets over a 97 × 61 image: gazes (centre, corner, outside), radii (0, tiny, mixed,
    /// huge) and block sizes.
    fn cases() -> Vec<FoveationParams> {
        let gazes = [
            [48.5, 30.5],
            [0.0, 0.0],
            [97.0, 61.0],
            [13.3, 47.9],
            [-40.0, 20.0],
            [300.0, -500.0],
        ];
        let radii = [
            (0.0, 0.0),
            (0.3, 0.7),
            (5.0, 17.0),
            (11.0, 29.5),
            (20.0, 8.0),
            (0.0, 1.0e9),
            (f32::MAX, f32::MAX),
        ];
        let blocks = [[1, 2, 4], [1, 1, 1], [1, 2, 8], [2, 4, 8], [1, 3, 6]];
        let mut out = Vec::new();
        for g in gazes {
            for r in radii {
                for b in blocks {
                    let mut p = FoveationParams::paper(g, r.0, r.1);
                    p.spp = [7, 3, 2, 0];
                    p.block_size = [b[0], b[1], b[2], 0];
                    assert_eq!(p.validate(), FOVEATION_OK);
                    out.push(p);
                }
            }
        }
        out
    }

    /// Blocks enumerated as "pixels that are their block's origin".
    fn enumerate(w: u32, h: u32, p: &FoveationParams) -> Vec<OwnedBlock> {
        let mut blocks = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let b = owning_block(x, y, p);
                if b.origin == [x, y] {
                    blocks.push(b);
                }
            }
        }
        blocks
    }

    #[test]
    fn every_pixel_is_owned_exactly_once() {
        for (w, h) in [(97u32, 61u32), (8, 8), (1, 1), (13, 5)] {
            for p in cases() {
                let mut cover = vec![0u32; (w * h) as usize];
                for b in enumerate(w, h, &p) {
                    assert_eq!(b.size, p.block_size[b.region as usize]);
                    assert_eq!(b.origin[0] % b.size, 0);
                    assert_eq!(b.origin[1] % b.size, 0);
                    let e = block_extent(&b, w, h);
                    assert!(e[0] >= 1 && e[1] >= 1);
                    for y in b.origin[1]..b.origin[1] + e[1] {
                        for x in b.origin[0]..b.origin[0] + e[0] {
                            cover[(y * w + x) as usize] += 1;
                            assert_eq!(owning_block(x, y, &p), b, "pixel ({x}, {y}) of {p:?}");
                        }
                    }
                }
                assert!(cover.iter().all(|&c| c == 1), "{w}x{h} {p:?}");
            }
        }
    }

    #[test]
    fn the_walk_visits_exactly_the_brute_force_blocks_and_bands_add_up() {
        for (w, h) in [(97u32, 61u32), (8, 8), (1, 1), (13, 5)] {
            for p in cases() {
                let key = |b: &OwnedBlock| (b.origin[1], b.origin[0]);
                let mut slow = enumerate(w, h, &p);
                slow.sort_by_key(key);
                let mut walked = Vec::new();
                for_each_block(w, h, &p, |b| walked.push(b));
                walked.sort_by_key(key);
                assert_eq!(walked, slow, "{w}x{h} {p:?}");
                // Band by band (as the CPU host renders): the same blocks.
                let band = p.block_size[2];
                let mut banded = Vec::new();
                let mut y = 0;
                while y < h {
                    for_each_block_in_rows(w, h, y, y + band, &p, |b| banded.push(b));
                    y += band;
                }
                banded.sort_by_key(key);
                assert_eq!(banded, slow, "{w}x{h} {p:?} in bands");
            }
        }
    }

    #[test]
    fn counts_match_brute_force() {
        for (w, h) in [(97u32, 61u32), (8, 8), (13, 5)] {
            for p in cases() {
                let mut samples = [0u64; 3];
                let mut blocks = [0u64; 3];
                for b in enumerate(w, h, &p) {
                    samples[b.region as usize] += u64::from(samples_in_block(&b, &p));
                    blocks[b.region as usize] += 1;
                }
                assert_eq!(count_samples(w, h, &p), samples, "{w}x{h} {p:?}");
                assert_eq!(count_blocks(w, h, &p), blocks, "{w}x{h} {p:?}");
            }
        }
    }

    #[test]
    fn nesting_only_refines() {
        let (w, h) = (97, 61);
        for p in cases() {
            for b in enumerate(w, h, &p) {
                let wanted = region_of_point(block_centre(&b), &p);
                // A coarser block than its centre asks for would have a larger region index.
                assert!(b.region <= wanted, "{b:?} centre wants {wanted} in {p:?}");
                if b.region != wanted {
                    // Overridden by the nesting: the enclosing coarser-grid square was not coarse.
                    if b.region == REGION_INTERMEDIATE {
                        assert!(!is_periphery_block(
                            b.origin[0] / p.block_size[2] * p.block_size[2],
                            b.origin[1] / p.block_size[2] * p.block_size[2],
                            &p
                        ));
                    } else {
                        let bi = p.block_size[1];
                        assert!(!is_intermediate_block(
                            b.origin[0] / bi * bi,
                            b.origin[1] / bi * bi,
                            &p
                        ));
                    }
                }
            }
        }
    }

    #[test]
    fn unnested_case_uses_centre_regions() {
        // With all block sizes 1 every block is a pixel and its region is its centre's region.
        let mut p = FoveationParams::paper([20.0, 10.0], 4.0, 9.0);
        p.block_size = [1, 1, 1, 0];
        for y in 0..30 {
            for x in 0..40 {
                let b = owning_block(x, y, &p);
                assert_eq!(b.origin, [x, y]);
                assert_eq!(
                    b.region,
                    region_of_point(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), &p)
                );
            }
        }
    }

    #[test]
    fn sample_positions_cover_the_clipped_footprint() {
        let p = FoveationParams::paper([0.0, 0.0], 0.0, 0.0);
        // 10 × 7 image: the periphery block at (8, 4) is clipped to 2 × 3.
        let b = owning_block(9, 6, &p);
        assert_eq!(
            b,
            OwnedBlock {
                region: REGION_PERIPHERY,
                size: 4,
                origin: [8, 4]
            }
        );
        assert_eq!(block_extent(&b, 10, 7), [2, 3]);
        assert_eq!(
            block_sample_position(&b, 10, 7, Vec2::ZERO),
            Vec2::new(8.0, 4.0)
        );
        let q = block_sample_position(&b, 10, 7, Vec2::new(0.999_999, 0.5));
        assert!(q.x < 10.0 && q.x > 9.99 && (q.y - 5.5).abs() < 1e-6);
        assert_eq!(block_centre(&b), Vec2::new(10.0, 6.0));
        assert_eq!(samples_in_block(&b, &p), 8);
    }

    #[test]
    fn paper_4k_sample_ratio() {
        // Gaze at the centre of a 4K frame, radii from 5.2° / 17°: about 30.6x fewer primary samples.
        let p = FoveationParams::paper([1920.0, 1080.0], 147.67, 486.02);
        let s = count_samples(3840, 2160, &p);
        let total: u64 = s.iter().sum();
        let ratio = (3840.0 * 2160.0 * 32.0) / total as f64;
        assert!((ratio - 30.6).abs() < 0.1, "ratio {ratio}");
        let b = count_blocks(3840, 2160, &p);
        assert_eq!(b[0] * 32, s[0]);
        assert_eq!(b[2] * 8, s[2]);
        // Fovea area ≈ π r².
        let area = core::f32::consts::PI * 147.67 * 147.67;
        assert!(((b[0] as f32) - area).abs() / area < 0.01);
    }

    #[test]
    fn uniform_has_one_block_per_pixel() {
        let p = FoveationParams::uniform(5);
        assert_eq!(count_blocks(97, 61, &p), [97 * 61, 0, 0]);
        assert_eq!(count_samples(97, 61, &p), [97 * 61 * 5, 0, 0]);
    }
}
