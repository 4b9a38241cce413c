//! Rendering one camera sample: from a block of the foveated image and a sample index to a radiance
//! estimate. Both hosts call [`render_block_sample`] and nothing else per sample.
pub mod path;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

pub use path::{trace_path, trace_path_with, IntegratorSettings};

use crate::bvh::{SceneSlices, TraversalSource};
use crate::camera::Camera;
use crate::foveation::{block_sample_position, FoveationParams, OwnedBlock};
use crate::rng::SampleRng;
use crate::scene::SceneView;

/// Everything that is fixed for one frame (GPU layout; push constants or a small uniform buffer).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct FrameParams {
    pub camera: Camera,
    pub foveation: FoveationParams,
    pub integrator: IntegratorSettings,
    /// Image size in pixels.
    pub width: u32,
    pub height: u32,
    /// Frame number (gaze traces render one frame per line); part of every random-number key.
    pub frame_index: u32,
    /// User seed; part of every random-number key.
    pub seed: u32,
}

/// Renders sample `sample` of `block`: a jittered camera ray over the block's footprint traced by the
/// path integrator. The random numbers depend only on (block origin, frame, sample, region, seed).
#[must_use]
pub fn render_block_sample<F: crate::scene::Features>(
    scene: &SceneView<F>,
    frame: &FrameParams,
    block: &OwnedBlock,
    sample: u32,
) -> Vec3 {
    render_block_sample_with(scene, &SceneSlices, frame, block, sample)
}

/// [`render_block_sample`] with traversal reading nodes and triangles from `source` (the GPU's texel
/// buffer).
#[must_use]
pub fn render_block_sample_with<F: crate::scene::Features, S: TraversalSource>(
    scene: &SceneView<F>,
    source: &S,
    frame: &FrameParams,
    block: &OwnedBlock,
    sample: u32,
) -> Vec3 {
    let mut rng = SampleRng::new(
        block.origin,
        frame.frame_index,
        sample,
        block.region,
        frame.seed,
    );
    let film = block_sample_position(block, frame.width, frame.height, rng.next_2d());
    let ray = frame.camera.generate_ray(film, frame.width, frame.height);
    trace_path_with(scene, source, ray, &mut rng, &frame.integrator)
}
