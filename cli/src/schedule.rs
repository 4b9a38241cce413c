//! The one frame driver of `render`, `report` and `view`: which frames a run renders (each one's
//! number, gaze and camera, from `--gaze`, a `--gaze-trace`, a `--camera-path` or, in `view`, live
//! input), and the one place that turns a run's settings into core's [`FrameParams`] and
//! [`FrameRequest`].
//!
//! A new frame option is a field of a clap group in `args.rs` and of [`FrameSettings`] here; every
//! command renders through [`FrameSettings::frame`] and [`FrameSettings::request`].
use std::collections::HashMap;

use fovea_core::camera::Camera;
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::integrator::{FrameParams, IntegratorSettings};
use fovea_core::passes::{FrameOutput, FrameRequest};

use crate::args::{ImageArgs, PathArgs, SequenceArgs};
use crate::camera_path::{read_camera_path, CameraKey};
use crate::error::{FoveaError, Result};

/// One frame of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScheduledFrame {
    /// The frame's number: part of its random-number key, and of its output file's name.
    pub number: u32,
    /// The fixation, in image pixels (between the eyes where a trace gives both).
    pub gaze: [f32; 2],
    /// Each eye's fixation, the left's then the right's, where a trace gives both (`None`: `gaze`
    /// for both).
    pub eyes: Option<[[f32; 2]; 2]>,
    /// The camera `--camera-path` gives the frame; `None` keeps the run's own camera.
    pub camera: Option<CameraKey>,
}

impl ScheduledFrame {
    /// Eye `view`'s fixation (0 left, 1 right): its own where the trace gives both, else `gaze`.
    #[must_use]
    pub fn eye_gaze(&self, view: usize) -> [f32; 2] {
        self.eyes.map_or(self.gaze, |eyes| eyes[view])
    }
}

/// What a `--camera-path` without a `--gaze-trace` means to a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LonePath {
    /// Its lines are the frames, all with the still frame's gaze (`render`).
    NumbersFrames,
    /// It is refused: the command's sequences follow a gaze trace (`report`).
    NeedsTrace,
}

/// The frames of a run, in the order they are rendered.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameSchedule {
    pub frames: Vec<ScheduledFrame>,
    /// Whether the frames come from files (a trace or a path), so that each gets its own output.
    pub from_files: bool,
    /// What may surprise about the trace's frames (a clock that does not start at 0, skipped frame
    /// numbers), one line each, for the command's warnings.
    pub notes: Vec<String>,
}

/// The frames a camera path gives, for messages: `frames 0 to 60 (61 lines)`.
fn span_of_keys(keys: &[CameraKey]) -> String {
    let lo = keys.iter().map(|k| k.frame).min().unwrap_or(0);
    let hi = keys.iter().map(|k| k.frame).max().unwrap_or(0);
    format!("frames {lo} to {hi} ({} lines)", keys.len())
}

impl FrameSchedule {
    /// The frames `sequence` gives for an `image` (a gaze trace's, a camera path's, or both, the path
    /// then giving every frame of the trace its camera), or `still` alone where it gives none.
    /// `max_frames` keeps the first frames only (`report --sequence-frames`). Errors name the option.
    pub fn read(
        sequence: &SequenceArgs,
        still: ScheduledFrame,
        image: [u32; 2],
        lone_path: LonePath,
        max_frames: Option<u32>,
    ) -> Result<Self> {
        if max_frames == Some(0) {
            return Err(FoveaError::option(
                "--sequence-frames",
                "renders at least one frame; give 1 or more",
            ));
        }
        let mut notes = Vec::new();
        let trace = match &sequence.gaze_trace {
            Some(path) => {
                let read = crate::gaze::read_trace_frames(
                    path,
                    sequence.trace_fps,
                    sequence.gaze_normalized,
                    image,
                )?;
                notes.extend(read.note);
                let eyes: Vec<Option<[[f32; 2]; 2]>> = match read.eyes {
                    Some(eyes) => eyes.into_iter().map(Some).collect(),
                    None => vec![None; read.frames.len()],
                };
                Some(
                    read.frames
                        .into_iter()
                        .zip(eyes)
                        .map(|((number, gaze), eyes)| (number, gaze, eyes))
                        .collect::<Vec<_>>(),
                )
            }
            None => None,
        };
        let keys = match (&sequence.camera_path, &trace, lone_path) {
            (Some(_), None, LonePath::NeedsTrace) => {
                return Err(FoveaError::option(
                    "--camera-path",
                    "moves the camera over a sequence; add --gaze-trace FILE.csv",
                ))
            }
            (Some(path), ..) => Some(read_camera_path(path)?),
            (None, ..) => None,
        };
        let mut frames: Vec<ScheduledFrame> = match (trace, &keys) {
            (Some(trace), keys) => {
                let by_frame: Option<HashMap<u32, CameraKey>> = keys
                    .as_ref()
                    .map(|k| k.iter().map(|k| (k.frame, *k)).collect());
                trace
                    .into_iter()
                    .map(|(number, gaze, eyes)| {
                        let camera = match &by_frame {
                            None => None,
                            Some(by_frame) => Some(*by_frame.get(&number).ok_or_else(|| {
                                let held = keys.as_deref().map_or(String::new(), span_of_keys);
                                FoveaError::option(
                                    "--camera-path",
                                    format!(
                                        "has no line for frame {number}, which the --gaze-trace \
                                         renders (the path gives {held})"
                                    ),
                                )
                            })?),
                        };
                        Ok(ScheduledFrame {
                            number,
                            gaze,
                            eyes,
                            camera,
                        })
                    })
                    .collect::<Result<_>>()?
            }
            (None, Some(keys)) => keys
                .iter()
                .map(|k| ScheduledFrame {
                    number: k.frame,
                    camera: Some(*k),
                    ..still
                })
                .collect(),
            (None, None) => vec![still],
        };
        if let (Some(keys), Some(_)) = (&keys, &sequence.gaze_trace) {
            let rendered: std::collections::HashSet<u32> =
                frames.iter().map(|f| f.number).collect();
            let unused = keys.iter().filter(|k| !rendered.contains(&k.frame)).count();
            if unused > 0 {
                notes.push(format!(
                    "the --camera-path gives {unused} frame(s) the --gaze-trace does not render \
                     (unused; the path gives {})",
                    span_of_keys(keys)
                ));
            }
        }
        if let Some(n) = max_frames {
            frames.truncate(n as usize);
        }
        for f in &frames {
            let eyes = f.eyes.unwrap_or([f.gaze; 2]);
            if eyes
                .iter()
                .flatten()
                .any(|v| v.abs() > crate::values::MAX_GAZE_OFFSET)
            {
                return Err(FoveaError::option(
                    "--gaze-trace",
                    format!("{:?} is absurdly far off the image", f.gaze),
                ));
            }
        }
        Ok(Self {
            frames,
            from_files: sequence.gaze_trace.is_some() || sequence.camera_path.is_some(),
            notes,
        })
    }

    /// Each frame's camera: the path's, chosen by `choose`, or `base`.
    pub fn cameras(
        &self,
        base: Camera,
        choose: impl Fn(&CameraKey) -> Result<Camera>,
    ) -> Result<Vec<Camera>> {
        self.frames
            .iter()
            .map(|f| f.camera.as_ref().map_or(Ok(base), &choose))
            .collect()
    }
}

/// How a run's foveation follows each view's gaze: the template (its sample counts, blocks and
/// radii), whether the run is uniform (no gaze), and where an eye's own frustum sets its radii.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FoveationRule {
    pub template: FoveationParams,
    pub uniform: bool,
    /// The regions' bounds in degrees (`--eccentricity`) where the radii follow each eye's focal
    /// length; `None` where `--radii` fixes them in pixels.
    pub eye_eccentricity: Option<[f32; 2]>,
}

impl FoveationRule {
    /// The foveation of a view fixating `gaze` (pixels), whose image has a focal length of
    /// `focal_px` pixels where its own frustum is given (an eye of `--stereo-views` or a headset).
    #[must_use]
    pub fn at(&self, gaze: [f32; 2], focal_px: Option<f32>) -> FoveationParams {
        let mut foveation = self.template;
        if self.uniform {
            return foveation;
        }
        foveation.gaze = gaze;
        if let (Some(eccentricity), Some(focal)) = (self.eye_eccentricity, focal_px) {
            // The eye's own angles set its pixels per degree, and so its radii.
            [foveation.radius_fovea, foveation.radius_intermediate] =
                eye_radii(eccentricity, focal);
        }
        foveation
    }
}

/// The region radii in pixels of an eye whose image has a focal length of `focal_px` pixels, for
/// regions bounded at `eccentricity` degrees: the paper's `r = (a / 2) · R / A` with `a = 2 d
/// tan(e / 2)` is `r = f · tan(e / 2)` for the focal length `f = d · R / A` in pixels.
#[must_use]
pub fn eye_radii(eccentricity: [f32; 2], focal_px: f32) -> [f32; 2] {
    eccentricity.map(|e| focal_px * (0.5 * e.to_radians()).tan())
}

/// One view of a frame as a run renders it: which (`None` for a frame of one view, else the eye,
/// 0 left, 1 right), and core's parameters for it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameView {
    pub view: Option<usize>,
    pub frame: FrameParams,
}

/// An eye of a frame: its camera, and its focal length in pixels where its own frustum is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeCamera {
    pub camera: Camera,
    pub focal_px: Option<f32>,
}

/// What every frame of a run shares. [`Self::frame`] and [`Self::request`] are the only places the
/// command line makes core's [`FrameParams`] and [`FrameRequest`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSettings {
    /// The image size in pixels.
    pub size: [u32; 2],
    pub integrator: IntegratorSettings,
    /// The seed of every random number (with the frame's number).
    pub seed: u32,
    /// `FILL_BILINEAR` or `FILL_REPLICATE`.
    pub fill_mode: u32,
    /// The tone map's exposure, in stops.
    pub exposure_ev: f32,
}

impl FrameSettings {
    /// The settings `path` and `image` give an image of `size` pixels.
    #[must_use]
    pub fn new(size: [u32; 2], path: &PathArgs, image: &ImageArgs) -> Self {
        Self {
            size,
            integrator: path.integrator(),
            seed: image.seed,
            fill_mode: path.fill_mode(),
            exposure_ev: image.exposure,
        }
    }

    /// Every option at its default, for a benchmark's fixed frame (`fovea bench scale`).
    #[must_use]
    pub fn defaults(size: [u32; 2], seed: u32) -> Self {
        Self {
            size,
            integrator: IntegratorSettings::default(),
            seed,
            fill_mode: fovea_core::foveation::fill::FILL_BILINEAR,
            exposure_ev: 0.0,
        }
    }

    /// The same settings with textures read at `texture_lod` (`integrator::path::TEXTURE_LOD_*`).
    #[must_use]
    pub fn with_texture_lod(self, texture_lod: u32) -> Self {
        Self {
            integrator: IntegratorSettings {
                texture_lod,
                ..self.integrator
            },
            ..self
        }
    }

    /// The same settings for an image of `size` pixels (the live view's window changes size).
    #[must_use]
    #[cfg_attr(not(feature = "vulkan"), allow(dead_code))]
    pub fn with_size(self, size: [u32; 2]) -> Self {
        Self { size, ..self }
    }

    /// Frame `number` seen by `camera`, foveated by `foveation`.
    #[must_use]
    pub fn frame(&self, number: u32, camera: Camera, foveation: FoveationParams) -> FrameParams {
        self.view_frame(number, 0, camera, foveation)
    }

    /// View `view` (an eye) of frame `number`: seen by its `camera`, foveated around its own gaze,
    /// with random numbers of its own ([`fovea_core::rng::view_seed`]; view 0's are a single view's).
    #[must_use]
    pub fn view_frame(
        &self,
        number: u32,
        view: u32,
        camera: Camera,
        foveation: FoveationParams,
    ) -> FrameParams {
        FrameParams {
            camera,
            foveation,
            integrator: self.integrator,
            width: self.size[0],
            height: self.size[1],
            frame_index: number,
            seed: fovea_core::rng::view_seed(self.seed, view),
        }
    }

    /// The views `scheduled` renders, each with its parameters: one seen by `camera`, or, with
    /// `eyes`, each eye by its own camera, fixating its own gaze (the trace's for that eye, else the
    /// frame's), foveated by `rule`. Every command renders its frames through this.
    #[must_use]
    pub fn views(
        &self,
        scheduled: &ScheduledFrame,
        camera: Camera,
        eyes: Option<[EyeCamera; 2]>,
        rule: &FoveationRule,
    ) -> Vec<FrameView> {
        match eyes {
            None => vec![FrameView {
                view: None,
                frame: self.frame(scheduled.number, camera, rule.at(scheduled.gaze, None)),
            }],
            Some(eyes) => eyes
                .iter()
                .enumerate()
                .map(|(view, eye)| {
                    let foveation = rule.at(scheduled.eye_gaze(view), eye.focal_px);
                    FrameView {
                        view: Some(view),
                        frame: self.view_frame(
                            scheduled.number,
                            view as u32,
                            eye.camera,
                            foveation,
                        ),
                    }
                })
                .collect(),
        }
    }

    /// How to render a frame: with a history and the denoiser or not, its image going to `output`.
    #[must_use]
    pub fn request(&self, history: bool, denoise: bool, output: FrameOutput) -> FrameRequest {
        FrameRequest::new(self.fill_mode, self.exposure_ev, history, denoise, output)
    }

    /// The image's aspect ratio (width over height), for a camera.
    #[must_use]
    pub fn aspect(&self) -> f32 {
        self.size[0] as f32 / self.size[1] as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::{Path, PathBuf};

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn sequence(trace: Option<PathBuf>, path: Option<PathBuf>) -> SequenceArgs {
        SequenceArgs {
            gaze_trace: trace,
            trace_fps: 30.0,
            gaze_normalized: false,
            camera_path: path,
        }
    }

    const STILL: ScheduledFrame = ScheduledFrame {
        number: 7,
        gaze: [5.0, 6.0],
        eyes: None,
        camera: None,
    };

    #[test]
    fn a_trace_and_a_path_give_each_frame_its_gaze_and_camera() {
        let dir = std::env::temp_dir().join(format!("fovea-schedule-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let trace = write(&dir, "t.csv", "0,1,2\n1,3,4\n2,5,6\n");
        let path = write(
            &dir,
            "p.csv",
            "frame,ex,ey,ez,tx,ty,tz\n0,0,0,1,0,0,0\n1,0,0,2,0,0,0\n2,0,0,3,0,0,0\n",
        );
        let image = [64, 48];
        let s = FrameSchedule::read(
            &sequence(Some(trace.clone()), Some(path.clone())),
            STILL,
            image,
            LonePath::NeedsTrace,
            None,
        )
        .unwrap();
        assert!(s.from_files);
        assert_eq!(s.frames.len(), 3);
        assert_eq!(s.frames[1].gaze, [3.0, 4.0]);
        assert_eq!(s.frames[2].camera.unwrap().eye, [0.0, 0.0, 3.0]);
        // At most two frames.
        let two = FrameSchedule::read(
            &sequence(Some(trace.clone()), None),
            STILL,
            image,
            LonePath::NeedsTrace,
            Some(2),
        )
        .unwrap();
        assert_eq!(two.frames.len(), 2);
        assert!(two.frames.iter().all(|f| f.camera.is_none()));
        // A path alone numbers the frames for `render` and is refused by `report`.
        let alone = FrameSchedule::read(
            &sequence(None, Some(path.clone())),
            STILL,
            image,
            LonePath::NumbersFrames,
            None,
        )
        .unwrap();
        assert_eq!(
            alone.frames.iter().map(|f| f.number).collect::<Vec<_>>(),
            [0, 1, 2]
        );
        assert!(alone.frames.iter().all(|f| f.gaze == STILL.gaze));
        let e = FrameSchedule::read(
            &sequence(None, Some(path)),
            STILL,
            image,
            LonePath::NeedsTrace,
            None,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("--gaze-trace"), "{e}");
        // A path that lacks one of the trace's frames names it.
        let short = write(&dir, "s.csv", "0,0,0,1,0,0,0\n1,0,0,2,0,0,0\n");
        let e = FrameSchedule::read(
            &sequence(Some(trace.clone()), Some(short)),
            STILL,
            image,
            LonePath::NeedsTrace,
            None,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("frame 2") && e.contains("the path gives frames 0 to 1 (2 lines)"),
            "{e}"
        );
        // A path with frames the trace does not render says so.
        let long = write(
            &dir,
            "l.csv",
            "0,0,0,1,0,0,0\n1,0,0,2,0,0,0\n2,0,0,3,0,0,0\n3,0,0,4,0,0,0\n",
        );
        let s = FrameSchedule::read(
            &sequence(Some(trace), Some(long)),
            STILL,
            image,
            LonePath::NeedsTrace,
            None,
        )
        .unwrap();
        assert!(
            s.notes
                .iter()
                .any(|n| n.contains("gives 1 frame(s) the --gaze-trace does not render")),
            "{:?}",
            s.notes
        );
        // Neither: the still frame.
        let still = FrameSchedule::read(
            &sequence(None, None),
            STILL,
            image,
            LonePath::NumbersFrames,
            None,
        )
        .unwrap();
        assert_eq!(still.frames, [STILL]);
        assert!(!still.from_files);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
