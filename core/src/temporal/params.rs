//! What the temporal pass needs besides the frame: the previous frame's camera and size, and the
//! history's caps and clamp (GPU layout; its own binding).
use bytemuck::{Pod, Zeroable};

use crate::camera::Camera;
#[cfg(not(target_arch = "spirv"))]
use crate::integrator::FrameParams;

/// [`TemporalParams::flags`]: the previous history and G-buffer hold a frame (else every pixel starts
/// afresh).
pub const TEMPORAL_HISTORY_VALID: u32 = 1;
/// [`TemporalParams::flags`]: the camera differs from the previous frame's (reproject and clamp).
pub const TEMPORAL_CAMERA_MOVED: u32 = 2;

/// What the temporal pass needs besides the frame (96 bytes, GPU layout; its own binding).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TemporalParams {
    /// The previous frame's camera.
    pub previous_camera: Camera,
    /// The previous frame's image size (of the previous history and G-buffer).
    pub previous_size: [u32; 2],
    /// `TEMPORAL_*` bits.
    pub flags: u32,
    /// The history cap in frames while the camera rests (`N`: each frame counts at least `1 / N`).
    pub max_frames_resting: f32,
    /// The history cap in frames while the camera moves.
    pub max_frames_moving: f32,
    /// The neighbourhood clamp's half-width in standard deviations (`γ`).
    pub clamp_gamma: f32,
    /// The fill mode the frame's filled values were made with (`crate::foveation::FILL_*`): which
    /// albedo their samples saw ([`filled_albedo`]).
    pub fill_mode: u32,
    /// The history's weight cap in samples of the pixel while the camera moves (the frame's own weight
    /// included); the frame cap applies too.
    pub max_weight_moving: f32,
}

/// Default [`TemporalParams::max_frames_resting`]: as many frames as the live view used to average.
pub const DEFAULT_MAX_FRAMES_RESTING: f32 = 4096.0;
/// Default [`TemporalParams::max_frames_moving`] (kajiya and SVGF keep 8 to 32 frames).
pub const DEFAULT_MAX_FRAMES_MOVING: f32 = 16.0;
/// Default [`TemporalParams::max_weight_moving`]: four frames of the paper's fovea (32 spp), sixteen
/// or more of every coarser region. Measured on a slow pan of Lost Empire (`tests/tests/temporal.rs`'s
/// benchmark): a fovea history of 16 frames had 1.4x the error of one of 4, the periphery's error
/// rose by half with 4.
pub const DEFAULT_MAX_WEIGHT_MOVING: f32 = 128.0;
/// Default [`TemporalParams::clamp_gamma`].
pub const DEFAULT_CLAMP_GAMMA: f32 = 1.5;

impl TemporalParams {
    /// The parameters for `frame`, filled in `fill_mode`, after a frame rendered with `previous` (its
    /// camera and image size); `None` starts every pixel's history afresh. Default caps and clamp.
    #[cfg(not(target_arch = "spirv"))]
    #[must_use]
    pub fn after(
        previous: Option<(Camera, [u32; 2])>,
        frame: &FrameParams,
        fill_mode: u32,
    ) -> Self {
        let (previous_camera, previous_size, flags) = match previous {
            None => (frame.camera, [frame.width, frame.height], 0),
            Some((camera, size)) => {
                let moved = camera != frame.camera || size != [frame.width, frame.height];
                let flags = TEMPORAL_HISTORY_VALID | if moved { TEMPORAL_CAMERA_MOVED } else { 0 };
                (camera, size, flags)
            }
        };
        Self {
            previous_camera,
            previous_size,
            flags,
            max_frames_resting: DEFAULT_MAX_FRAMES_RESTING,
            max_frames_moving: DEFAULT_MAX_FRAMES_MOVING,
            clamp_gamma: DEFAULT_CLAMP_GAMMA,
            fill_mode,
            max_weight_moving: DEFAULT_MAX_WEIGHT_MOVING,
        }
    }
}
