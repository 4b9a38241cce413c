//! A foveated SVGF-like denoiser (after Schied et al. 2017, "Spatiotemporal Variance-Guided
//! Filtering"): three passes of the frame pipeline after the history's resolve (input, the à-trous
//! steps, output), each a function of one pixel that both hosts run.
//!
//! 1. [`denoise_input`]: the pixel's *lighting*, so the filter blurs lighting, not texture: with
//!    history, what the resolve showed over the pixel's own albedo ([`crate::temporal::resolve`]), else
//!    the HDR pixel divided by the albedo its samples saw (the G-buffer's mean over its block); and a
//!    luminance variance: the history's (its second moment over its frames) where it holds at least
//!    [`DENOISE_TEMPORAL_FRAMES`] frames, else a spatial one from the pixel's block and its eight
//!    neighbouring blocks, each demodulated by its own albedo.
//! 2. [`denoise_atrous`], [`DENOISE_MAX_PASSES`] times: an à-trous wavelet step (a 5 × 5 B3-spline
//!    kernel with holes, step `2^k`) whose weights stop at depth and normal edges and at luminance
//!    differences large against the noise (`σ_l √variance`); the variance is filtered with the squared
//!    weights.
//! 3. [`denoise_output`]: remodulated by the pixel's own albedo, which puts back, at full resolution,
//!    the texture that a coarse block's samples averaged away.
//!
//! **Foveated.** How many à-trous steps a pixel takes follows the samples behind it
//! ([`denoise_passes`]): `spp / b²` of its block (32 in the paper's fovea, 4 in the intermediate ring,
//! 0.5 in the periphery) or, with history, those behind the resolve's blend when more; and at most as
//! many as the eye resolves at its eccentricity ([`acuity_passes`]). The fovea at full sample count is
//! left alone (it keeps every detail it paid for); the periphery, with few samples per block and low
//! acuity, takes four or five steps, in multiples of its block edge (steps 4, 8, 16, 32 pixels for
//! 4 × 4 blocks) while the fill dominates what it shows, whose wide support reconstructs smooth lighting
//! over its block structure rather than preserving it. A converging history lowers the strength by
//! itself.
//!
//! **Bad input.** A non-finite HDR value is marked invalid: no neighbour reads it, and it takes its
//! neighbours' filtered value (or black where it has none). Finite values are clamped to
//! [`crate::temporal::HISTORY_SAMPLE_MAX`] first.
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::foveation::{owning_block, samples_in_block};
use crate::foveation::{FILL_BILINEAR, FILL_REPLICATE};
use crate::integrator::FrameParams;
use crate::math::color::{is_finite3, luminance};
use crate::math::float::{exp, sqrt};
use crate::math::vec3_from;
use crate::temporal::albedo::{demodulation_albedo, filled_albedo};
use crate::temporal::HISTORY_SAMPLE_MAX;
use crate::temporal::{GBufferTexel, HistoryTexel};

/// À-trous steps of the most filtered pixels (steps 1, 2, 4, 8, 16 pixels: a support of 125 pixels).
pub const DENOISE_MAX_PASSES: u32 = 5;
/// [`denoise_input`]'s `flags`: the frame has a history (temporal variance where it is long enough).
pub const DENOISE_WITH_HISTORY: u32 = 1;
/// [`denoise_input`]'s `flags`: the frame was filled with [`crate::foveation::FILL_REPLICATE`] (which
/// albedo a filled value's samples saw, [`filled_albedo`]).
pub const DENOISE_FILL_REPLICATE: u32 = 2;
/// Frames of history from which its variance replaces the spatial estimate (SVGF uses 4).
pub const DENOISE_TEMPORAL_FRAMES: f32 = 4.0;
/// The luminance edge stop `σ_l`: neighbours within a few standard deviations of noise blend.
pub const DENOISE_SIGMA_LUMINANCE: f32 = 4.0;
/// The depth edge stop: relative depth change per pixel of offset still taken as one surface (a
/// surface at 80° from the view at about a milliradian per pixel).
pub const DENOISE_DEPTH_SLOPE: f32 = 0.01;

/// The B3-spline kernel's taps at offsets 0, ±1, ±2.
const KERNEL: [f32; 3] = [3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];

/// `√(dx² + dy²)` of the kernel's taps, indexed by `dx² + dy²` (0 to 8), each the correctly rounded
/// `f32`, as `sqrt` gives it: the offset of a tap in steps. A table because `libm`'s `sqrtf` is an
/// opaque instruction on x86 that the compiler can neither fold nor schedule, and that one call per tap
/// was about two thirds of the à-trous pass's time on the CPU (docs/performance.md, "The denoiser's
/// tap offsets").
const TAP_DISTANCE: [f32; 9] = [
    0.0,
    1.0,
    core::f32::consts::SQRT_2,
    0.0, // no tap (3 = dx² + dy² has no solution)
    2.0,
    2.236_068,
    0.0, // no tap
    0.0, // no tap
    2.0 * core::f32::consts::SQRT_2,
];

/// One pixel between the denoiser's passes (32 bytes, GPU layout): `color` = (demodulated radiance
/// rgb, its luminance variance), `info` = (à-trous steps it takes, 1 if valid else 0, its block's
/// edge, 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DenoiseTexel {
    pub color: [f32; 4],
    pub info: [f32; 4],
}

impl DenoiseTexel {
    /// A pixel without a usable value.
    pub const INVALID: Self = Self {
        color: [0.0; 4],
        info: [0.0; 4],
    };

    /// The demodulated radiance.
    #[inline]
    #[must_use]
    pub fn radiance(&self) -> Vec3 {
        vec3_from(self.color)
    }

    /// Its luminance variance.
    #[inline]
    #[must_use]
    pub fn variance(&self) -> f32 {
        self.color[3]
    }

    /// À-trous steps this pixel takes.
    #[inline]
    #[must_use]
    pub fn passes(&self) -> u32 {
        self.info[0] as u32
    }

    /// The edge of the block its value came from: the à-trous steps are multiples of it (within a
    /// filled block, neighbouring pixels are interpolated, not independent).
    #[inline]
    #[must_use]
    pub fn footprint(&self) -> u32 {
        (self.info[2] as u32).max(1)
    }

    /// Whether it holds a value.
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.info[1] > 0.5
    }
}

/// À-trous steps for a pixel with `samples` samples behind its value: none at 32 or more (the paper's
/// fovea keeps every detail it paid for), 1 from 16, 2 from 8, 3 from 2, 4 from 1/2 (the paper's
/// periphery), else 5.
#[inline]
#[must_use]
pub fn denoise_passes(samples: f32) -> u32 {
    if samples >= 32.0 {
        0
    } else if samples >= 16.0 {
        1
    } else if samples >= 8.0 {
        2
    } else if samples >= 2.0 {
        3
    } else if samples >= 0.5 {
        4
    } else {
        DENOISE_MAX_PASSES
    }
}

/// The HDR value at `p`, finite and clamped to `[0, HISTORY_SAMPLE_MAX]`, or `None` if not finite.
#[inline]
fn clean(hdr: &[[f32; 4]], p: usize) -> (Vec3, bool) {
    let c = vec3_from(hdr[p]);
    if is_finite3(c) {
        (c.clamp(Vec3::ZERO, Vec3::splat(HISTORY_SAMPLE_MAX)), true)
    } else {
        (Vec3::ZERO, false)
    }
}

/// The most à-trous steps a pixel `distance` pixels from the gaze may take, for a fovea of radius
/// `radius_fovea`: acuity falls linearly with eccentricity (the minimum angle of resolution grows as
/// `ω₀ + m e`, Guenter et al. 2012), so the blur the eye does not see doubles with each doubling of
/// `1 + d / r_f`: 2 steps at the gaze, 3 at the fovea's edge, 4 at three fovea radii, 5 beyond seven.
#[inline]
#[must_use]
pub fn acuity_passes(distance: f32, radius_fovea: f32) -> u32 {
    let r = (1.0 + distance / radius_fovea.max(1.0e-3)).max(1.0);
    let mut passes = 2u32;
    let mut bound = 2.0f32;
    while r >= bound && passes < DENOISE_MAX_PASSES {
        passes += 1;
        bound *= 2.0;
    }
    passes
}

/// The demodulated value of pixel `q` for the denoiser: with history, the resolved image over the
/// pixel's own albedo (the lighting [`crate::temporal::resolve`] showed); without, the filled value
/// over the albedo its samples saw. `None` where it is not finite (or has no history).
#[allow(clippy::too_many_arguments)]
#[inline]
fn demodulated_at(
    frame: &FrameParams,
    hdr: &[[f32; 4]],
    gbuffer: &[GBufferTexel],
    cell_albedo: &[[f32; 4]],
    flags: u32,
    x: u32,
    y: u32,
) -> (Vec3, bool) {
    let q = (y * frame.width + x) as usize;
    let (c, valid) = clean(hdr, q);
    if !valid {
        return (Vec3::ZERO, false);
    }
    let albedo = if flags & DENOISE_WITH_HISTORY != 0 {
        demodulation_albedo(&gbuffer[q])
    } else {
        let mode = if flags & DENOISE_FILL_REPLICATE != 0 {
            FILL_REPLICATE
        } else {
            FILL_BILINEAR
        };
        filled_albedo(frame, gbuffer, cell_albedo, mode, x, y)
    };
    (c / albedo, true)
}

/// The first pass at pixel (`x`, `y`): its HDR value demodulated, its variance and its number of
/// à-trous steps. `history` is read only with [`DENOISE_WITH_HISTORY`] in `flags`; `cell_albedo`
/// (the cell-albedo pass's buffer, [`crate::temporal::albedo::cell_albedo_at`]) only without it.
///
/// **Strength.** The steps a pixel needs follow the samples behind what it shows
/// ([`denoise_passes`]): `spp / b²` of its block, or with history those of the blend
/// [`crate::temporal::resolve`] showed, its own samples' weight for their share `s` and the fill
/// average's (`spp / b²` a frame) for the rest. They are capped by what the eye resolves at the
/// pixel's eccentricity ([`acuity_passes`]).
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn denoise_input(
    frame: &FrameParams,
    hdr: &[[f32; 4]],
    gbuffer: &[GBufferTexel],
    cell_albedo: &[[f32; 4]],
    history: &[HistoryTexel],
    flags: u32,
    x: u32,
    y: u32,
) -> DenoiseTexel {
    let (w, h) = (frame.width, frame.height);
    let p = (y * w + x) as usize;
    let block = owning_block(x, y, &frame.foveation);
    let b = block.size.max(1);
    let mut samples = samples_in_block(&block, &frame.foveation) as f32 / (b * b) as f32;
    let with_history = flags & DENOISE_WITH_HISTORY != 0;
    // The value to filter, demodulated. `denoise_output` remodulates by the pixel's own albedo, which
    // puts back texture the blocks blurred.
    let (demodulated, valid) = demodulated_at(frame, hdr, gbuffer, cell_albedo, flags, x, y);
    if !valid {
        return DenoiseTexel::INVALID;
    }

    let mut variance = -1.0;
    // With history, a pixel's own samples (32 a frame in the fovea, one every other frame in the
    // periphery) are what it shows; the fill's share is spatial.
    let mut footprint = b;
    if with_history {
        let t = &history[p];
        let share =
            crate::temporal::resolve::own_share(t, b, samples_in_block(&block, &frame.foveation));
        samples = samples.max(share * t.weight() + (1.0 - share) * samples * t.fill_frames());
        if share >= 0.5 {
            footprint = 1;
        }
        if t.frames() >= DENOISE_TEMPORAL_FRAMES {
            // The variance of the history's mean: its frames' variance over their count.
            variance = t.luminance_variance() / t.frames().max(1.0);
        }
    }
    if variance < 0.0 {
        // Spatially: the luminance of this block and its eight neighbours (one value per block, as
        // the pixels of a filled block are not independent), each demodulated by its own albedo.
        let (mut sum, mut sum2, mut n) = (0.0f32, 0.0f32, 0.0f32);
        let mut dy = -1i32;
        while dy <= 1 {
            let mut dx = -1i32;
            while dx <= 1 {
                let qx = x as i32 + dx * b as i32;
                let qy = y as i32 + dy * b as i32;
                if qx >= 0 && qy >= 0 && (qx as u32) < w && (qy as u32) < h {
                    let (cq, ok) = demodulated_at(
                        frame,
                        hdr,
                        gbuffer,
                        cell_albedo,
                        flags,
                        qx as u32,
                        qy as u32,
                    );
                    if ok {
                        let l = luminance(cq);
                        sum += l;
                        sum2 += l * l;
                        n += 1.0;
                    }
                }
                dx += 1;
            }
            dy += 1;
        }
        let mean = sum / n.max(1.0);
        variance = (sum2 / n.max(1.0) - mean * mean).max(0.0);
    }
    let centre = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    let distance = (centre - frame.foveation.gaze()).length();
    let passes = denoise_passes(samples).min(acuity_passes(distance, frame.foveation.radius_fovea));
    DenoiseTexel {
        color: [demodulated.x, demodulated.y, demodulated.z, variance],
        info: [passes as f32, 1.0, footprint as f32, 0.0],
    }
}

/// How much the G-buffer lets pixel `q` (`offset_px` pixels away) stand in for `p`: 0 across a depth
/// or normal edge, 1 on one flat surface (or both in the sky).
#[inline]
#[must_use]
pub fn geometry_weight(p: &GBufferTexel, q: &GBufferTexel, offset_px: f32) -> f32 {
    match (p.is_sky(), q.is_sky()) {
        (true, true) => return 1.0,
        (true, false) | (false, true) => return 0.0,
        _ => {}
    }
    // max(0, n_p · n_q)^128 by seven squarings (the same arithmetic on every backend).
    let mut normal = p.normal().dot(q.normal()).max(0.0);
    let mut i = 0;
    while i < 7 {
        normal *= normal;
        i += 1;
    }
    // Across a crease the weight is 0 whatever the depths say: the exponential is left out (the
    // product would be +0 all the same).
    if normal == 0.0 {
        return 0.0;
    }
    let (zp, zq) = (p.distance(), q.distance());
    let depth = exp(-(zp - zq).abs() / (DENOISE_DEPTH_SLOPE * zp * offset_px + 1.0e-6));
    depth * normal
}

/// À-trous step `pass` (0-based; step `2^pass` pixels) at pixel (`x`, `y`) of the previous step's
/// texels, `input[base..base + width · height]` (the GPU keeps both halves in one buffer). A pixel that
/// takes fewer steps passes its texel through.
#[must_use]
pub fn denoise_atrous(
    frame: &FrameParams,
    input: &[DenoiseTexel],
    base: usize,
    gbuffer: &[GBufferTexel],
    pass: u32,
    x: u32,
    y: u32,
) -> DenoiseTexel {
    let (w, h) = (frame.width, frame.height);
    let p = (y * w + x) as usize;
    let centre = input[base + p];
    if pass >= centre.passes() && centre.is_valid() {
        return centre;
    }
    let step = (1i32 << pass) * centre.footprint() as i32;
    let lp = luminance(centre.radiance());
    let sigma = DENOISE_SIGMA_LUMINANCE * sqrt(centre.variance().max(0.0)) + 1.0e-4;
    let (mut sum_c, mut sum_v, mut sum_w) = (Vec3::ZERO, 0.0f32, 0.0f32);
    let mut dy = -2i32;
    while dy <= 2 {
        let mut dx = -2i32;
        while dx <= 2 {
            let qx = x as i32 + dx * step;
            let qy = y as i32 + dy * step;
            if qx >= 0 && qy >= 0 && (qx as u32) < w && (qy as u32) < h {
                let q = (qy as u32 * w + qx as u32) as usize;
                let t = input[base + q];
                if t.is_valid() {
                    let kernel =
                        KERNEL[dx.unsigned_abs() as usize] * KERNEL[dy.unsigned_abs() as usize];
                    let offset = step as f32 * TAP_DISTANCE[(dx * dx + dy * dy) as usize];
                    let mut weight = kernel;
                    if q != p {
                        weight *= geometry_weight(&gbuffer[p], &gbuffer[q], offset);
                        // An invalid centre has no luminance to compare with; a tap the geometry
                        // already shut out needs none (adding +0 to the sums changes nothing).
                        if centre.is_valid() && weight > 0.0 {
                            weight *= exp(-(luminance(t.radiance()) - lp).abs() / sigma);
                        }
                    }
                    if weight > 0.0 {
                        sum_c += t.radiance() * weight;
                        sum_v += t.variance() * weight * weight;
                        sum_w += weight;
                    }
                }
            }
            dx += 1;
        }
        dy += 1;
    }
    if !(sum_w > 0.0) {
        return centre;
    }
    let c = sum_c / sum_w;
    // An invalid centre takes its neighbours' value and the most passes' support from now on.
    let passes = if centre.is_valid() {
        centre.info[0]
    } else {
        DENOISE_MAX_PASSES as f32
    };
    // The footprint goes on with the texel: every step of a coarse block's pixel is a multiple of it
    // (4, 8, 16, 32 pixels for a 4 × 4 block).
    DenoiseTexel {
        color: [c.x, c.y, c.z, sum_v / (sum_w * sum_w)],
        info: [passes, 1.0, centre.info[2], 0.0],
    }
}

/// The last pass at pixel (`x`, `y`): the filtered texel (`filtered[base + pixel]`) remodulated by the
/// albedo (HDR layout, alpha 1); black where no valid value reached the pixel.
#[must_use]
pub fn denoise_output(
    frame: &FrameParams,
    filtered: &[DenoiseTexel],
    base: usize,
    gbuffer: &[GBufferTexel],
    x: u32,
    y: u32,
) -> [f32; 4] {
    let p = (y * frame.width + x) as usize;
    let t = filtered[base + p];
    if !t.is_valid() {
        return [0.0, 0.0, 0.0, 1.0];
    }
    let c = t.radiance() * demodulation_albedo(&gbuffer[p]);
    [c.x, c.y, c.z, 1.0]
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec;
    use std::vec::Vec;

    use super::*;
    use crate::foveation::regions::FoveationParams;

    fn frame(w: u32, h: u32, foveation: FoveationParams) -> FrameParams {
        FrameParams {
            width: w,
            height: h,
            foveation,
            ..bytemuck::Zeroable::zeroed()
        }
    }

    fn wall(distance: f32, albedo: f32) -> GBufferTexel {
        GBufferTexel {
            normal_distance: [0.0, 0.0, 1.0, distance],
            albedo: [albedo, albedo, albedo, 1.0],
        }
    }

    /// Runs the three passes over an image.
    fn denoise(f: &FrameParams, hdr: &[[f32; 4]], g: &[GBufferTexel]) -> Vec<[f32; 4]> {
        let (w, h) = (f.width, f.height);
        let cells = crate::temporal::albedo::test_support::cell_albedo_buffer(f, g);
        let mut a: Vec<DenoiseTexel> = (0..w * h)
            .map(|i| denoise_input(f, hdr, g, &cells, &[], 0, i % w, i / w))
            .collect();
        for pass in 0..DENOISE_MAX_PASSES {
            a = (0..w * h)
                .map(|i| denoise_atrous(f, &a, 0, g, pass, i % w, i / w))
                .collect();
        }
        (0..w * h)
            .map(|i| denoise_output(f, &a, 0, g, i % w, i / w))
            .collect()
    }

    /// A deterministic noisy value around `mean`.
    fn noisy(i: u32, mean: f32) -> f32 {
        let u = (i.wrapping_mul(2_654_435_761) >> 8) as f32 / (1u32 << 24) as f32;
        mean * (0.4 + 1.2 * u)
    }

    #[test]
    fn the_tap_distances_are_the_square_roots() {
        for dy in -2i32..=2 {
            for dx in -2i32..=2 {
                let n = (dx * dx + dy * dy) as usize;
                assert_eq!(TAP_DISTANCE[n].to_bits(), sqrt(n as f32).to_bits(), "√{n}");
            }
        }
    }

    #[test]
    fn fewer_samples_take_more_steps() {
        assert_eq!(denoise_passes(32.0), 0);
        assert_eq!(denoise_passes(4.0), 3);
        assert_eq!(denoise_passes(0.5), 4);
        assert_eq!(denoise_passes(1.0 / 16.0), DENOISE_MAX_PASSES);
    }

    #[test]
    fn noise_on_one_surface_is_smoothed_and_its_mean_kept() {
        let (w, h) = (48, 32);
        let f = frame(w, h, FoveationParams::uniform(1));
        let g = vec![wall(5.0, 0.5); (w * h) as usize];
        let hdr: Vec<[f32; 4]> = (0..w * h)
            .map(|i| {
                let v = noisy(i, 0.5);
                [v, v, v, 1.0]
            })
            .collect();
        let out = denoise(&f, &hdr, &g);
        let stats = |img: &[[f32; 4]]| {
            let n = img.len() as f32;
            let mean = img.iter().map(|p| p[0]).sum::<f32>() / n;
            let var = img
                .iter()
                .map(|p| (p[0] - mean) * (p[0] - mean))
                .sum::<f32>()
                / n;
            (mean, var)
        };
        let (m0, v0) = stats(&hdr);
        let (m1, v1) = stats(&out);
        assert!((m1 - m0).abs() < 0.02 * m0, "mean {m0} -> {m1}");
        assert!(v1 < 0.1 * v0, "variance {v0} -> {v1}");
    }

    #[test]
    fn an_edge_in_depth_or_albedo_texture_survives() {
        // Left half near, right half far: the depth stop keeps them apart. A checker albedo on the
        // near half is demodulated away and put back.
        let (w, h) = (32, 16);
        let f = frame(w, h, FoveationParams::uniform(1));
        let g: Vec<GBufferTexel> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if x < w / 2 {
                    wall(2.0, if (x + y) % 2 == 0 { 0.8 } else { 0.2 })
                } else {
                    wall(20.0, 0.5)
                }
            })
            .collect();
        let hdr: Vec<[f32; 4]> = (0..w * h)
            .map(|i| {
                let x = i % w;
                let light = if x < w / 2 { 1.0 } else { 0.1 };
                let v = light * g[i as usize].albedo[0];
                [v, v, v, 1.0]
            })
            .collect();
        let out = denoise(&f, &hdr, &g);
        for (i, (o, r)) in out.iter().zip(&hdr).enumerate() {
            assert!(
                (o[0] - r[0]).abs() < 1e-3 * r[0].max(1.0),
                "pixel {i}: {} vs {}",
                o[0],
                r[0]
            );
        }
    }

    #[test]
    fn a_nan_or_infinite_pixel_does_not_spread() {
        let (w, h) = (16, 16);
        let f = frame(w, h, FoveationParams::uniform(1));
        let g = vec![wall(3.0, 1.0); (w * h) as usize];
        let mut hdr = vec![[0.25f32, 0.25, 0.25, 1.0]; (w * h) as usize];
        hdr[5 * 16 + 5] = [f32::NAN, 0.0, 0.0, 1.0];
        hdr[9 * 16 + 9] = [f32::INFINITY, 1.0, 1.0, 1.0];
        let out = denoise(&f, &hdr, &g);
        for (i, o) in out.iter().enumerate() {
            for c in &o[..3] {
                assert!((c - 0.25).abs() < 1e-5, "pixel {i}: {o:?}");
            }
        }
    }
}
