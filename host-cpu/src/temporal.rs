//! The CPU's temporal passes: after the fill, the G-buffer
//! ([`fovea_core::temporal::first_hit_gbuffer`]) and the reproject-and-accumulate pass
//! ([`fovea_core::temporal::temporal_accumulate`]), over two history buffers used in turn. The state
//! between frames (history, G-buffer, the previous camera) lives in [`TemporalHistory`].
use fovea_core::camera::Camera;
use fovea_core::foveation::fill::cell_buffer_len;
use fovea_core::integrator::FrameParams;
use fovea_core::scene::{SceneSlices, SceneView};
use fovea_core::temporal::albedo::cell_albedo_at;
use fovea_core::temporal::{
    first_hit_gbuffer, resolve_pixel, temporal_accumulate, GBufferTexel, HistoryTexel,
    TemporalParams,
};
use rayon::prelude::*;

use fovea_frame::FrameImage;

/// Each pixel's history and what it was rendered with, carried from frame to frame.
#[derive(Default)]
pub struct TemporalHistory {
    history: Vec<HistoryTexel>,
    /// This frame's G-buffer (after the G-buffer pass; the last frame's before it).
    gbuffer: Vec<GBufferTexel>,
    /// The previous frame's G-buffer, which the temporal pass reprojects against.
    previous_gbuffer: Vec<GBufferTexel>,
    /// The previous frame's camera and size; `None` before the first frame and after a reset.
    previous: Option<(Camera, [u32; 2])>,
    /// Scratch: this frame's history before it becomes the previous one.
    next_history: Vec<HistoryTexel>,
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

    /// Whether `frame` continues this history: there was a previous frame since the last reset, of
    /// the same size. Otherwise the frame starts every pixel afresh.
    #[must_use]
    pub fn continues(&self, frame: &FrameParams) -> bool {
        self.previous
            .is_some_and(|(_, size)| size == [frame.width, frame.height])
    }

    /// The history of the last frame (row-major), empty before the first.
    #[must_use]
    pub fn texels(&self) -> &[HistoryTexel] {
        &self.history
    }

    /// The G-buffer of the last frame (this frame's after its G-buffer pass).
    #[must_use]
    pub fn gbuffer(&self) -> &[GBufferTexel] {
        &self.gbuffer
    }

    /// The parameters the next `frame`, filled in `fill_mode`, would be accumulated with. A frame of
    /// another size starts afresh (its pixels are not the previous frame's).
    #[must_use]
    pub fn params_for(&self, frame: &FrameParams, fill_mode: u32) -> TemporalParams {
        let previous = self
            .previous
            .filter(|(_, size)| *size == [frame.width, frame.height]);
        TemporalParams::after(previous, frame, fill_mode)
    }

    /// The G-buffer pass: each pixel's first hit ([`first_hit_gbuffer`]) into this frame's G-buffer;
    /// the last frame's becomes the previous one.
    pub fn gbuffer_pass(&mut self, scene: &SceneView, frame: &FrameParams) {
        let (w, h) = (frame.width, frame.height);
        std::mem::swap(&mut self.gbuffer, &mut self.previous_gbuffer);
        self.gbuffer
            .resize(w as usize * h as usize, GBufferTexel::SKY);
        self.gbuffer
            .par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, texel) in row.iter_mut().enumerate() {
                    *texel = first_hit_gbuffer(scene, &SceneSlices, frame, x as u32, y as u32);
                }
            });
    }

    /// The cell-albedo pass, after [`Self::gbuffer_pass`]: each cell's mean albedo
    /// ([`cell_albedo_at`]), laid out as the cell means.
    #[must_use]
    pub fn cell_albedo_pass(&self, frame: &FrameParams) -> Vec<[f32; 4]> {
        (0..cell_buffer_len(frame.width, frame.height, &frame.foveation))
            .into_par_iter()
            .map(|i| {
                cell_albedo_at(frame, &self.gbuffer, i)
                    .extend(0.0)
                    .to_array()
            })
            .collect()
    }

    /// The temporal pass: the previous history reprojected to each pixel and the samples that landed in
    /// it (`pixel_samples`, the samples pass's per-pixel sums) merged in ([`temporal_accumulate`], with
    /// `temporal`, usually [`Self::params_for`]; `filled`, the frame's filled HDR image, is the
    /// neighbourhood clamp's), after [`Self::gbuffer_pass`] and the cell-albedo pass (`cell_albedo`,
    /// [`fovea_core::temporal::albedo::cell_albedo_at`]). This frame's history then becomes the previous
    /// one.
    pub fn temporal_pass(
        &mut self,
        frame: &FrameParams,
        temporal: &TemporalParams,
        pixel_samples: &[[f32; 4]],
        filled: &[[f32; 4]],
        cell_albedo: &[[f32; 4]],
    ) {
        let (w, h) = (frame.width, frame.height);
        self.next_history
            .resize(w as usize * h as usize, HistoryTexel::EMPTY);
        let (gbuffer, previous_gbuffer, previous_history) =
            (&self.gbuffer, &self.previous_gbuffer, &self.history);
        self.next_history
            .par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, texel) in row.iter_mut().enumerate() {
                    *texel = temporal_accumulate(
                        frame,
                        temporal,
                        pixel_samples,
                        filled,
                        gbuffer,
                        cell_albedo,
                        previous_gbuffer,
                        previous_history,
                        x as u32,
                        y as u32,
                    );
                }
            });
        std::mem::swap(&mut self.history, &mut self.next_history);
        self.previous = Some((frame.camera, [w, h]));
    }

    /// The resolve pass, in place over `hdr` (the frame's filled image): what is shown of each pixel
    /// ([`resolve_pixel`]: its history where confident, else the fill, under its own albedo).
    pub fn resolve_pass(
        &self,
        frame: &FrameParams,
        hdr: &mut [[f32; 4]],
        cell_albedo: &[[f32; 4]],
        fill_mode: u32,
    ) {
        let w = frame.width as usize;
        let resolved: Vec<[f32; 4]> = (0..hdr.len())
            .into_par_iter()
            .map(|p| {
                resolve_pixel(
                    frame,
                    &self.history,
                    hdr,
                    &self.gbuffer,
                    cell_albedo,
                    fill_mode,
                    (p % w) as u32,
                    (p / w) as u32,
                )
            })
            .collect();
        hdr.copy_from_slice(&resolved);
    }

    /// Adds `image` to the history outside a frame, as one sample landing in each pixel (the G-buffer
    /// and temporal passes with `temporal`, `image` also the clamp's filled image): for tests that feed
    /// the history values of their own.
    pub fn accumulate(
        &mut self,
        scene: &SceneView,
        frame: &FrameParams,
        temporal: &TemporalParams,
        image: &FrameImage,
    ) {
        self.gbuffer_pass(scene, frame);
        let cell_albedo = self.cell_albedo_pass(frame);
        let one_each: Vec<[f32; 4]> = image
            .pixels
            .iter()
            .map(|c| [c[0], c[1], c[2], 1.0])
            .collect();
        self.temporal_pass(frame, temporal, &one_each, &image.pixels, &cell_albedo);
    }
}
