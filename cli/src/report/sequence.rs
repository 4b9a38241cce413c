//! `fovea report --gaze-trace FILE`: a sequence judged as an eye would see it.
//!
//! The trace (the same files `render` and `view` read) is rendered frame by frame for each
//! configuration: uniform 32 spp and the paper's three foveated configurations, each without and with
//! temporal reuse, and a uniform spp sweep for the equal-time comparison. Every frame is scored against
//! the converged reference (the camera is static, so one reference serves every frame) and pooled two
//! ways around *that frame's* gaze:
//! - by region (the paper's 32/16/8 regions at the gaze, for every configuration alike);
//! - by eccentricity band (`--band-deg`, 1° by default): the visual angle between the gaze and the
//!   pixel on the display model ([`radius_px_to_eccentricity_deg`]).
//!
//! Flicker is the frame-to-frame change of the image where the reference does not change: per pixel
//! `(Y_t − Y_{t−1})² / (Y_ref² + ε)` (luminance, the relMSE's normalisation), averaged over pixels of
//! a band or region and over consecutive frame pairs. An unbiased renderer without history has about
//! twice its per-frame luminance variance here; temporal reuse and a denoiser lower it.
use std::path::Path;

use fovea_core::camera::Camera;
use fovea_core::foveation::display::{radius_px_to_eccentricity_deg, DisplayGeometry};
use fovea_core::foveation::regions::FoveationParams;
use fovea_cpu::FrameImage;
use fovea_scene::pack::PackedScene;
use indicatif::ProgressBar;

use super::configs::{ConfigKind, UNIFORM_SPP};
use super::fvvdp::{FovVideoVdp, FovVideoVdpScore, RawFrames};
use super::median;
use super::metrics::{self, RegionMap, RegionMeans, REL_MSE_EPSILON};
use super::saccades::{fovea_lag, saccade_frames, FoveaLag};
use crate::backend::{FrameOutput, Renderer};
use crate::error::{FoveaError, Result};
use crate::schedule::{FoveationRule, FrameSchedule, FrameSettings};

/// The trace's frames and how to pool them.
#[derive(Clone, Debug)]
pub struct SequencePlan {
    /// The trace file, for the report.
    pub trace: String,
    /// The frames: numbers, gaze in image pixels and, with `--camera-path`, cameras.
    pub schedule: FrameSchedule,
    /// Frames per second the trace was sampled at (timed traces).
    pub fps: f64,
    /// Width of an eccentricity band in degrees.
    pub band_deg: f32,
    /// `--camera-path`: the file (each frame's camera is in `schedule`).
    pub camera_path: Option<String>,
}

/// One frame's camera and the converged reference it is scored against (shared by every frame while
/// the camera is still).
#[derive(Clone, Copy)]
pub struct FrameView<'a> {
    pub camera: Camera,
    pub reference: &'a FrameImage,
    pub reference_rgb8: &'a [u8],
}

/// One configuration of the sequence.
#[derive(Clone, Debug)]
pub struct SequenceSpec {
    pub name: String,
    pub slug: String,
    pub kind: ConfigKind,
    /// Samples per pixel or block; uniform when the three are equal and `foveated` is false.
    pub spp: [u32; 3],
    pub foveated: bool,
    pub history: bool,
    pub denoise: bool,
}

/// One band of eccentricity around each frame's gaze, averaged over the frames where it has pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct BandResult {
    pub from_deg: f64,
    pub to_deg: f64,
    /// Mean pixels per frame.
    pub pixels: f64,
    pub flip: f64,
    pub rel_mse: f64,
    /// NaN for a one-frame sequence.
    pub flicker: f64,
}

/// One configuration's sequence, measured.
#[derive(Clone, Debug)]
pub struct SequenceResult {
    pub spec: SequenceSpec,
    pub frames: u32,
    /// Median frame time, as the backend reports it.
    pub frame_ms: f64,
    pub primary_samples_per_frame: f64,
    /// Means over the frames of the per-frame region means (regions at each frame's gaze).
    pub flip: RegionMeans,
    pub rel_mse: RegionMeans,
    pub flicker: RegionMeans,
    pub bands: Vec<BandResult>,
    /// FovVideoVDP's verdict on the sequence, where it is set up.
    pub fovvideovdp: Option<FovVideoVdpScore>,
    /// How long the fovea takes to recover its quality after a saccade (`None` without saccades).
    pub fovea_lag: Option<FoveaLag>,
    /// Median milliseconds per frame of fovea's own scoring (FLIP, relMSE, flicker, pooling), not
    /// counting FovVideoVDP.
    pub evaluation_ms: f64,
}

/// The sequence part of a scene's report.
#[derive(Clone, Debug)]
pub struct SequenceReport {
    pub trace: String,
    /// The `--camera-path` file, when the camera moved.
    pub camera_path: Option<String>,
    pub frames: u32,
    pub fps: f64,
    pub band_deg: f32,
    /// The region bounds of the paper's foveation as eccentricities (degrees from the gaze).
    pub region_bounds_deg: [f64; 2],
    pub results: Vec<SequenceResult>,
    /// Whether FovVideoVDP ran, and if not, how to set it up.
    pub fovvideovdp_note: String,
    /// Frames where the gaze jumped out of the previous fovea ([`saccade_frames`]).
    pub saccades: Vec<usize>,
}

/// The configurations of a sequence: uniform 32 and the paper's three foveated ones, each without and
/// with history, the uniform sweep (`sweep`) without and with history for the equal-time curves, then the
/// denoiser on 32/16/8 alone, after 32/16/8's history and after 32/2/1's.
#[must_use]
pub fn sequence_specs(sweep: &[u32]) -> Vec<SequenceSpec> {
    let mut specs = Vec::new();
    for history in [false, true] {
        let suffix = if history { " + history" } else { "" };
        let slug_suffix = if history { "-history" } else { "" };
        specs.push(SequenceSpec {
            name: format!("uniform{suffix}"),
            slug: format!("uniform{slug_suffix}"),
            kind: ConfigKind::Uniform,
            spp: [UNIFORM_SPP; 3],
            foveated: false,
            history,
            denoise: false,
        });
        for spp in [[32, 16, 8], [32, 8, 4], [32, 2, 1]] {
            let base = format!("{}/{}/{}", spp[0], spp[1], spp[2]);
            specs.push(SequenceSpec {
                name: format!("{base}{suffix}"),
                slug: format!("{}{slug_suffix}", base.replace('/', "-")),
                kind: ConfigKind::Foveated,
                spp,
                foveated: true,
                history,
                denoise: false,
            });
        }
    }
    for history in [false, true] {
        for &spp in sweep.iter().filter(|&&s| s != UNIFORM_SPP) {
            let (suffix, slug_suffix) = if history {
                (" + history", "-history")
            } else {
                ("", "")
            };
            specs.push(SequenceSpec {
                name: format!("uniform {spp}{suffix}"),
                slug: format!("uniform-{spp}{slug_suffix}"),
                kind: ConfigKind::Sweep,
                spp: [spp; 3],
                foveated: false,
                history,
                denoise: false,
            });
        }
    }
    // The denoiser: on the frame alone and after the history.
    for (spp, history) in [
        ([32, 16, 8], false),
        ([32, 16, 8], true),
        ([32, 2, 1], true),
    ] {
        let base = format!("{}/{}/{}", spp[0], spp[1], spp[2]);
        let (name, slug) = if history {
            (
                format!("{base} + history + denoiser"),
                format!("{}-history-denoised", base.replace('/', "-")),
            )
        } else {
            (
                format!("{base} + denoiser"),
                format!("{}-denoised", base.replace('/', "-")),
            )
        };
        specs.push(SequenceSpec {
            name,
            slug,
            kind: ConfigKind::Foveated,
            spp,
            foveated: true,
            history,
            denoise: true,
        });
    }
    // Uniform 1 spp after its history, denoised: about the frame time of 32/16/8 + history + denoiser,
    // so that foveation meets uniform at equal time with the denoiser on both sides.
    specs.push(SequenceSpec {
        name: "uniform 1 + history + denoiser".into(),
        slug: "uniform-1-history-denoised".into(),
        kind: ConfigKind::EqualTime,
        spp: [1; 3],
        foveated: false,
        history: true,
        denoise: true,
    });
    specs
}

/// Everything a sequence run needs from the scene's report.
pub struct SequenceInputs<'a> {
    pub packed: &'a PackedScene,
    /// What every frame shares (each frame's camera is in `views`).
    pub settings: FrameSettings,
    /// The paper's 32/16/8 foveation at the image centre; moved to each frame's gaze.
    pub paper: FoveationParams,
    pub display: DisplayGeometry,
    pub ppd: f32,
    /// Each frame's camera and reference, in the plan's frame order.
    pub views: Vec<FrameView<'a>>,
    pub scene_name: &'a str,
    pub bar: &'a ProgressBar,
    /// FovVideoVDP where it is set up, else why not; and the folder its frames are written to.
    pub fovvideovdp: std::result::Result<&'a FovVideoVdp, String>,
    pub scratch_dir: &'a Path,
}

/// The eccentricity of each pixel centre around `gaze`, in degrees.
#[must_use]
pub fn eccentricity_map(
    width: u32,
    height: u32,
    gaze: [f32; 2],
    display: &DisplayGeometry,
) -> Vec<f32> {
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height {
        for x in 0..width {
            let dx = x as f32 + 0.5 - gaze[0];
            let dy = y as f32 + 0.5 - gaze[1];
            out.push(radius_px_to_eccentricity_deg(
                (dx * dx + dy * dy).sqrt(),
                display,
            ));
        }
    }
    out
}

/// Per-pixel flicker between two consecutive frames: the change of their error,
/// `((Y_t − R_t) − (Y_{t−1} − R_{t−1}))² / (R_t² + ε)` for test luminance Y and reference luminance R.
/// With a still camera the references are one image and this is `(Y_t − Y_{t−1})² / (R² + ε)`; with
/// a moving one, what the scene itself does between frames is not counted as flicker.
#[must_use]
pub fn flicker_map(
    current: &FrameImage,
    previous: &FrameImage,
    reference: &FrameImage,
    previous_reference: &FrameImage,
) -> Vec<f32> {
    let luminance = |p: &[f32; 4]| {
        0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
    };
    current
        .pixels
        .iter()
        .zip(&previous.pixels)
        .zip(reference.pixels.iter().zip(&previous_reference.pixels))
        .map(|((c, p), (r, rp))| {
            let d = (luminance(c) - luminance(r)) - (luminance(p) - luminance(rp));
            let y = luminance(r);
            (d * d / (y * y + REL_MSE_EPSILON)) as f32
        })
        .collect()
}

/// Sums of per-frame means, per band or region, for averaging over frames.
#[derive(Clone, Debug, Default)]
struct FrameMeans {
    sum: Vec<f64>,
    frames: Vec<u32>,
}

impl FrameMeans {
    fn new(len: usize) -> Self {
        Self {
            sum: vec![0.0; len],
            frames: vec![0; len],
        }
    }

    /// Adds one frame's means (NaN where a band or region has no pixels in that frame).
    fn add(&mut self, means: &[f64]) {
        for (i, m) in means.iter().enumerate() {
            if m.is_finite() {
                self.sum[i] += m;
                self.frames[i] += 1;
            }
        }
    }

    fn means(&self) -> Vec<f64> {
        self.sum
            .iter()
            .zip(&self.frames)
            .map(|(s, &n)| if n == 0 { f64::NAN } else { s / f64::from(n) })
            .collect()
    }
}

/// Means of `values` per band (`band[i]` the band of pixel `i`, `bands` of them); NaN for empty bands.
fn band_means(values: &[f32], band: &[u16], bands: usize) -> Vec<f64> {
    let mut sum = vec![0.0f64; bands];
    let mut count = vec![0u64; bands];
    for (v, &b) in values.iter().zip(band) {
        sum[b as usize] += f64::from(*v);
        count[b as usize] += 1;
    }
    sum.iter()
        .zip(&count)
        .map(|(s, &n)| if n == 0 { f64::NAN } else { s / n as f64 })
        .collect()
}

fn region_array(m: RegionMeans) -> [f64; 4] {
    m.to_array()
}

fn region_means(a: &[f64]) -> RegionMeans {
    RegionMeans {
        all: a[0],
        fovea: a[1],
        intermediate: a[2],
        periphery: a[3],
    }
}

/// The seed of configuration `slug`'s frames: `seed` with the slug's hash, so that every
/// configuration of a sequence has its own random numbers.
#[must_use]
pub fn spec_seed(seed: u32, slug: &str) -> u32 {
    let h = crate::content_hash::fnv1a64(slug.as_bytes());
    seed ^ (h as u32) ^ ((h >> 32) as u32)
}

/// Renders and scores every configuration of the sequence.
///
/// Long because it is one loop over configurations and frames whose accumulators (by region, by band,
/// flicker, the frames FovVideoVDP scores) are all read when each configuration ends.
pub fn run_sequence(
    renderer: &mut Renderer,
    plan: &SequencePlan,
    specs: &[SequenceSpec],
    inputs: &SequenceInputs<'_>,
) -> Result<SequenceReport> {
    let [w, h] = inputs.settings.size;
    if plan.schedule.frames.is_empty() {
        return Err(FoveaError::option(
            "--gaze-trace",
            "the trace has no frame to render",
        ));
    }
    // Bands up to the farthest pixel from any gaze of the trace (gazes may lie off the image).
    let band_deg = plan.band_deg;
    let max_ecc = plan
        .schedule
        .frames
        .iter()
        .map(|f| f.gaze)
        .flat_map(|g| {
            [
                [0.0, 0.0],
                [w as f32, 0.0],
                [0.0, h as f32],
                [w as f32, h as f32],
            ]
            .map(|c| ((c[0] - g[0]).hypot(c[1] - g[1]), inputs.display))
        })
        .map(|(d, display)| radius_px_to_eccentricity_deg(d, &display))
        .fold(0.0f32, f32::max);
    let bands = ((max_ecc / band_deg).floor() as usize + 1).clamp(1, 2048);

    // Per frame: the regions and bands around its gaze (the same for every configuration).
    let per_frame: Vec<(RegionMap, Vec<u16>, FoveationParams)> = plan
        .schedule
        .frames
        .iter()
        .map(|f| {
            let gaze = f.gaze;
            let mut paper = inputs.paper;
            paper.gaze = gaze;
            let regions = RegionMap::new(w, h, &paper);
            let band: Vec<u16> = eccentricity_map(w, h, gaze, &inputs.display)
                .iter()
                .map(|e| ((e / band_deg) as usize).min(bands - 1) as u16)
                .collect();
            (regions, band, paper)
        })
        .collect();
    let band_pixels: Vec<f64> = {
        let mut count = vec![0u64; bands];
        for (_, band, _) in &per_frame {
            for &b in band {
                count[b as usize] += 1;
            }
        }
        count
            .iter()
            .map(|&n| n as f64 / per_frame.len() as f64)
            .collect()
    };

    if inputs.views.len() != plan.schedule.frames.len() {
        return Err(FoveaError::Backend(format!(
            "{} frames but {} cameras and references",
            plan.schedule.frames.len(),
            inputs.views.len()
        )));
    }
    // FovVideoVDP's reference: one frame while the camera is still, else each frame's.
    let moving = plan.camera_path.is_some();
    let fvvdp_reference = match &inputs.fovvideovdp {
        Ok(_) => {
            let mut raw = RawFrames::create(inputs.scratch_dir.join("reference.rgb"))
                .map_err(FoveaError::Backend)?;
            let frames = if moving { inputs.views.len() } else { 1 };
            for view in &inputs.views[..frames] {
                raw.push(view.reference_rgb8).map_err(FoveaError::Backend)?;
            }
            Some(raw.finish().map_err(FoveaError::Backend)?)
        }
        Err(_) => None,
    };
    let fixations: Vec<[f32; 2]> = plan.schedule.frames.iter().map(|f| f.gaze).collect();
    let bounds = [inputs.paper.radius_fovea, inputs.paper.radius_intermediate]
        .map(|r| radius_px_to_eccentricity_deg(r, &inputs.display));
    let saccades = saccade_frames(&fixations, &inputs.display, bounds[0]);
    let mut fvvdp_failure: Option<String> = None;

    let mut results = Vec::new();
    // Each configuration's fovea FLIP per frame, for the recovery after saccades.
    let mut fovea_series: Vec<Vec<f64>> = Vec::new();
    for spec in specs {
        renderer.reset_history();
        let mut raw = match &fvvdp_reference {
            Some(_) => Some(
                RawFrames::create(inputs.scratch_dir.join(format!("{}.rgb", spec.slug)))
                    .map_err(FoveaError::Backend)?,
            ),
            None => None,
        };
        let mut flip_regions = FrameMeans::new(4);
        let mut rel_regions = FrameMeans::new(4);
        let mut flicker_regions = FrameMeans::new(4);
        let mut flip_bands = FrameMeans::new(bands);
        let mut rel_bands = FrameMeans::new(bands);
        let mut flicker_bands = FrameMeans::new(bands);
        let mut frame_ms = Vec::new();
        let mut evaluation_ms = Vec::new();
        let mut fovea_flip = Vec::new();
        let mut samples = 0u64;
        let mut previous: Option<FrameImage> = None;
        // Each configuration draws its own random numbers, so that no comparison between two of them
        // holds by construction (with one key, uniform's and 32/16/8's foveas would be the same image).
        let settings = FrameSettings {
            seed: spec_seed(inputs.settings.seed, &spec.slug),
            ..inputs.settings
        };
        for (i, scheduled) in plan.schedule.frames.iter().enumerate() {
            inputs.bar.set_message(format!(
                "{}: sequence {} (frame {}/{})",
                inputs.scene_name,
                spec.name,
                i + 1,
                plan.schedule.frames.len()
            ));
            let (regions, band, paper_at_gaze) = &per_frame[i];
            let view = inputs.views[i];
            let template = if spec.foveated {
                let mut f = *paper_at_gaze;
                f.spp = [spec.spp[0], spec.spp[1], spec.spp[2], 0];
                f
            } else {
                FoveationParams::uniform(spec.spp[0])
            };
            let rule = FoveationRule {
                template,
                uniform: !spec.foveated,
                eye_eccentricity: None,
            };
            let frame = settings.views(scheduled, view.camera, None, &rule)[0].frame;
            let request = settings.request(
                spec.history,
                spec.denoise,
                FrameOutput::ReadBack {
                    want_hdr: true,
                    want_raw: false,
                },
            );
            let rendered = renderer.render(inputs.packed, &frame, &request, &|n| {
                inputs.bar.inc(n);
            })?;
            frame_ms.push(rendered.stats.render_ms);
            samples += rendered.stats.primary_samples;
            let (Some(rgb8), Some(hdr)) = (rendered.image.rgb8(), rendered.image.hdr) else {
                return Err(FoveaError::Backend(
                    "the backend returned no HDR or 8-bit image".into(),
                ));
            };
            if let Some(raw) = raw.as_mut() {
                raw.push(&rgb8).map_err(FoveaError::Backend)?;
            }
            let evaluation = std::time::Instant::now();
            let flip = metrics::flip_map(view.reference_rgb8, &rgb8, w, h, inputs.ppd);
            let rel = metrics::rel_mse_map(&hdr, view.reference);
            let flip_by_region = RegionMeans::of(&flip, regions);
            fovea_flip.push(flip_by_region.fovea);
            flip_regions.add(&region_array(flip_by_region));
            rel_regions.add(&region_array(RegionMeans::of(&rel, regions)));
            flip_bands.add(&band_means(&flip, band, bands));
            rel_bands.add(&band_means(&rel, band, bands));
            if let Some(prev) = &previous {
                let prev_reference = inputs.views[i - 1].reference;
                let flicker = flicker_map(&hdr, prev, view.reference, prev_reference);
                flicker_regions.add(&region_array(RegionMeans::of(&flicker, regions)));
                flicker_bands.add(&band_means(&flicker, band, bands));
            }
            evaluation_ms.push(evaluation.elapsed().as_secs_f64() * 1e3);
            previous = Some(hdr);
        }
        let fovvideovdp = match (raw, &inputs.fovvideovdp, &fvvdp_reference) {
            (Some(raw), Ok(metric), Some(reference)) => {
                inputs.bar.set_message(format!(
                    "{}: sequence {} (FovVideoVDP)",
                    inputs.scene_name, spec.name
                ));
                let test = raw.finish().map_err(FoveaError::Backend)?;
                let score = metric.score(
                    inputs.scratch_dir,
                    &test,
                    reference,
                    [w, h],
                    plan.schedule.frames.len() as u32,
                    plan.fps,
                    &fixations,
                    &inputs.display,
                );
                let _ = std::fs::remove_file(&test);
                match score {
                    Ok(s) => Some(s),
                    Err(e) => {
                        fvvdp_failure.get_or_insert(e);
                        None
                    }
                }
            }
            _ => None,
        };
        let (flip_b, rel_b, flicker_b) =
            (flip_bands.means(), rel_bands.means(), flicker_bands.means());
        let band_results = (0..bands)
            .map(|b| BandResult {
                from_deg: f64::from(band_deg) * b as f64,
                to_deg: f64::from(band_deg) * (b + 1) as f64,
                pixels: band_pixels[b],
                flip: flip_b[b],
                rel_mse: rel_b[b],
                flicker: flicker_b[b],
            })
            .collect();
        fovea_series.push(fovea_flip);
        results.push(SequenceResult {
            spec: spec.clone(),
            frames: plan.schedule.frames.len() as u32,
            frame_ms: median(&frame_ms),
            primary_samples_per_frame: samples as f64 / plan.schedule.frames.len() as f64,
            flip: region_means(&flip_regions.means()),
            rel_mse: region_means(&rel_regions.means()),
            flicker: region_means(&flicker_regions.means()),
            bands: band_results,
            fovvideovdp,
            fovea_lag: None,
            evaluation_ms: median(&evaluation_ms),
        });
    }
    if let Some(reference) = &fvvdp_reference {
        let _ = std::fs::remove_file(reference);
    }
    // The fovea's recovery, its error taken relative to uniform 32 spp without history on the same
    // frame: the new point of gaze may see harder content than the old one, which is not lag.
    let baseline = results
        .iter()
        .position(|r| !r.spec.foveated && !r.spec.history && !r.spec.denoise);
    for (result, series) in results.iter_mut().zip(&fovea_series) {
        let relative: Vec<f64> = match baseline {
            Some(b) => series
                .iter()
                .zip(&fovea_series[b])
                .map(|(e, u)| e / u)
                .collect(),
            None => series.clone(),
        };
        result.fovea_lag = fovea_lag(&relative, &saccades);
    }
    Ok(SequenceReport {
        trace: plan.trace.clone(),
        camera_path: plan.camera_path.clone(),
        frames: plan.schedule.frames.len() as u32,
        fps: plan.fps,
        band_deg,
        region_bounds_deg: bounds.map(f64::from),
        saccades,
        fovvideovdp_note: fovvideovdp_note(&inputs.fovvideovdp, fvvdp_failure, &results),
        results,
    })
}

/// What the report says of FovVideoVDP: its setting and run time, or why it did not run.
fn fovvideovdp_note(
    metric: &std::result::Result<&FovVideoVdp, String>,
    failure: Option<String>,
    results: &[SequenceResult],
) -> String {
    match (metric, failure) {
        (Err(why), _) => format!("FovVideoVDP: {why}."),
        (Ok(_), Some(e)) => format!("FovVideoVDP: {e}."),
        (Ok(_), None) => {
            let scored: Vec<&FovVideoVdpScore> = results
                .iter()
                .filter_map(|r| r.fovvideovdp.as_ref())
                .collect();
            let seconds: f64 = scored.iter().map(|s| s.seconds).sum();
            let info = scored.first().map_or("", |s| s.info.as_str());
            format!(
                "FovVideoVDP (pyfvvdp, foveated, the gaze of each frame; display {} cd/m² peak, \
                 {}:1, sRGB): {info}. JOD 10 = no visible difference; 1 JOD less = 75 % of viewers \
                 prefer the other. {:.1} s for {} sequences.",
                super::fvvdp::PEAK_CD_M2,
                super::fvvdp::CONTRAST,
                seconds,
                scored.len()
            )
        }
    }
}

impl SequencePlan {
    /// The plan of `--gaze-trace trace`'s frames, `schedule`, pooled in bands `band_deg` wide.
    pub fn read(
        sequence: &crate::args::SequenceArgs,
        trace: &Path,
        schedule: FrameSchedule,
        band_deg: f32,
    ) -> Result<Self> {
        if !(band_deg.is_finite() && (0.05..=90.0).contains(&band_deg)) {
            return Err(FoveaError::option(
                "--band-deg",
                format!("{band_deg} is not a band width in [0.05, 90] degrees"),
            ));
        }
        Ok(Self {
            trace: trace.display().to_string(),
            schedule,
            fps: sequence.trace_fps,
            band_deg,
            camera_path: sequence
                .camera_path
                .as_ref()
                .map(|p| p.display().to_string()),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, value: f32) -> FrameImage {
        FrameImage {
            width: w,
            height: h,
            pixels: vec![[value, value, value, 1.0]; (w * h) as usize],
        }
    }

    #[test]
    fn eccentricity_grows_from_the_gaze_and_matches_the_display_model() {
        let d = DisplayGeometry {
            resolution: [64, 36],
            ..DisplayGeometry::default()
        };
        let e = eccentricity_map(64, 36, [32.0, 18.0], &d);
        // The four pixels around the gaze are nearest; a corner is farthest.
        let centre = e[(18 * 64 + 32) as usize];
        assert!(centre < 1.0);
        assert!(e[0] > 10.0 * centre);
        // 64 px span the display's 70.848 cm, seen from 60 cm: about 34 degrees to the corner.
        let corner_cm = 31.5f32.hypot(17.5) * 70.848 / 64.0;
        let expect = (corner_cm / 60.0).atan().to_degrees();
        assert!((e[0] - expect).abs() < 1e-3, "{} vs {expect}", e[0]);
    }

    #[test]
    fn a_still_image_does_not_flicker_and_a_change_does_by_its_relative_size() {
        let r = image(4, 2, 1.0);
        assert!(flicker_map(&r, &r, &r, &r).iter().all(|&f| f == 0.0));
        let brighter = image(4, 2, 1.5);
        let f = flicker_map(&brighter, &r, &r, &r);
        let expect = (0.25 / (1.0 + REL_MSE_EPSILON)) as f32;
        assert!(f.iter().all(|&v| (v - expect).abs() < 1e-6));
        // A moving camera: when the scene itself brightens, a render that follows it exactly does not
        // flicker; one that stays behind does, by how far it fell behind.
        assert!(flicker_map(&brighter, &r, &brighter, &r)
            .iter()
            .all(|&f| f == 0.0));
        let f = flicker_map(&r, &r, &brighter, &r);
        let expect = (0.25 / (2.25 + REL_MSE_EPSILON)) as f32;
        assert!(f.iter().all(|&v| (v - expect).abs() < 1e-6));
    }

    #[test]
    fn means_over_frames_skip_empty_bands() {
        let mut m = FrameMeans::new(2);
        m.add(&[1.0, f64::NAN]);
        m.add(&[3.0, f64::NAN]);
        let means = m.means();
        assert_eq!(means[0], 2.0);
        assert!(means[1].is_nan());
        assert_eq!(band_means(&[1.0, 2.0, 4.0], &[0, 0, 2], 3)[0], 1.5);
    }

    #[test]
    fn specs_pair_each_configuration_with_and_without_history_then_sweep() {
        let specs = sequence_specs(&[1, 2, 32]);
        assert_eq!(specs.len(), 8 + 4 + 3 + 1);
        assert_eq!(specs.iter().filter(|s| s.history).count(), 9);
        assert!(specs.iter().any(|s| s.slug == "32-16-8-history"));
        assert!(specs.iter().any(|s| s.slug == "32-16-8-history-denoised"));
        // Uniform 1 spp after its history, denoised: the equal-time partner of the line above.
        let equal = specs.last().unwrap();
        assert_eq!(equal.slug, "uniform-1-history-denoised");
        assert!(equal.history && equal.denoise && !equal.foveated && equal.spp == [1; 3]);
        assert_eq!(specs[9].spp, [2, 2, 2]);
        assert!(specs[11].history && specs[11].spp == [2, 2, 2]);
    }
}
