//! Albedo demodulation: the history and the denoiser keep *lighting* (radiance divided by the albedo
//! that the samples saw), and each displayed pixel takes its texture from its own first hit.
//!
//! Texture is what a camera move and a coarse block blur most. Dividing it out before the history is
//! resampled ([`super::reproject`]) or the denoiser filters, and multiplying the pixel's own albedo back
//! in afterwards, keeps it sharp: SVGF's demodulation (Schied et al. 2017, section 4), which kajiya and
//! strolle also use. The albedo a filled value saw ([`filled_albedo`]) is the fill's own blend of
//! block means ([`crate::foveation::fill`]) applied to the G-buffer's albedo: a 4 × 4 periphery block's
//! samples land anywhere in its 16 pixels, and a filled pixel blends four blocks. The albedo it is
//! shown with is the pixel's own G-buffer texel ([`demodulation_albedo`]), which puts back, at full
//! resolution, the texture a coarse block averaged away.
use glam::Vec3;

use super::gbuffer::GBufferTexel;
use crate::foveation::fill::{
    axis_weights, cell_at, cell_grid_offset, cell_grid_size, FILL_REPLICATE,
};
use crate::foveation::owning_block;
use crate::integrator::FrameParams;
use crate::math::vec3_from;

/// Albedo channels below this are not divided by (black surfaces would amplify noise).
pub const ALBEDO_MIN: f32 = 0.01;

/// The albedo a pixel is demodulated and remodulated by: the G-buffer's base colour, each channel at
/// least [`ALBEDO_MIN`]; 1 for the sky.
#[inline]
#[must_use]
pub fn demodulation_albedo(g: &GBufferTexel) -> Vec3 {
    if g.is_sky() {
        return Vec3::ONE;
    }
    vec3_from(g.albedo).max(Vec3::splat(ALBEDO_MIN))
}

/// The mean [`demodulation_albedo`] over the `b × b` block at `origin` (clipped to the image): the
/// albedo that the block's samples saw.
#[must_use]
pub fn block_albedo(
    frame: &FrameParams,
    gbuffer: &[GBufferTexel],
    origin: [u32; 2],
    b: u32,
) -> Vec3 {
    let x_end = (origin[0] + b).min(frame.width);
    let y_end = (origin[1] + b).min(frame.height);
    let mut sum = Vec3::ZERO;
    let mut n = 0.0f32;
    let mut y = origin[1];
    while y < y_end {
        let mut x = origin[0];
        while x < x_end {
            sum += demodulation_albedo(&gbuffer[(y * frame.width + x) as usize]);
            n += 1.0;
            x += 1;
        }
        y += 1;
    }
    if n > 0.0 {
        sum / n
    } else {
        Vec3::ONE
    }
}

/// The cell-albedo pass: element `index` of the cell buffer holds the mean [`demodulation_albedo`]
/// of its cell's pixels ([`block_albedo`]), laid out as the cell means are
/// ([`crate::foveation::fill::cell_grid_offset`]); zero past the buffer's end. Computed once per frame
/// after the G-buffer, so that [`filled_albedo`] reads four values instead of averaging four cells'
/// texels for every pixel.
#[must_use]
pub fn cell_albedo_at(frame: &FrameParams, gbuffer: &[GBufferTexel], index: u32) -> Vec3 {
    let [b, cx, cy] = cell_at(frame.width, frame.height, &frame.foveation, index);
    if b == 0 {
        return Vec3::ZERO;
    }
    block_albedo(frame, gbuffer, [cx * b, cy * b], b)
}

/// The albedo behind pixel (`x`, `y`)'s filled value in fill `mode`: its own G-buffer albedo in a
/// block of one pixel; its block's mean (its cell's, blocks being aligned to their grid) under
/// [`crate::foveation::FILL_REPLICATE`];
/// else the fill's bilinear blend of the four cells around it
/// ([`crate::foveation::fill::fill_value`]), each cell's value the mean albedo of its pixels
/// (`cell_albedo`, made by [`cell_albedo_at`]), which is what the block of that size there saw.
/// Dividing the filled radiance by it leaves the lighting (exactly, where the lighting is constant over
/// the four cells).
#[must_use]
pub fn filled_albedo(
    frame: &FrameParams,
    gbuffer: &[GBufferTexel],
    cell_albedo: &[[f32; 4]],
    mode: u32,
    x: u32,
    y: u32,
) -> Vec3 {
    let block = owning_block(x, y, &frame.foveation);
    let b = block.size.max(1);
    if b == 1 {
        return demodulation_albedo(&gbuffer[(y * frame.width + x) as usize]);
    }
    let offset = cell_grid_offset(frame.width, frame.height, &frame.foveation, block.region);
    let grid = cell_grid_size(frame.width, frame.height, b);
    let at = |cx: u32, cy: u32| vec3_from(cell_albedo[(offset + cy * grid[0] + cx) as usize]);
    if mode == FILL_REPLICATE {
        // Blocks are aligned to their size's grid: the block is the cell the pixel lies in.
        return at(x / b, y / b);
    }
    let (x0, x1, fx) = axis_weights(x, frame.width, b, grid[0]);
    let (y0, y1, fy) = axis_weights(y, frame.height, b, grid[1]);
    let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
    let bottom = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// For the core's tests.
#[cfg(test)]
pub(crate) mod test_support {
    extern crate std;
    use std::vec::Vec;

    use super::*;

    /// The cell-albedo pass over a whole frame, serially (the hosts run [`cell_albedo_at`] in
    /// parallel).
    pub(crate) fn cell_albedo_buffer(
        frame: &FrameParams,
        gbuffer: &[GBufferTexel],
    ) -> Vec<[f32; 4]> {
        let len = crate::foveation::cell_buffer_len(frame.width, frame.height, &frame.foveation);
        (0..len)
            .map(|i| cell_albedo_at(frame, gbuffer, i).extend(0.0).to_array())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec;
    use std::vec::Vec;

    use super::*;
    use crate::camera::Camera;
    use crate::foveation::FoveationParams;
    use crate::integrator::IntegratorSettings;

    fn texel(albedo: f32) -> GBufferTexel {
        GBufferTexel {
            normal_distance: [0.0, 0.0, 1.0, 2.0],
            albedo: [albedo, albedo, albedo, 1.0],
        }
    }

    #[test]
    fn black_is_not_divided_by_and_the_sky_is_one() {
        assert_eq!(demodulation_albedo(&texel(0.0)), Vec3::splat(ALBEDO_MIN));
        assert_eq!(demodulation_albedo(&texel(0.5)), Vec3::splat(0.5));
        assert_eq!(demodulation_albedo(&GBufferTexel::SKY), Vec3::ONE);
    }

    #[test]
    fn a_block_sees_its_pixels_mean_clipped_to_the_image() {
        let frame = FrameParams {
            camera: Camera::default(),
            foveation: FoveationParams::paper([0.5, 0.5], 1.5, 3.0),
            integrator: IntegratorSettings::default(),
            width: 3,
            height: 2,
            frame_index: 0,
            seed: 0,
        };
        let g = [0.1, 0.3, 0.9, 0.5, 0.7, 0.9].map(texel);
        assert!((block_albedo(&frame, &g, [0, 0], 2).x - 0.4).abs() < 1e-6);
        // The block at (2, 0) is clipped to its one column.
        assert!((block_albedo(&frame, &g, [2, 0], 4).x - 0.9).abs() < 1e-6);
    }

    #[test]
    fn a_filled_pixel_sees_the_fill_s_blend_of_its_blocks_albedo() {
        use crate::foveation::fill::{cell_buffer_len, cell_mean_at, fill_pixel, FILL_BILINEAR};
        // A 16 x 8 image, gaze far away: all 4 x 4 periphery blocks. The G-buffer albedo varies per
        // pixel; "radiance" = albedo x a constant light of 3, replicated per block as the samples give.
        let frame = FrameParams {
            camera: Camera::default(),
            foveation: FoveationParams::paper([-500.0, -500.0], 1.5, 3.0),
            integrator: IntegratorSettings::default(),
            width: 16,
            height: 8,
            frame_index: 0,
            seed: 0,
        };
        let g: Vec<_> = (0..128u32)
            .map(|i| texel(0.1 + 0.8 * (((i * 7) % 11) as f32 / 10.0)))
            .collect();
        let mut replicated = vec![[0.0f32; 4]; 128];
        for y in 0..8u32 {
            for x in 0..16u32 {
                let o = [x / 4 * 4, y / 4 * 4];
                let a = block_albedo(&frame, &g, o, 4).x * 3.0;
                replicated[(y * 16 + x) as usize] = [a, a, a, 1.0];
            }
        }
        let f = &frame.foveation;
        let cells: Vec<[f32; 4]> = (0..cell_buffer_len(16, 8, f))
            .map(|i| cell_mean_at(&replicated, 16, 8, f, i).to_array())
            .collect();
        let cell_albedo = super::test_support::cell_albedo_buffer(&frame, &g);
        for y in 0..8u32 {
            for x in 0..16u32 {
                let filled = fill_pixel(&replicated, &cells, 16, 8, f, x, y, FILL_BILINEAR);
                let a = filled_albedo(&frame, &g, &cell_albedo, FILL_BILINEAR, x, y);
                assert!(
                    (filled.x / a.x - 3.0).abs() < 1e-4,
                    "({x}, {y}): {filled} / {a}"
                );
                let own = filled_albedo(&frame, &g, &cell_albedo, FILL_REPLICATE, x, y);
                let r = Vec3::from_slice(&replicated[(y * 16 + x) as usize][..3]);
                assert!((r.x / own.x - 3.0).abs() < 1e-4);
            }
        }
    }
}
