//! Rendering one foveated frame on the CPU: core's pass list, each pass a rayon loop over its core
//! function.
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use fovea_core::denoise::{denoise_atrous, denoise_input, denoise_output, DenoiseTexel};
use fovea_core::foveation::blocks::{block_sample_range, for_each_block_in_rows, samples_in_block};
use fovea_core::foveation::fill::{block_mean, cell_buffer_len, cell_mean_at, fill_value};
use fovea_core::foveation::overlay::overlay_rgba8;
use fovea_core::foveation::regions::REGION_COUNT;
use fovea_core::integrator::{block_sample_range_sum, block_sample_sum_into_pixels, FrameParams};
use fovea_core::passes::{frame_passes, FrameOutput, FramePass, FrameRequest};
use fovea_core::post::tonemap::tonemap_to_rgba8;
use fovea_core::scene::{Features, SceneView};

use crate::specialize::{dispatch, path_mask, WithScene};
use crate::temporal::TemporalHistory;
use glam::{Vec3, Vec4};
use rayon::prelude::*;

pub use fovea_frame::{FrameImage, RenderStats, RenderedFrame};

/// The most memory the CPU host's frame holds per pixel, in bytes, with history and the denoiser on:
/// the image, the one kept from before the denoiser and the per-pixel sample sums, the RGBA8 image, the
/// cell means (at most a third of a pixel's), two history images (this frame's and the last), two
/// G-buffers and the denoiser's two halves. `fovea view` refuses a `--size` whose frames would not fit in memory (up front, rather than
/// aborting on allocation).
pub const FRAME_BYTES_PER_PIXEL: u64 = {
    use fovea_core::temporal::{GBufferTexel, HistoryTexel};
    let image = std::mem::size_of::<[f32; 4]>() as u64;
    3 * image
        + 4
        + image.div_ceil(3)
        + 2 * std::mem::size_of::<HistoryTexel>() as u64
        + 2 * std::mem::size_of::<GBufferTexel>() as u64
        + 2 * std::mem::size_of::<DenoiseTexel>() as u64
};

/// Renders one frame of `scene` by walking core's pass list ([`frame_passes`]) and running each pass's
/// CPU step: one rayon loop over its core function. With `request.history` the frame joins `history`
/// (kept from one call to the next; a frame of another size starts afresh) and the HDR image is the
/// history's mean. `progress` is called from worker threads with the camera samples just finished.
///
/// The samples are traced by the compiled path for `scene.features` ([`crate::specialize`]): pass
/// `packed.view().with_features(packed.features())` to leave out what the scene lacks, or the plain
/// view (every feature) for the general path. Both give the same image.
pub fn render_frame_passes(
    scene: &SceneView,
    frame: &FrameParams,
    request: &FrameRequest,
    history: &mut TemporalHistory,
    progress: &(dyn Fn(u64) + Sync),
) -> (RenderedFrame, RenderStats) {
    let start = Instant::now();
    let (width, height) = (frame.width, frame.height);
    let foveation = &frame.foveation;
    let mut pixels = vec![[0.0f32; 4]; width as usize * height as usize];
    // With history, the samples pass also sums each pixel's own samples, which its history takes.
    let mut pixel_samples: Vec<[f32; 4]> = if request.history {
        vec![[0.0f32; 4]; pixels.len()]
    } else {
        Vec::new()
    };
    let mut cell_means: Vec<[f32; 4]> = Vec::new();
    let mut rgba8: Option<Vec<u32>> = None;
    let mut raw_hdr: Option<FrameImage> = None;
    // The denoiser's two halves, used in turn by its steps.
    let mut denoise: [Vec<DenoiseTexel>; 2] = Default::default();
    let temporal = history.params_for(frame, request.fill_mode);
    let counters: [AtomicU64; 6] = Default::default();
    let mut passes = Vec::new();

    for pass in frame_passes(request.setup()) {
        let pass_start = Instant::now();
        match pass {
            FramePass::Samples => dispatch(
                scene,
                SamplePass {
                    frame,
                    output: SampleOutput::Mean,
                    replicated: &mut pixels,
                    pixel_sums: request.history.then_some(pixel_samples.as_mut_slice()),
                    counters: &counters,
                    progress,
                },
            ),
            FramePass::CellMeans => cell_means = cell_means_step(frame, &pixels),
            FramePass::Fill => fill_step(frame, &cell_means, request.fill_mode, &mut pixels),
            FramePass::GBuffer => history.gbuffer_pass(scene, frame),
            // Over the cell means, which the fill has used: each cell's mean albedo.
            FramePass::CellAlbedo => cell_means = history.cell_albedo_pass(frame),
            FramePass::Temporal => {
                history.temporal_pass(frame, &temporal, &pixel_samples, &pixels, &cell_means)
            }
            FramePass::ResolveHistory => {
                history.resolve_pass(frame, &mut pixels, &cell_means, request.fill_mode)
            }
            FramePass::DenoiseInput => {
                if request.output.wants_raw() {
                    raw_hdr = Some(FrameImage {
                        width,
                        height,
                        pixels: pixels.clone(),
                    });
                }
                let flags = request.denoise_flags();
                let (gbuffer, texels) = (history.gbuffer(), history.texels());
                denoise[0] = per_pixel(width, height, |x, y| {
                    denoise_input(frame, &pixels, gbuffer, &cell_means, texels, flags, x, y)
                });
            }
            FramePass::DenoiseAtrous => {
                for step in 0..pass.repeats() {
                    let (read, write) = (step as usize % 2, 1 - step as usize % 2);
                    let input = std::mem::take(&mut denoise[read]);
                    let gbuffer = history.gbuffer();
                    denoise[write] = per_pixel(width, height, |x, y| {
                        denoise_atrous(frame, &input, 0, gbuffer, step, x, y)
                    });
                    denoise[read] = input;
                }
            }
            FramePass::DenoiseOutput => {
                let filtered = &denoise[FramePass::DenoiseAtrous.repeats() as usize % 2];
                let gbuffer = history.gbuffer();
                for_each_pixel(&mut pixels, width, |x, y, pixel| {
                    *pixel = denoise_output(frame, filtered, 0, gbuffer, x, y);
                });
            }
            FramePass::ToneMap => {
                let exposure = request.exposure_ev;
                rgba8 = Some(
                    pixels
                        .par_iter()
                        .map(|p| tonemap_to_rgba8(Vec3::new(p[0], p[1], p[2]), exposure))
                        .collect(),
                );
            }
            FramePass::Overlay => {
                if let Some(rgba) = rgba8.as_mut() {
                    for_each_pixel(rgba, width, |x, y, c| {
                        *c = overlay_rgba8(*c, x, y, foveation);
                    });
                }
            }
        }
        passes.push((pass.name(), pass_start.elapsed().as_secs_f64() * 1e3));
    }

    let render_ms = start.elapsed().as_secs_f64() * 1e3;
    let stats = render_stats(scene, &counters, render_ms, passes);
    let hdr = FrameImage {
        width,
        height,
        pixels,
    };
    (
        RenderedFrame {
            width,
            height,
            hdr: Some(hdr),
            rgba8,
            raw_hdr,
        },
        stats,
    )
}

/// A frame's statistics from the samples pass's counters (samples, then blocks, per region).
fn render_stats(
    scene: &SceneView,
    counters: &[AtomicU64; 6],
    render_ms: f64,
    passes: Vec<(&'static str, f64)>,
) -> RenderStats {
    let loaded = counters.each_ref().map(|c| c.load(Ordering::Relaxed));
    RenderStats {
        render_ms,
        primary_samples: loaded[0] + loaded[1] + loaded[2],
        samples_per_region: [loaded[0], loaded[1], loaded[2]],
        blocks_per_region: [loaded[3], loaded[4], loaded[5]],
        path_features: path_mask(scene.features.bits()),
        passes,
    }
}

/// The cell-means pass: the cell-mean grids of every block size above 1, in one buffer, from the
/// replicated block means.
fn cell_means_step(frame: &FrameParams, replicated: &[[f32; 4]]) -> Vec<[f32; 4]> {
    let (width, height) = (frame.width, frame.height);
    (0..cell_buffer_len(width, height, &frame.foveation))
        .into_par_iter()
        .map(|i| cell_mean_at(replicated, width, height, &frame.foveation, i).to_array())
        .collect()
}

/// The fill pass, in place: a pixel's fill reads only its own replicated value and the cell means.
fn fill_step(
    frame: &FrameParams,
    cell_means: &[[f32; 4]],
    fill_mode: u32,
    pixels: &mut [[f32; 4]],
) {
    let (width, height) = (frame.width, frame.height);
    for_each_pixel(pixels, width, |x, y, pixel| {
        let own = Vec4::from(*pixel);
        let v = fill_value(
            own,
            cell_means,
            width,
            height,
            &frame.foveation,
            x,
            y,
            fill_mode,
        );
        *pixel = [v.x, v.y, v.z, 1.0];
    });
}

/// Part of a frame split by samples (`fovea render --samples first..end`): each block's samples
/// `first..end` (clipped to its own count, [`block_sample_range`]), their sum and count written to
/// every pixel of the block as `[r, g, b, count]`. The parts of a split are merged by adding their
/// sums and counts and calling [`fill_from_sample_sums`].
#[must_use]
pub fn render_sample_range(
    scene: &SceneView,
    frame: &FrameParams,
    [first, end]: [u32; 2],
    progress: &(dyn Fn(u64) + Sync),
) -> (FrameImage, RenderStats) {
    let start = Instant::now();
    let mut pixels = vec![[0.0f32; 4]; frame.width as usize * frame.height as usize];
    let counters: [AtomicU64; 6] = Default::default();
    dispatch(
        scene,
        SamplePass {
            frame,
            output: SampleOutput::RangeSum { first, end },
            replicated: &mut pixels,
            pixel_sums: None,
            counters: &counters,
            progress,
        },
    );
    let render_ms = start.elapsed().as_secs_f64() * 1e3;
    let passes = vec![(FramePass::Samples.name(), render_ms)];
    let stats = render_stats(scene, &counters, render_ms, passes);
    let image = FrameImage {
        width: frame.width,
        height: frame.height,
        pixels,
    };
    (image, stats)
}

/// The foveated HDR image from every block's sample sum and count (`[r, g, b, count]` per pixel, as
/// [`render_sample_range`] writes them, added over the parts of a split): the block means, then the
/// frame's cell-means and fill passes. From one part holding every sample it is bit for bit the
/// image [`render_frame`] renders.
#[must_use]
pub fn fill_from_sample_sums(frame: &FrameParams, sums: &[[f32; 4]], fill_mode: u32) -> FrameImage {
    let mut pixels: Vec<[f32; 4]> = sums
        .par_iter()
        .map(|s| block_mean(Vec3::new(s[0], s[1], s[2]), s[3] as u32))
        .collect();
    let cell_means = cell_means_step(frame, &pixels);
    fill_step(frame, &cell_means, fill_mode, &mut pixels);
    FrameImage {
        width: frame.width,
        height: frame.height,
        pixels,
    }
}

/// `f(x, y)` for every pixel of a `width × height` image, row-major, rows in parallel.
fn per_pixel<T: Send>(width: u32, height: u32, f: impl Fn(u32, u32) -> T + Sync) -> Vec<T> {
    (0..width * height)
        .into_par_iter()
        .map(|i| f(i % width, i / width))
        .collect()
}

/// Runs `f(x, y, element)` over a row-major image `width` wide, rows in parallel.
fn for_each_pixel<T: Send>(image: &mut [T], width: u32, f: impl Fn(u32, u32, &mut T) + Sync) {
    image
        .par_chunks_mut(width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, element) in row.iter_mut().enumerate() {
                f(x as u32, y as u32, element);
            }
        });
}

/// The foveated HDR image alone (samples, cell means, fill): [`render_frame_passes`] without history
/// or tone map. `fill_mode` is `FILL_BILINEAR` or `FILL_REPLICATE`.
pub fn render_frame(
    scene: &SceneView,
    frame: &FrameParams,
    fill_mode: u32,
    progress: &(dyn Fn(u64) + Sync),
) -> (FrameImage, RenderStats) {
    let request = hdr_request(fill_mode, false);
    let (out, stats) = render_frame_passes(
        scene,
        frame,
        &request,
        &mut TemporalHistory::new(),
        progress,
    );
    (
        out.hdr.expect("the CPU host always returns the HDR image"),
        stats,
    )
}

/// [`render_frame`] with temporal reuse: the frame joins `history` and the returned image is the
/// history's mean. The statistics list each pass the frame ran (`FramePass::name`).
pub fn render_frame_with_history(
    scene: &SceneView,
    frame: &FrameParams,
    fill_mode: u32,
    history: &mut TemporalHistory,
    progress: &(dyn Fn(u64) + Sync),
) -> (FrameImage, RenderStats) {
    let request = hdr_request(fill_mode, true);
    let (out, stats) = render_frame_passes(scene, frame, &request, history, progress);
    (
        out.hdr.expect("the CPU host always returns the HDR image"),
        stats,
    )
}

/// A request for the HDR image alone, with or without history.
fn hdr_request(fill_mode: u32, history: bool) -> FrameRequest {
    FrameRequest::new(fill_mode, 0.0, history, false, FrameOutput::Hdr)
}

/// What the samples pass writes to every pixel of a block.
#[derive(Clone, Copy, Debug)]
enum SampleOutput {
    /// The mean of the block's samples (a frame).
    Mean,
    /// The sum of the block's samples `first..end` and their count, `[r, g, b, count]` (a part of a
    /// render split by samples).
    RangeSum { first: u32, end: u32 },
}

/// The samples pass of [`render_frame_passes`]: every block's samples, band by band (core's walk over
/// the blocks in each band's rows), written to every pixel of the block; with `pixel_sums`, each sample
/// also added to the sum of the pixel it landed in.
struct SamplePass<'a> {
    frame: &'a FrameParams,
    output: SampleOutput,
    replicated: &'a mut [[f32; 4]],
    pixel_sums: Option<&'a mut [[f32; 4]]>,
    counters: &'a [AtomicU64; 6],
    progress: &'a (dyn Fn(u64) + Sync),
}

impl WithScene for SamplePass<'_> {
    type Output = ();

    fn run<F: Features + Sync>(self, scene: &SceneView<'_, F>) {
        let SamplePass {
            frame,
            output,
            replicated,
            pixel_sums,
            counters,
            progress,
        } = self;
        let (width, height) = (frame.width, frame.height);
        let foveation = &frame.foveation;
        let band = foveation.block_size[2].max(1);
        let band_len = width as usize * band as usize;
        // One band of rows: its blocks' values into `rows` (and their samples into `sums`).
        let run_band =
            |band_index: usize, rows: &mut [[f32; 4]], mut sums: Option<&mut [[f32; 4]]>| {
                let y0 = band_index as u32 * band;
                let rows_in_band = (rows.len() / width as usize) as u32;
                let mut local = [0u64; 6];
                let y_band_end = y0 + rows_in_band;
                for_each_block_in_rows(width, height, y0, y_band_end, foveation, |block| {
                    let spp = samples_in_block(&block, foveation);
                    let (value, traced) = match output {
                        SampleOutput::Mean => {
                            let sum = match sums.as_deref_mut() {
                                Some(sums) => block_sample_sum_into_pixels(
                                    scene, frame, &block, spp, sums, y0,
                                ),
                                None => block_sample_range_sum(scene, frame, &block, 0, spp),
                            };
                            (block_mean(sum, spp), spp)
                        }
                        SampleOutput::RangeSum { first, end } => {
                            let [first, end] = block_sample_range(spp, first, end);
                            let sum = block_sample_range_sum(scene, frame, &block, first, end);
                            ([sum.x, sum.y, sum.z, (end - first) as f32], end - first)
                        }
                    };
                    let x_end = (block.origin[0] + block.size).min(width);
                    let y_end = (block.origin[1] + block.size).min(y_band_end);
                    for by in block.origin[1]..y_end {
                        let row = ((by - y0) * width) as usize;
                        rows[row + block.origin[0] as usize..row + x_end as usize].fill(value);
                    }
                    let region = block.region.min(REGION_COUNT - 1) as usize;
                    local[region] += u64::from(traced);
                    local[3 + region] += 1;
                });
                // Once per band: a progress bar's update is an atomic read-modify-write (1 % of the
                // run time when it was per block).
                progress(local[0] + local[1] + local[2]);
                for (c, v) in counters.iter().zip(local) {
                    c.fetch_add(v, Ordering::Relaxed);
                }
            };
        match pixel_sums {
            Some(sums) => replicated
                .par_chunks_mut(band_len)
                .zip(sums.par_chunks_mut(band_len))
                .enumerate()
                .for_each(|(i, (rows, sums))| run_band(i, rows, Some(sums))),
            None => replicated
                .par_chunks_mut(band_len)
                .enumerate()
                .for_each(|(i, rows)| run_band(i, rows, None)),
        }
    }
}
