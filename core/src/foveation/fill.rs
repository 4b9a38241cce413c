//! Block fill: from one value per block to a full-resolution image (Mohanto et al. 2023, section 3.4,
//! "the missing pixels are filled ... using standard linear interpolation").
//!
//! Two passes, each a pure function per output element so that a GPU can run them as kernels:
//!
//! - *Pass 0* (the renderer) writes the *replicated* image: every pixel of a block holds the block's mean
//!   sample value (`[f32; 4]` per pixel, rgb and an unused `w`).
//! - *Pass 1* ([`cell_mean_at`]) computes, for each block size `b > 1` in use, the grid of cell means: the
//!   mean of the replicated image over each aligned (clipped) `b × b` cell. A cell owned by one block gets
//!   that block's value, a cell inside a coarser block the coarser value, a cell split into finer blocks the
//!   area-weighted mean of their values. The grids of all sizes share one buffer ([`cell_grid_offset`]).
//! - *Pass 2* ([`fill_pixel`]): pixels of blocks of size 1 keep their value; a pixel of a block of size
//!   `b > 1` takes the bilinear interpolation, at its centre, of the 4 nearest cell centres of the `b` grid,
//!   with cell indices clamped at the image border. [`FILL_REPLICATE`] keeps the block value instead (what
//!   the paper's code does).
//!
//! Cell centres: a full cell's centre is `cell · b + b / 2`. A cell clipped by the right or bottom image
//! edge uses the centre of its clipped footprint instead, which is where the jittered samples of a clipped
//! block ([`super::blocks::block_sample_position`]) are centred; it equals `cell · b + b / 2` for full
//! cells.
//!
//! Why the fill is continuous across region borders: the cell grids are image-wide and do not depend on
//! the regions, the fill of a pixel is a weighted mean of cell values whose weights vary continuously with
//! the pixel position, and a cell that straddles a border carries the mean of the blocks on both sides. A
//! coarse pixel next to a finer region therefore interpolates towards the mean of the fine values across
//! the border, and a fine pixel next to a coarser region towards the coarse block's value (the cells inside
//! a coarse block carry its value), so both sides converge to the same values at the border instead of
//! meeting with the step that block replication leaves. The two sides are different interpolants, so
//! the fill is not exactly continuous for every image, but the remaining jump is of the order of the
//! coarse block's own sampling error. For an affine image the fill is exact in every pixel of the coarsest
//! block size and every pixel whose four cells are not inside coarser blocks (a cell mean of an affine
//! image is its value at the cell's centre, and bilinear interpolation reproduces affine functions); in a
//! finer ring next to a coarser one the error is at most a fraction of the gradient times the coarse block
//! size.
use glam::{Vec3, Vec4};

use super::blocks::owning_block;
use super::regions::{FoveationParams, REGION_COUNT};
use crate::math::float::floor;

/// Fill mode: bilinear interpolation between cell centres (the paper's "standard linear interpolation").
pub const FILL_BILINEAR: u32 = 0;
/// Fill mode: every pixel keeps its block's value (the paper's public code).
pub const FILL_REPLICATE: u32 = 1;

/// Pass 0's value of a block: the mean of its `spp` samples (`sum` of them, added in sample order from
/// zero), alpha 1, which every pixel of the block holds in the replicated image. Both hosts write it.
#[inline]
#[must_use]
pub fn block_mean(sum: Vec3, spp: u32) -> [f32; 4] {
    let mean = sum / spp.max(1) as f32;
    [mean.x, mean.y, mean.z, 1.0]
}

/// Dimensions of the grid of aligned `b × b` cells covering a `width × height` image (partial cells at
/// the right and bottom count).
#[inline]
#[must_use]
pub fn cell_grid_size(width: u32, height: u32, b: u32) -> [u32; 2] {
    [width.div_ceil(b), height.div_ceil(b)]
}

/// The first region whose block size equals that of `region` (block sizes are non-decreasing, so equal
/// sizes are adjacent); regions with the same block size share one cell grid.
#[inline]
#[must_use]
fn grid_region(params: &FoveationParams, region: u32) -> u32 {
    let mut g = region;
    while g > 0 && params.block_size[(g - 1) as usize] == params.block_size[region as usize] {
        g -= 1;
    }
    g
}

/// Whether `region` stores a cell grid in the cell buffer: its block size is above 1 and no finer region
/// has the same size.
#[inline]
#[must_use]
fn has_grid(params: &FoveationParams, region: u32) -> bool {
    params.block_size[region as usize] > 1 && grid_region(params, region) == region
}

/// Number of cells of `region`'s grid, 0 for a region without its own grid.
#[inline]
#[must_use]
fn grid_cells(width: u32, height: u32, params: &FoveationParams, region: u32) -> u32 {
    if has_grid(params, region) {
        let g = cell_grid_size(width, height, params.block_size[region as usize]);
        g[0] * g[1]
    } else {
        0
    }
}

/// Offset in the cell buffer of the cell grid a pixel of `region` interpolates (row-major, `cell_x`
/// fastest). Grids are stored for each distinct block size above 1, finest first.
#[must_use]
pub fn cell_grid_offset(width: u32, height: u32, params: &FoveationParams, region: u32) -> u32 {
    let g = grid_region(params, region);
    let mut offset = 0;
    for s in 0..g {
        offset += grid_cells(width, height, params, s);
    }
    offset
}

/// Length of the cell buffer (all grids) for a `width × height` image; 0 when all block sizes are 1.
#[must_use]
pub fn cell_buffer_len(width: u32, height: u32, params: &FoveationParams) -> u32 {
    let mut len = 0;
    for s in 0..REGION_COUNT {
        len += grid_cells(width, height, params, s);
    }
    len
}

/// Mean of the replicated image over the `b × b` cell (`cell_x`, `cell_y`) clipped to the image.
#[must_use]
pub fn cell_mean(
    replicated: &[[f32; 4]],
    width: u32,
    height: u32,
    b: u32,
    cell_x: u32,
    cell_y: u32,
) -> Vec4 {
    let x0 = cell_x * b;
    let y0 = cell_y * b;
    let x1 = (x0 + b).min(width);
    let y1 = (y0 + b).min(height);
    let mut sum = Vec4::ZERO;
    for y in y0..y1 {
        for x in x0..x1 {
            sum += Vec4::from(replicated[(y * width + x) as usize]);
        }
    }
    let count = (x1 - x0) * (y1 - y0);
    if count == 0 {
        Vec4::ZERO
    } else {
        sum / count as f32
    }
}

/// Which cell element `index` of the cell buffer is (see [`cell_grid_offset`]): its grid's block edge
/// `b` and the cell's column and row, `[b, cell_x, cell_y]`; `b` is 0 past the buffer's end.
#[must_use]
pub fn cell_at(width: u32, height: u32, params: &FoveationParams, index: u32) -> [u32; 3] {
    let mut base = 0;
    for s in 0..REGION_COUNT {
        let n = grid_cells(width, height, params, s);
        if index < base + n {
            let b = params.block_size[s as usize];
            let gw = cell_grid_size(width, height, b)[0];
            let local = index - base;
            return [b, local % gw, local / gw];
        }
        base += n;
    }
    [0, 0, 0]
}

/// Pass 1 kernel: element `index` of the cell buffer (see [`cell_grid_offset`]); zero past its end.
#[must_use]
pub fn cell_mean_at(
    replicated: &[[f32; 4]],
    width: u32,
    height: u32,
    params: &FoveationParams,
    index: u32,
) -> Vec4 {
    let [b, cx, cy] = cell_at(width, height, params, index);
    if b == 0 {
        return Vec4::ZERO;
    }
    cell_mean(replicated, width, height, b, cx, cy)
}

/// Centre along one axis of cell `i` of the `b` grid over an axis of `extent` pixels: `i · b + b / 2` for
/// full cells, the centre of the clipped footprint for the last, partial cell.
#[inline]
#[must_use]
fn cell_centre(i: u32, b: u32, extent: u32) -> f32 {
    let start = i * b;
    start as f32 + 0.5 * b.min(extent - start) as f32
}

/// Bilinear weights along one axis for the pixel `x`: the two cell indices and the weight of the second,
/// clamped at the image border.
#[inline]
#[must_use]
pub fn axis_weights(x: u32, extent: u32, b: u32, cells: u32) -> (u32, u32, f32) {
    let p = x as f32 + 0.5;
    let t = p / b as f32 - 0.5;
    if t <= 0.0 {
        return (0, 0, 0.0);
    }
    let i0 = floor(t) as u32;
    if i0 + 1 >= cells {
        return (cells - 1, cells - 1, 0.0);
    }
    let c0 = cell_centre(i0, b, extent);
    let c1 = cell_centre(i0 + 1, b, extent);
    (i0, i0 + 1, ((p - c0) / (c1 - c0)).clamp(0.0, 1.0))
}

/// Pass 2 kernel: the final value of pixel (`x`, `y`) from the replicated image and the cell buffer of
/// pass 1, in fill `mode` ([`FILL_BILINEAR`] or [`FILL_REPLICATE`]).
#[must_use]
pub fn fill_pixel(
    replicated: &[[f32; 4]],
    cell_means: &[[f32; 4]],
    width: u32,
    height: u32,
    params: &FoveationParams,
    x: u32,
    y: u32,
    mode: u32,
) -> Vec4 {
    let own = Vec4::from(replicated[(y * width + x) as usize]);
    fill_value(own, cell_means, width, height, params, x, y, mode)
}

/// [`fill_pixel`] given the pixel's own replicated value `own`: pass 2 reads no other pixel of the
/// replicated image, only the cell buffer, so a host may overwrite the replicated image with the filled
/// one in place (the CPU host does, which saves a second full-resolution buffer).
#[must_use]
pub fn fill_value(
    own: Vec4,
    cell_means: &[[f32; 4]],
    width: u32,
    height: u32,
    params: &FoveationParams,
    x: u32,
    y: u32,
    mode: u32,
) -> Vec4 {
    if mode == FILL_REPLICATE {
        return own;
    }
    let block = owning_block(x, y, params);
    let b = block.size;
    if b <= 1 {
        return own;
    }
    let offset = cell_grid_offset(width, height, params, block.region);
    let grid = cell_grid_size(width, height, b);
    let (x0, x1, fx) = axis_weights(x, width, b, grid[0]);
    let (y0, y1, fy) = axis_weights(y, height, b, grid[1]);
    let at = |cx: u32, cy: u32| Vec4::from(cell_means[(offset + cy * grid[0] + cx) as usize]);
    let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
    let bottom = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
    top * (1.0 - fy) + bottom * fy
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec;
    use std::vec::Vec;

    use super::*;
    use crate::foveation::blocks::{block_sample_position, OwnedBlock};
    use crate::foveation::regions::{REGION_FOVEA, REGION_INTERMEDIATE, REGION_PERIPHERY};
    use glam::Vec2;

    /// Pass 0 with an exact "renderer": every pixel of a block gets `f` at the block's sample centroid
    /// (the centre of its clipped footprint).
    fn replicate(w: u32, h: u32, p: &FoveationParams, f: impl Fn(Vec2) -> Vec4) -> Vec<[f32; 4]> {
        let mut img = vec![[0.0f32; 4]; (w * h) as usize];
        for y in 0..h {
            for x in 0..w {
                let b = owning_block(x, y, p);
                let c = block_sample_position(&b, w, h, Vec2::splat(0.5));
                img[(y * w + x) as usize] = f(c).to_array();
            }
        }
        img
    }

    fn cells(img: &[[f32; 4]], w: u32, h: u32, p: &FoveationParams) -> Vec<[f32; 4]> {
        (0..cell_buffer_len(w, h, p))
            .map(|i| cell_mean_at(img, w, h, p, i).to_array())
            .collect()
    }

    fn params() -> Vec<FoveationParams> {
        let mut out = Vec::new();
        for b in [
            [1, 2, 4],
            [2, 4, 8],
            [1, 2, 8],
            [1, 4, 4],
            [1, 3, 6],
            [1, 1, 1],
        ] {
            for g in [[40.0, 25.0], [3.0, 58.0], [-30.0, 10.0]] {
                let mut p = FoveationParams::paper(g, 6.0, 19.0);
                p.block_size = [b[0], b[1], b[2], 0];
                out.push(p);
            }
        }
        out
    }

    #[test]
    fn buffer_layout() {
        let p = FoveationParams::paper([0.0, 0.0], 1.0, 2.0);
        // 97 × 61: 2-grid 49 × 31, 4-grid 25 × 16.
        assert_eq!(cell_grid_size(97, 61, 2), [49, 31]);
        assert_eq!(cell_grid_size(97, 61, 4), [25, 16]);
        assert_eq!(cell_grid_offset(97, 61, &p, REGION_INTERMEDIATE), 0);
        assert_eq!(cell_grid_offset(97, 61, &p, REGION_PERIPHERY), 49 * 31);
        assert_eq!(cell_buffer_len(97, 61, &p), 49 * 31 + 25 * 16);
        // Shared grid when two regions have the same block size.
        let mut q = p;
        q.block_size = [1, 4, 4, 0];
        assert_eq!(cell_buffer_len(97, 61, &q), 25 * 16);
        assert_eq!(cell_grid_offset(97, 61, &q, REGION_PERIPHERY), 0);
        // A fovea block size above 1 has its own grid, first.
        q.block_size = [2, 4, 8, 0];
        assert_eq!(cell_grid_offset(97, 61, &q, REGION_FOVEA), 0);
        assert_eq!(cell_grid_offset(97, 61, &q, REGION_INTERMEDIATE), 49 * 31);
        assert_eq!(cell_buffer_len(97, 61, &q), 49 * 31 + 25 * 16 + 13 * 8);
        assert_eq!(cell_buffer_len(97, 61, &FoveationParams::uniform(1)), 0);
    }

    #[test]
    fn constant_image_stays_constant() {
        let (w, h) = (97, 61);
        let c = Vec4::new(0.25, 1.5, 3.0, 0.0);
        for p in params() {
            let img = vec![c.to_array(); (w * h) as usize];
            let cm = cells(&img, w, h, &p);
            for y in 0..h {
                for x in 0..w {
                    for mode in [FILL_BILINEAR, FILL_REPLICATE] {
                        let v = fill_pixel(&img, &cm, w, h, &p, x, y, mode);
                        assert!((v - c).abs().max_element() < 1e-6, "{v} at ({x}, {y})");
                    }
                }
            }
        }
    }

    #[test]
    fn cell_means_follow_ownership() {
        // 16 × 16, fovea around (4, 4): block values are their region index + origin tag.
        let (w, h) = (16, 16);
        let p = FoveationParams::paper([4.0, 4.0], 1.5, 4.0);
        let value = |b: &OwnedBlock| (b.region * 1000 + b.origin[1] * 16 + b.origin[0]) as f32;
        let mut img = vec![[0.0f32; 4]; 256];
        for y in 0..h {
            for x in 0..w {
                img[(y * w + x) as usize] = [value(&owning_block(x, y, &p)), 0.0, 0.0, 0.0];
            }
        }
        let mut seen = [0; 3];
        for b in [2u32, 4] {
            let g = cell_grid_size(w, h, b);
            for cy in 0..g[1] {
                for cx in 0..g[0] {
                    let m = cell_mean(&img, w, h, b, cx, cy).x;
                    // Blocks overlapping the cell, by area.
                    let mut sum = 0.0;
                    let mut owners = Vec::new();
                    for y in cy * b..cy * b + b {
                        for x in cx * b..cx * b + b {
                            let o = owning_block(x, y, &p);
                            sum += value(&o);
                            if !owners.contains(&o) {
                                owners.push(o);
                            }
                        }
                    }
                    assert!((m - sum / (b * b) as f32).abs() < 1e-3);
                    if owners.len() == 1 {
                        assert_eq!(m, value(&owners[0]));
                        if owners[0].size > b {
                            seen[0] += 1; // covered by a coarser block
                        } else {
                            seen[1] += 1; // exactly one block
                        }
                    } else {
                        assert!(owners.iter().all(|o| o.size < b));
                        seen[2] += 1; // split into finer blocks
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s > 0), "{seen:?}");
    }

    #[test]
    fn affine_ramp_is_reproduced() {
        // Block values sampled from an affine image are interpolated back exactly in pixels of the
        // coarsest block size wherever the pixel centre lies between cell centres (everywhere except the
        // outer half cell at the image border), including next to finer regions; finer pixels next to
        // coarser blocks are within half a coarse block of gradient.
        let (w, h) = (97, 61);
        let f = |q: Vec2| {
            Vec4::new(
                0.3 * q.x - 0.2 * q.y + 5.0,
                0.1 * q.y,
                2.0 - 0.05 * q.x,
                0.0,
            )
        };
        let mut checked_periphery = 0;
        for p in params() {
            let img = replicate(w, h, &p, f);
            let cm = cells(&img, w, h, &p);
            for y in 0..h {
                for x in 0..w {
                    let b = owning_block(x, y, &p);
                    let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let inside = |q: f32, n: u32| {
                        let last = (n - 1) / b.size * b.size;
                        q >= 0.5 * b.size as f32
                            && q <= last as f32 + 0.5 * (n - last).min(b.size) as f32
                    };
                    if b.size > 1 && !(inside(centre.x, w) && inside(centre.y, h)) {
                        continue;
                    }
                    let v = fill_pixel(&img, &cm, w, h, &p, x, y, FILL_BILINEAR);
                    let want = f(centre);
                    let err = (v - want).abs().max_element();
                    if b.size == 1 || b.size == p.block_size[2] {
                        assert!(err < 2e-4, "{v} vs {want} at ({x}, {y}) {b:?} {p:?}");
                    } else {
                        // Largest L1 gradient of f is 0.5.
                        assert!(
                            err <= 0.25 * p.block_size[2] as f32 + 1e-4,
                            "{err} {b:?} {p:?}"
                        );
                    }
                    if b.region == REGION_PERIPHERY && b.size > 1 {
                        checked_periphery += 1;
                    }
                }
            }
        }
        assert!(checked_periphery > 1000);
    }

    #[test]
    fn replicate_mode_returns_the_block_value() {
        let (w, h) = (37, 23);
        let p = FoveationParams::paper([10.0, 10.0], 3.0, 8.0);
        let f = |q: Vec2| Vec4::new(q.x * q.y, q.x, q.y, 0.0);
        let img = replicate(w, h, &p, f);
        let cm = cells(&img, w, h, &p);
        for y in 0..h {
            for x in 0..w {
                let b = owning_block(x, y, &p);
                let want = f(block_sample_position(&b, w, h, Vec2::splat(0.5)));
                assert_eq!(fill_pixel(&img, &cm, w, h, &p, x, y, FILL_REPLICATE), want);
                if b.size == 1 {
                    assert_eq!(fill_pixel(&img, &cm, w, h, &p, x, y, FILL_BILINEAR), want);
                }
            }
        }
    }

    #[test]
    fn bilinear_beats_replication_on_smooth_images() {
        let (w, h) = (97, 61);
        let f = |q: Vec2| {
            let s = crate::math::float::sin(0.11 * q.x) * crate::math::float::cos(0.07 * q.y);
            Vec4::new(s, 0.0, 0.0, 0.0)
        };
        let p = FoveationParams::paper([48.0, 30.0], 6.0, 15.0);
        let img = replicate(w, h, &p, f);
        let cm = cells(&img, w, h, &p);
        let (mut e_bilinear, mut e_replicate, mut jump_b, mut jump_r) =
            (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        let mut prev = (0.0f32, 0.0f32);
        for y in 0..h {
            for x in 0..w {
                let want = f(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).x;
                let vb = fill_pixel(&img, &cm, w, h, &p, x, y, FILL_BILINEAR).x;
                let vr = fill_pixel(&img, &cm, w, h, &p, x, y, FILL_REPLICATE).x;
                e_bilinear += (vb - want).abs();
                e_replicate += (vr - want).abs();
                if x > 0 {
                    jump_b = jump_b.max((vb - prev.0).abs());
                    jump_r = jump_r.max((vr - prev.1).abs());
                }
                prev = (vb, vr);
            }
        }
        assert!(
            e_bilinear < 0.5 * e_replicate,
            "{e_bilinear} vs {e_replicate}"
        );
        assert!(jump_b < 0.6 * jump_r, "{jump_b} vs {jump_r}");
    }
}
