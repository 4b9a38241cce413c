//! Rendering one foveated frame on the CPU.
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use fovea_core::foveation::blocks::{owning_block, samples_in_block};
use fovea_core::foveation::fill::{block_mean, cell_buffer_len, cell_mean_at, fill_value};
use fovea_core::foveation::regions::REGION_COUNT;
use fovea_core::integrator::{block_sample_sum, FrameParams};
use fovea_core::scene::{Features, SceneView};

use crate::specialize::{dispatch, path_mask, WithScene};
use glam::Vec4;
use rayon::prelude::*;

pub use fovea_frame::{FrameImage, RenderStats};

/// Renders one frame of `scene`. `fill_mode` is `FILL_BILINEAR` or `FILL_REPLICATE`. `progress` is called
/// from worker threads with the number of camera samples just finished.
///
/// The samples are traced by the compiled path for `scene.features` ([`crate::specialize`]): pass
/// `packed.view().with_features(packed.features())` to leave out what the scene lacks, or the plain
/// view (every feature) for the general path. Both give the same image.
pub fn render_frame(
    scene: &SceneView,
    frame: &FrameParams,
    fill_mode: u32,
    progress: &(dyn Fn(u64) + Sync),
) -> (FrameImage, RenderStats) {
    let start = Instant::now();
    let (width, height) = (frame.width, frame.height);
    let foveation = &frame.foveation;
    let mut replicated = vec![[0.0f32; 4]; width as usize * height as usize];
    let counters: [AtomicU64; 6] = Default::default();

    // Pass 1: samples, band by band.
    dispatch(
        scene,
        SamplePass {
            frame,
            replicated: &mut replicated,
            counters: &counters,
            progress,
        },
    );

    let samples_ms = start.elapsed().as_secs_f64() * 1e3;

    // Pass 2: the cell-mean grids of every block size above 1, in one buffer.
    let cells_start = Instant::now();
    let cell_count = cell_buffer_len(width, height, foveation);
    let cell_means: Vec<[f32; 4]> = (0..cell_count)
        .into_par_iter()
        .map(|i| cell_mean_at(&replicated, width, height, foveation, i).to_array())
        .collect();

    let cells_ms = cells_start.elapsed().as_secs_f64() * 1e3;

    // Pass 3: fill, in place: a pixel's fill reads only its own replicated value and the cell means.
    let fill_start = Instant::now();
    let mut pixels = replicated;
    pixels
        .par_chunks_mut(width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, pixel) in row.iter_mut().enumerate() {
                let own = Vec4::from(*pixel);
                let (x, y) = (x as u32, y as u32);
                let v = fill_value(own, &cell_means, width, height, foveation, x, y, fill_mode);
                *pixel = [v.x, v.y, v.z, 1.0];
            }
        });

    let loaded: Vec<u64> = counters.iter().map(|c| c.load(Ordering::Relaxed)).collect();
    let stats = RenderStats {
        render_ms: start.elapsed().as_secs_f64() * 1e3,
        primary_samples: loaded[0] + loaded[1] + loaded[2],
        samples_per_region: [loaded[0], loaded[1], loaded[2]],
        blocks_per_region: [loaded[3], loaded[4], loaded[5]],
        path_features: path_mask(scene.features.bits()),
        passes: vec![
            ("samples", samples_ms),
            ("cell_means", cells_ms),
            ("fill", fill_start.elapsed().as_secs_f64() * 1e3),
        ],
    };
    (
        FrameImage {
            width,
            height,
            pixels,
        },
        stats,
    )
}

/// Pass 1 of [`render_frame`]: every block's samples, band by band, written to every pixel of the block.
struct SamplePass<'a> {
    frame: &'a FrameParams,
    replicated: &'a mut [[f32; 4]],
    counters: &'a [AtomicU64; 6],
    progress: &'a (dyn Fn(u64) + Sync),
}

impl WithScene for SamplePass<'_> {
    type Output = ();

    fn run<F: Features + Sync>(self, scene: &SceneView<'_, F>) {
        let SamplePass {
            frame,
            replicated,
            counters,
            progress,
        } = self;
        let (width, height) = (frame.width, frame.height);
        let foveation = &frame.foveation;
        let band = foveation.block_size[2].max(1);
        replicated
            .par_chunks_mut(width as usize * band as usize)
            .enumerate()
            .for_each(|(band_index, rows)| {
                let y0 = band_index as u32 * band;
                let rows_in_band = (rows.len() / width as usize) as u32;
                let mut local = [0u64; 6];
                for dy in 0..rows_in_band {
                    let y = y0 + dy;
                    for x in 0..width {
                        let block = owning_block(x, y, foveation);
                        if block.origin != [x, y] {
                            continue;
                        }
                        let spp = samples_in_block(&block, foveation);
                        let value = block_mean(block_sample_sum(scene, frame, &block, spp), spp);
                        let x_end = (block.origin[0] + block.size).min(width);
                        let y_end = (block.origin[1] + block.size).min(height);
                        for by in block.origin[1]..y_end {
                            let row = ((by - y0) * width) as usize;
                            for bx in block.origin[0]..x_end {
                                rows[row + bx as usize] = value;
                            }
                        }
                        let region = block.region.min(REGION_COUNT - 1) as usize;
                        local[region] += spp as u64;
                        local[3 + region] += 1;
                    }
                }
                // Once per band: a progress bar's update is an atomic read-modify-write (1 % of the
                // run time when it was per block).
                progress(local[0] + local[1] + local[2]);
                for (c, v) in counters.iter().zip(local) {
                    c.fetch_add(v, Ordering::Relaxed);
                }
            });
    }
}
