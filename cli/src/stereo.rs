//! Both eyes (`render --stereo IPD`, `render --stereo-views FILE`): each frame is two views, the left
//! and the right eye, each with its own camera, gaze and foveation, rendered as views 0 and 1 of one
//! frame ([`fovea_core::passes::FrameRequest::view`]) so that each keeps its own history and
//! G-buffer while the scene and its upload are shared.
//!
//! # Per-eye views file (`--stereo-views`)
//!
//! One line per eye and frame, in OpenXR's conventions (an `XrPosef` and an `XrFovf` as
//! `xrLocateViews` returns them):
//!
//! ```text
//! frame,eye,x,y,z,qx,qy,qz,qw,angle_left,angle_right,angle_up,angle_down
//! 0,left,-0.032,1.6,0,0,0,0,1,-0.94,0.79,0.84,-0.91
//! 0,right,0.032,1.6,0,0,0,0,1,-0.79,0.94,0.84,-0.91
//! ```
//!
//! `eye` is `left` or `right` (or `0`, `1`); `x,y,z` is the eye's position in world coordinates (as
//! `--eye`); `qx,qy,qz,qw` its orientation, a unit quaternion turning the eye's frame (looking
//! along -z, y up, x right) into the world's; the four angles in radians bound its frustum, `left`
//! and `down` negative for a frustum around the view direction. Every frame gives both eyes once. A
//! header line (named by its first field not being a number) and `#` comments are allowed.
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use fovea_core::camera::Camera;
use glam::{DQuat, DVec3, Vec3};

use crate::error::{FoveaError, Result};

/// The views of a stereo frame: the left eye, then the right.
pub const EYES: usize = 2;

/// The most frames a views file may hold.
pub const MAX_VIEW_FRAMES: usize = 1_000_000;

/// The largest frustum angle accepted, in radians: just under 90°, where the film plane would be
/// infinitely wide.
pub const MAX_FRUSTUM_ANGLE: f32 = 1.55;

/// Where a stereo frame's eyes come from.
#[derive(Clone, Debug, PartialEq)]
pub enum StereoSource {
    /// Two eyes `ipd` apart (scene units) along the camera's right vector, the camera between them,
    /// both looking the camera's way with its frustum (a headset's eyes are parallel).
    Separation(f32),
    /// Each frame's eye poses and frusta from a file.
    Views(BTreeMap<u32, [EyeView; EYES]>),
}

/// One eye of one frame: an OpenXR pose and field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeView {
    /// World position (as `--eye`).
    pub position: [f64; 3],
    /// Unit quaternion `x, y, z, w`: the eye's frame (looking along -z, y up) in the world.
    pub orientation: [f64; 4],
    /// `[left, right, up, down]` in radians, as `XrFovf`.
    pub angles: [f32; 4],
}

impl EyeView {
    /// Where the eye looks straight ahead on its `size` image, in pixels (the image's centre for a
    /// symmetric frustum): the gaze when no eye tracker gives one.
    #[must_use]
    #[cfg_attr(not(feature = "vulkan"), allow(dead_code))]
    pub fn ahead_px(&self, [w, h]: [u32; 2]) -> [f32; 2] {
        let [l, r, u, d] = self.angles.map(f32::tan);
        [w as f32 * -l / (r - l), h as f32 * u / (u - d)]
    }

    /// The eye's camera in the scene's coordinates (`origin`: where the scene's origin lies in the
    /// world, see `fovea_scene::rebase`).
    #[must_use]
    pub fn camera(&self, origin: [f64; 3]) -> Camera {
        let [x, y, z, w] = self.orientation;
        let q = DQuat::from_xyzw(x, y, z, w).normalize();
        let forward = (q * DVec3::NEG_Z).as_vec3();
        let up = (q * DVec3::Y).as_vec3();
        let position = Vec3::from(fovea_scene::rebase::to_local(self.position, origin));
        Camera::from_fov_angles(position, forward, up, self.angles)
    }

    /// The focal length of a `width`-pixel image of this frustum, in pixels (pixels per unit of
    /// tangent across the view), from which the foveation radii follow.
    #[must_use]
    pub fn focal_px(&self, width: u32) -> f32 {
        width as f32 / (self.angles[1].tan() - self.angles[0].tan())
    }
}

impl StereoSource {
    /// The two eyes' cameras of frame `number`, whose camera (the one between the eyes) is `mono`;
    /// `origin` is the scene's (see [`EyeView::camera`]).
    pub fn cameras(&self, number: u32, mono: Camera, origin: [f64; 3]) -> Result<[Camera; EYES]> {
        match self {
            Self::Separation(ipd) => Ok([
                mono.moved_sideways(-0.5 * ipd),
                mono.moved_sideways(0.5 * ipd),
            ]),
            Self::Views(views) => {
                let eyes = views.get(&number).ok_or_else(|| {
                    FoveaError::option(
                        "--stereo-views",
                        format!("has no lines for frame {number}, which the run renders"),
                    )
                })?;
                Ok([eyes[0].camera(origin), eyes[1].camera(origin)])
            }
        }
    }

    /// The two eyes of frame `number` for an image `width` pixels wide: their cameras (see
    /// [`Self::cameras`]) and, where a file gives each eye its own frustum, its focal length in
    /// pixels (which sets the eye's radii: [`crate::schedule::FoveationRule::at`]).
    pub fn eye_cameras(
        &self,
        number: u32,
        mono: Camera,
        origin: [f64; 3],
        width: u32,
    ) -> Result<[crate::schedule::EyeCamera; EYES]> {
        let cameras = self.cameras(number, mono, origin)?;
        let views = self.eye_views(number);
        Ok([0, 1].map(|eye| crate::schedule::EyeCamera {
            camera: cameras[eye],
            focal_px: views.map(|v| v[eye].focal_px(width)),
        }))
    }

    /// The two eyes' views of frame `number` from a file, if they come from one.
    #[must_use]
    pub fn eye_views(&self, number: u32) -> Option<&[EyeView; EYES]> {
        match self {
            Self::Separation(_) => None,
            Self::Views(views) => views.get(&number),
        }
    }

    /// The frames a views file numbers (when no gaze trace or camera path does).
    #[must_use]
    pub fn frame_numbers(&self) -> Option<Vec<u32>> {
        match self {
            Self::Separation(_) => None,
            Self::Views(views) => Some(views.keys().copied().collect()),
        }
    }
}

/// `out.png` → `out_left.png` for view 0 of a stereo frame (`out_right.png` for view 1).
#[must_use]
pub fn eye_path(path: &Path, view: usize) -> PathBuf {
    let name = fovea_core::passes::STEREO_VIEW_NAMES[view];
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    match path.extension() {
        Some(ext) => path.with_file_name(format!("{stem}_{name}.{}", ext.to_string_lossy())),
        None => path.with_file_name(format!("{stem}_{name}")),
    }
}

/// A views file's columns, each with the names its header may give it.
const VIEWS_COLUMNS: &[&[&str]] = &[
    &["frame"],
    &["eye"],
    &["x"],
    &["y"],
    &["z"],
    &["qx"],
    &["qy"],
    &["qz"],
    &["qw"],
    &["angle_left", "l", "left"],
    &["angle_right", "r", "right"],
    &["angle_up", "u", "up"],
    &["angle_down", "d", "down"],
];

/// Parses a views file (see the [module documentation](self)); errors name the file and the line.
pub fn parse_eye_views(path: &Path, text: &str) -> Result<BTreeMap<u32, [EyeView; EYES]>> {
    const EXPECTED: &str =
        "expected frame,eye,x,y,z,qx,qy,qz,qw,angle_left,angle_right,angle_up,angle_down";
    // Each frame's eyes as they are read, with the line that gave each.
    let mut frames: BTreeMap<u32, [Option<(EyeView, usize)>; EYES]> = BTreeMap::new();
    let text = crate::csv_lines::strip_bom(text);
    let mut seen_content = false;
    for (index, raw) in text.lines().enumerate() {
        let line_no = index + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        if !std::mem::replace(&mut seen_content, true)
            && crate::csv_lines::is_header(line, VIEWS_COLUMNS, "a views file")
                .map_err(|e| FoveaError::file(path, format!("line {line_no}: {e}")))?
        {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let bad =
            |what: String| FoveaError::file(path, format!("line {line_no}: {what} ({EXPECTED})"));
        if fields.len() != 13 {
            return Err(bad(format!("{} fields in '{line}'", fields.len())));
        }
        let frame: u32 = fields[0]
            .parse()
            .map_err(|_| bad(format!("'{}' is not a frame number", fields[0])))?;
        let eye = match fields[1].to_ascii_lowercase().as_str() {
            "left" | "0" => 0,
            "right" | "1" => 1,
            other => return Err(bad(format!("eye '{other}' is neither left nor right"))),
        };
        let mut v = [0.0f64; 11];
        for (k, f) in fields[2..].iter().enumerate() {
            v[k] = f
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && x.abs() <= f64::from(f32::MAX))
                .ok_or_else(|| bad(format!("'{f}' is not a finite number")))?;
        }
        let orientation = [v[3], v[4], v[5], v[6]];
        let norm = orientation.iter().map(|c| c * c).sum::<f64>().sqrt();
        if (norm - 1.0).abs() > 1e-3 {
            return Err(bad(format!(
                "the orientation {orientation:?} is not a unit quaternion (its length is {norm})"
            )));
        }
        let angles = [v[7], v[8], v[9], v[10]].map(|a| a as f32);
        if let Some(a) = angles.iter().find(|a| a.abs() > MAX_FRUSTUM_ANGLE) {
            return Err(bad(format!(
                "the angle {a} is not within ±{MAX_FRUSTUM_ANGLE} radians; the angles are radians, \
                 as OpenXR's XrFovf gives them"
            )));
        }
        if !(angles[0] < angles[1] && angles[3] < angles[2]) {
            return Err(bad(format!(
                "the angles {angles:?} bound no frustum: angle_left must be below angle_right and \
                 angle_down below angle_up"
            )));
        }
        let view = EyeView {
            position: [v[0], v[1], v[2]],
            orientation,
            angles,
        };
        let slot = frames.entry(frame).or_default();
        if let Some((_, earlier)) = slot[eye] {
            let name = fovea_core::passes::STEREO_VIEW_NAMES[eye];
            return Err(FoveaError::file(
                path,
                format!("lines {earlier} and {line_no} both give frame {frame}'s {name} eye; give each once"),
            ));
        }
        slot[eye] = Some((view, line_no));
        if frames.len() > MAX_VIEW_FRAMES {
            return Err(FoveaError::file(
                path,
                format!("more than {MAX_VIEW_FRAMES} frames"),
            ));
        }
    }
    if frames.is_empty() {
        return Err(FoveaError::file(
            path,
            format!("the views file has no eye lines; {EXPECTED}"),
        ));
    }
    frames
        .into_iter()
        .map(|(frame, eyes)| match eyes {
            [Some((left, _)), Some((right, _))] => Ok((frame, [left, right])),
            [Some(_), None] | [None, Some(_)] => {
                let missing = if eyes[0].is_none() { "left" } else { "right" };
                Err(FoveaError::file(
                    path,
                    format!(
                        "frame {frame} has no line for the {missing} eye; every frame needs both"
                    ),
                ))
            }
            [None, None] => unreachable!("a frame is entered with an eye"),
        })
        .collect()
}

/// Reads and parses a views file.
pub fn read_eye_views(path: &Path) -> Result<BTreeMap<u32, [EyeView; EYES]>> {
    let text = std::fs::read_to_string(path).map_err(|e| FoveaError::file(path, e))?;
    parse_eye_views(path, &text)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TWO_EYES: &str = "frame,eye,x,y,z,qx,qy,qz,qw,l,r,u,d\n\
        0,left,-0.032,1.6,0,0,0,0,1,-0.94,0.79,0.84,-0.91\n\
        0,right,0.032,1.6,0,0,0,0,1,-0.79,0.94,0.84,-0.91\n";

    #[test]
    fn views_files_parse_and_name_bad_lines() {
        let p = Path::new("v.csv");
        let views = parse_eye_views(p, TWO_EYES).unwrap();
        assert_eq!(views.len(), 1);
        assert_eq!(views[&0][1].position, [0.032, 1.6, 0.0]);
        assert_eq!(views[&0][0].angles[0], -0.94);
        // A byte-order mark, and a file without a header: the first line is data.
        let bom = format!("\u{feff}{}", TWO_EYES.split_once('\n').unwrap().1);
        assert_eq!(parse_eye_views(p, &bom).unwrap(), views);
        let line = |s: &str| format!("0,left,0,0,0,0,0,0,1,{s}\n0,right,0,0,0,0,0,0,1,-1,1,1,-1\n");
        for (text, needle) in [
            ("0,left,0,0,0,0,0,0,1,-1,1,1\n".to_string(), "12 fields"),
            ("0,middle,0,0,0,0,0,0,1,-1,1,1,-1\n".into(), "'middle'"),
            (
                "0,left,0,0,0,0,0,0,2,-1,1,1,-1\n".into(),
                "not a unit quaternion",
            ),
            (line("-60,60,45,-45"), "radians"),
            (line("1,-1,1,-1"), "bound no frustum"),
            (line("-1,1,1,nan"), "'nan'"),
            (
                "0,left,0,0,0,0,0,0,1,-1,1,1,-1\n".into(),
                "no line for the right eye",
            ),
            (
                format!("{}0,left,0,0,0,0,0,0,1,-1,1,1,-1\n", line("-1,1,1,-1")),
                "lines 1 and 3",
            ),
            ("# nothing\n".into(), "no eye lines"),
            (
                "frame,eye,x,y,z,qw,qx,qy,qz,l,r,u,d\n".into(),
                "names its columns frame,eye,x,y,z,qx,qy,qz,qw,angle_left",
            ),
            (
                "frame;eye;x;y;z;qx;qy;qz;qw;l;r;u;d\n".into(),
                "separated by semicolons",
            ),
            (
                "time,eye\n".into(),
                "line 1: 'time,eye' is neither a header",
            ),
        ] {
            let e = parse_eye_views(p, &text).unwrap_err().to_string();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
    }

    #[test]
    fn an_identity_pose_looks_down_minus_z_with_its_frustum() {
        let views = parse_eye_views(Path::new("v.csv"), TWO_EYES).unwrap();
        let left = views[&0][0];
        let camera = left.camera([0.0; 3]);
        let centre_ray = camera.generate_ray(glam::Vec2::new(100.0, 50.0), 200, 100);
        // The image's centre looks off axis, towards the side with the wider angle.
        assert!(centre_ray.direction.x < 0.0 && centre_ray.direction.z < 0.0);
        let edge = camera
            .generate_ray(glam::Vec2::new(0.0, 50.0), 200, 100)
            .direction;
        assert!((edge.x.atan2(-edge.z) + 0.94).abs() < 1e-5);
        assert!((left.focal_px(200) - 200.0 / (0.79f32.tan() + 0.94f32.tan())).abs() < 1e-3);
        // A pose the scene's origin moved away from is read in world coordinates.
        let moved = left.camera([0.0, 1.0, 0.0]);
        assert!(
            (Vec3::from_slice(&moved.position[..3]) - Vec3::new(-0.032, 0.6, 0.0)).length() < 1e-6
        );
    }

    #[test]
    fn eye_paths_name_the_eye() {
        assert_eq!(
            eye_path(Path::new("out/a.png"), 0),
            PathBuf::from("out/a_left.png")
        );
        assert_eq!(
            eye_path(Path::new("b.exr"), 1),
            PathBuf::from("b_right.exr")
        );
    }
}
