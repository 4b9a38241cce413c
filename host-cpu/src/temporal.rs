//! The CPU's temporal passes: after [`crate::render_frame`]'s fill, the G-buffer
//! ([`fovea_core::temporal::first_hit_gbuffer`]) and the reproject-and-accumulate pass
//! ([`fovea_core::temporal::temporal_accumulate`]), over two history buffers used in turn. The state
//! between frames (history, G-buffer, the previous camera) lives in [`TemporalHistory`].
use std::time::Instant;

use fovea_core::camera::Camera;
use fovea_core::integrator::FrameParams;
use fovea_core::scene::{SceneSlices, SceneView};
use fovea_core::temporal::{
    first_hit_gbuffer, temporal_accumulate, GBufferTexel, HistoryTexel, TemporalParams,
};
use rayon::prelude::*;

use crate::render::{render_frame, FrameImage, RenderStats};

/// Each pixel's history and what it was rendered with, carried from frame to frame.
#[derive(Default)]
pub struct TemporalHistory {
    history: Vec<HistoryTexel>,
    gbuffer: Vec<GBufferTexel>,
    /// The previous frame's camera and size; `None` before the first frame and after a reset.
    previous: Option<(Camera, [u32; 2])>,
    /// Scratch: this frame's history and G-buffer before they become the previous ones.
    next_history: Vec<HistoryTexel>,
    next_gbuffer: Vec<GBufferTexel>,
}

impl TemporalHistory {
    /// No history yet.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets everything: the next frame starts every pixel afresh.
    pub fn reset(&mut self) {
        self.previous = None;
    }

    /// The history of the last frame (row-major), empty before the first.
    #[must_use]
    pub fn texels(&self) -> &[HistoryTexel] {
        &self.history
    }

    /// The G-buffer of the last frame.
    #[must_use]
    pub fn gbuffer(&self) -> &[GBufferTexel] {
        &self.gbuffer
    }

    /// The parameters the next `frame` would be accumulated with. A frame of another size starts
    /// afresh (its pixels are not the previous frame's).
    #[must_use]
    pub fn params_for(&self, frame: &FrameParams) -> TemporalParams {
        let previous = self
            .previous
            .filter(|(_, size)| *size == [frame.width, frame.height]);
        TemporalParams::after(previous, frame)
    }

    /// Adds `filled` (the frame's filled HDR image, from [`render_frame`]) to the history: the G-buffer
    /// pass, then the temporal pass with `temporal` (usually [`Self::params_for`]). Returns the two
    /// passes' milliseconds.
    pub fn accumulate(
        &mut self,
        scene: &SceneView,
        frame: &FrameParams,
        temporal: &TemporalParams,
        filled: &FrameImage,
    ) -> [(&'static str, f64); 2] {
        let (w, h) = (frame.width, frame.height);
        let n = w as usize * h as usize;
        let start = Instant::now();
        self.next_gbuffer.resize(n, GBufferTexel::SKY);
        self.next_gbuffer
            .par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, texel) in row.iter_mut().enumerate() {
                    *texel = first_hit_gbuffer(scene, &SceneSlices, frame, x as u32, y as u32);
                }
            });
        let gbuffer_ms = start.elapsed().as_secs_f64() * 1e3;

        let start = Instant::now();
        self.next_history.resize(n, HistoryTexel::EMPTY);
        let (gbuffer, previous_gbuffer, previous_history) =
            (&self.next_gbuffer, &self.gbuffer, &self.history);
        self.next_history
            .par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, texel) in row.iter_mut().enumerate() {
                    *texel = temporal_accumulate(
                        frame,
                        temporal,
                        &filled.pixels,
                        gbuffer,
                        previous_gbuffer,
                        previous_history,
                        x as u32,
                        y as u32,
                    );
                }
            });
        std::mem::swap(&mut self.history, &mut self.next_history);
        std::mem::swap(&mut self.gbuffer, &mut self.next_gbuffer);
        self.previous = Some((frame.camera, [w, h]));
        [
            ("gbuffer", gbuffer_ms),
            ("temporal", start.elapsed().as_secs_f64() * 1e3),
        ]
    }

    /// The displayed image: each pixel's history mean (alpha 1).
    #[must_use]
    pub fn image(&self, width: u32, height: u32) -> FrameImage {
        FrameImage {
            width,
            height,
            pixels: self
                .history
                .par_iter()
                .map(HistoryTexel::displayed)
                .collect(),
        }
    }
}

/// [`render_frame`] followed by the temporal passes: the frame joins `history`, and the returned image
/// is the history's mean. The statistics list all five passes.
pub fn render_frame_with_history(
    scene: &SceneView,
    frame: &FrameParams,
    fill_mode: u32,
    history: &mut TemporalHistory,
    progress: &(dyn Fn(u64) + Sync),
) -> (FrameImage, RenderStats) {
    let (filled, mut stats) = render_frame(scene, frame, fill_mode, progress);
    let start = Instant::now();
    let temporal = history.params_for(frame);
    let passes = history.accumulate(scene, frame, &temporal, &filled);
    stats.passes.extend(passes);
    stats.render_ms += start.elapsed().as_secs_f64() * 1e3;
    (history.image(frame.width, frame.height), stats)
}
