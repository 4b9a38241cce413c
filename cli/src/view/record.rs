//! What the live view writes: one record per frame (`--stats`) and screenshots (the files `fovea render`
//! writes: tone-mapped PNG, linear EXR, the regions overlay and a stats JSON).
use std::path::{Path, PathBuf};

use fovea_core::foveation::regions::FoveationParams;
use fovea_cpu::{FrameImage, RenderStats};
use serde_json::{json, Value};

use crate::error::{FoveaError, Result};
use crate::output::{regions_overlay, tonemapped_rgb8, write_image, write_png, ImageFormat};
use crate::stats::write_json;

/// The figures of one frame of the live view.
#[derive(Clone, Debug)]
pub struct FrameRecord {
    /// Frame number (ticks of the view, the clock scripts use).
    pub frame: u64,
    pub gaze: [f32; 2],
    /// The eye tracker's sample before the fixation filter.
    pub raw_gaze: [f32; 2],
    pub uniform: bool,
    pub config: String,
    /// Samples per pixel / block of this frame (after the budget shift).
    pub frame_spp: [u32; 3],
    pub budget_shift: u32,
    pub render: RenderStats,
    /// Frames in the running mean, this one included.
    pub accumulated_frames: u32,
    /// Samples per pixel / block in the running mean (summed over its frames).
    pub effective_spp: [u64; 3],
    pub render_ms: f64,
    pub present_ms: f64,
    /// Wall time of the whole frame (input, render, present).
    pub frame_ms: f64,
    /// Time from the gaze sample this frame used to the present call's return, when the sample was new.
    pub latency_ms: Option<f64>,
    pub window: [u32; 2],
    /// The rendered size (the window's times `--render-scale`).
    pub rendered: [u32; 2],
    pub presented: bool,
    /// The camera's position in world space.
    pub eye: [f64; 3],
    pub radii_px: [f32; 2],
}

impl FrameRecord {
    pub fn to_json(&self) -> Value {
        json!({
            "frame": self.frame,
            "gaze": self.gaze,
            "raw_gaze": self.raw_gaze,
            "uniform": self.uniform,
            "config": self.config,
            "frame_spp": self.frame_spp,
            "budget_shift": self.budget_shift,
            "primary_samples": self.render.primary_samples,
            "samples_per_region": self.render.samples_per_region,
            "accumulated_frames": self.accumulated_frames,
            "history_frames": self.accumulated_frames,
            "pass_ms": crate::stats::pass_object(&self.render.passes),
            "effective_spp": self.effective_spp,
            "render_ms": self.render_ms,
            "present_ms": self.present_ms,
            "frame_ms": self.frame_ms,
            "latency_ms": self.latency_ms,
            "window": self.window,
            "rendered": self.rendered,
            "presented": self.presented,
            "eye": self.eye,
            "radii_px": self.radii_px,
        })
    }
}

/// The median of `values` (NaN-free), or `None` when empty.
#[must_use]
pub fn median(values: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// The `--stats` document: the run's settings, every frame and a summary.
pub fn stats_document(header: Value, frames: &[FrameRecord], validation: &[String]) -> Value {
    let frame_ms: Vec<f64> = frames.iter().map(|f| f.frame_ms).collect();
    let latency: Vec<f64> = frames.iter().filter_map(|f| f.latency_ms).collect();
    let median_frame = median(&frame_ms);
    json!({
        "run": header,
        "summary": {
            "frames": frames.len(),
            "presented": frames.iter().filter(|f| f.presented).count(),
            "median_frame_ms": median_frame,
            "fps": median_frame.map(|m| if m > 0.0 { 1e3 / m } else { 0.0 }),
            "median_render_ms": median(&frames.iter().map(|f| f.render_ms).collect::<Vec<_>>()),
            "median_latency_ms": median(&latency),
        },
        "validation_messages": validation,
        "frames": frames.iter().map(FrameRecord::to_json).collect::<Vec<_>>(),
    })
}

/// Writes a screenshot of `mean` (the accumulated linear image) as `DIR/fovea_view_FRAME` `.png`, `.exr`,
/// `_regions.png` and `.json` (with `details` and the frame's record); returns the PNG's path.
pub fn write_screenshot(
    dir: &Path,
    mean: &FrameImage,
    exposure: f32,
    foveation: &FoveationParams,
    record: &FrameRecord,
    details: Value,
) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).map_err(|e| {
        FoveaError::option(
            "--screenshot-dir",
            format!("cannot create '{}': {e}", dir.display()),
        )
    })?;
    let stem = dir.join(format!("fovea_view_{:05}", record.frame));
    let png = stem.with_extension("png");
    // Tone-mapped once, for the PNG and the overlay.
    let rgb = tonemapped_rgb8(mean, exposure);
    write_png(&png, mean.width, mean.height, &rgb)?;
    write_image(
        &stem.with_extension("exr"),
        ImageFormat::Exr,
        mean,
        exposure,
    )?;
    let overlay_path = dir.join(format!("fovea_view_{:05}_regions.png", record.frame));
    write_png(
        &overlay_path,
        mean.width,
        mean.height,
        &regions_overlay(&rgb, mean.width, mean.height, foveation),
    )?;
    let doc = json!({
        "view": details,
        "frame": record.to_json(),
        "foveation": {
            "gaze": foveation.gaze,
            "radius_fovea": foveation.radius_fovea,
            "radius_intermediate": foveation.radius_intermediate,
            "spp": &foveation.spp[..3],
            "block_size": &foveation.block_size[..3],
        },
        "resolution": [mean.width, mean.height],
        "exposure": exposure,
        "image": png,
    });
    write_json(&stem.with_extension("json"), &doc)?;
    Ok(png)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_ignores_nan_and_handles_empty() {
        assert_eq!(median(&[3.0, f64::NAN, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[]), None);
    }
}
