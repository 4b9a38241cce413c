//! The region overlay: a tone-mapped pixel tinted by the region of the block that owns it, with block
//! edges darkened, so that a viewer sees where the fovea, the intermediate ring and the periphery are
//! (`fovea render --regions-overlay` and the live view's overlay key). One function per pixel, so the CPU
//! and the GPU kernel draw the same overlay.
use crate::foveation::blocks::owning_block;
use crate::foveation::regions::FoveationParams;
use crate::post::tonemap::pack_rgba8;

/// Tints of the regions in the overlay (linear 0..1 on the sRGB bytes): fovea green, intermediate amber,
/// periphery blue.
pub const REGION_TINTS: [[f32; 3]; 3] = [[0.2, 0.85, 0.3], [1.0, 0.7, 0.1], [0.25, 0.45, 1.0]];

/// Weight of the tint in the blend (the render keeps the rest).
const TINT_WEIGHT: f32 = 0.5;
/// Brightness of a block's first row and column.
const EDGE_SHADE: f32 = 0.6;

/// One 8-bit channel `base` blended with `tint`, darkened on a block edge (round to nearest).
#[inline]
#[must_use]
pub fn overlay_channel(base: u32, tint: f32, edge: bool) -> u32 {
    let v = (1.0 - TINT_WEIGHT) * (base & 0xFF) as f32 / 255.0 + TINT_WEIGHT * tint;
    let v = if edge { v * EDGE_SHADE } else { v };
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u32
}

/// Pixel (`x`, `y`) of a tone-mapped RGBA8 image (`rgba`, R in the low byte) with the overlay drawn
/// over it: tinted by its owning block's region, darkened on the first row and column of blocks larger
/// than a pixel. Alpha becomes 255.
#[inline]
#[must_use]
pub fn overlay_rgba8(rgba: u32, x: u32, y: u32, foveation: &FoveationParams) -> u32 {
    let block = owning_block(x, y, foveation);
    let region = if block.region > 2 { 2 } else { block.region };
    let tint = REGION_TINTS[region as usize];
    let edge = block.size > 1 && (x == block.origin[0] || y == block.origin[1]);
    pack_rgba8(
        overlay_channel(rgba, tint[0], edge),
        overlay_channel(rgba >> 8, tint[1], edge),
        overlay_channel(rgba >> 16, tint[2], edge),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fovea_pixels_are_tinted_green_and_block_edges_are_darker() {
        let fov = FoveationParams {
            gaze: [32.0, 32.0],
            radius_fovea: 4.0,
            radius_intermediate: 12.0,
            spp: [32, 16, 8, 0],
            block_size: [1, 2, 4, 0],
        };
        let black = pack_rgba8(0, 0, 0);
        let centre = overlay_rgba8(black, 32, 32, &fov);
        let [r, g, b] = [centre & 0xFF, (centre >> 8) & 0xFF, (centre >> 16) & 0xFF];
        assert!(g > r && g > b, "fovea tint is green: {r} {g} {b}");
        // A periphery block's origin pixel is darker than its interior.
        let edge = overlay_rgba8(black, 0, 0, &fov);
        let inner = overlay_rgba8(black, 1, 1, &fov);
        assert!((edge >> 16) & 0xFF < (inner >> 16) & 0xFF);
        assert_eq!(edge >> 24, 255);
    }
}
