//! Rendering one camera sample: from a block of the foveated image and a sample index to a radiance
//! estimate. Both hosts call [`render_block_sample`] and nothing else per sample.
pub mod path;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

pub use path::{trace_path, trace_path_with, IntegratorSettings};

use crate::camera::Camera;
use crate::foveation::landing::{block_sample_number, landing_pixel, pixel_sample_position};
use crate::foveation::{samples_in_block, FoveationParams, OwnedBlock};
use crate::geometry::Ray;
use crate::rng::SampleRng;
use crate::scene::{SceneSlices, SceneSource, SceneView};

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

/// Renders sample `sample` of `block`: a camera ray jittered over the pixel of the block the sample
/// lands in ([`sample_pixel`]), traced by the path integrator. The random numbers depend only on (block
/// origin, frame, sample, region, seed).
#[must_use]
pub fn render_block_sample<F: crate::scene::Features>(
    scene: &SceneView<F>,
    frame: &FrameParams,
    block: &OwnedBlock,
    sample: u32,
) -> Vec3 {
    render_block_sample_with(scene, &SceneSlices, frame, block, sample)
}

/// [`render_block_sample`] reading the scene's large arrays from `source` (the GPU's texel buffer).
#[must_use]
pub fn render_block_sample_with<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    frame: &FrameParams,
    block: &OwnedBlock,
    sample: u32,
) -> Vec3 {
    let (ray, mut rng) = camera_sample(frame, block, sample);
    path::trace_camera_path(
        scene,
        source,
        ray,
        cone_spread(frame, block),
        &mut rng,
        &frame.integrator,
    )
}

/// The spread angle of the ray cone of `block`'s camera samples (`crate::material::texture`): a
/// pixel's, `2 tan(fov / 2) / height`, times the block's edge under [`path::TEXTURE_LOD_BLOCK`]; 0
/// under [`path::TEXTURE_LOD_OFF`].
#[inline]
#[must_use]
pub fn cone_spread(frame: &FrameParams, block: &OwnedBlock) -> f32 {
    let lod = frame.integrator.texture_lod;
    if lod == path::TEXTURE_LOD_OFF {
        return 0.0;
    }
    let pixel = pixel_cone_spread(frame);
    if lod == path::TEXTURE_LOD_BLOCK {
        pixel * block.size as f32
    } else {
        pixel
    }
}

/// The spread angle of one pixel's ray cone: `2 tan(fov / 2) / height` (the camera's `up` is
/// `tan(fov / 2)` long).
#[inline]
#[must_use]
pub fn pixel_cone_spread(frame: &FrameParams) -> f32 {
    2.0 * crate::math::vec3_from(frame.camera.up).length() / frame.height.max(1) as f32
}

/// The pixel of `block` that its sample `sample` of this frame lands in
/// ([`crate::foveation::landing`]): every pixel of a block in turn, over the frames.
#[inline]
#[must_use]
pub fn sample_pixel(frame: &FrameParams, block: &OwnedBlock, sample: u32) -> [u32; 2] {
    let spp = samples_in_block(block, &frame.foveation);
    let number = block_sample_number(frame.frame_index, spp, sample);
    landing_pixel(block, frame.width, frame.height, frame.seed, number)
}

/// The index in a buffer of per-pixel values, row-major `frame.width` wide and starting at row
/// `first_row`, of pixel `pixel`.
#[inline]
#[must_use]
fn pixel_index(frame: &FrameParams, first_row: u32, pixel: [u32; 2]) -> usize {
    ((pixel[1] - first_row) * frame.width + pixel[0]) as usize
}

/// Zeroes the per-pixel sample sums (`[r, g, b, count]`, row-major, rows from `first_row`) of
/// `block`'s pixels, before its samples are added ([`add_to_pixel_sum`]).
pub fn clear_block_pixel_sums(
    sums: &mut [[f32; 4]],
    first_row: u32,
    frame: &FrameParams,
    block: &OwnedBlock,
) {
    let e = crate::foveation::block_extent(block, frame.width, frame.height);
    let mut dy = 0;
    while dy < e[1] {
        let mut dx = 0;
        while dx < e[0] {
            let p = [block.origin[0] + dx, block.origin[1] + dy];
            sums[pixel_index(frame, first_row, p)] = [0.0; 4];
            dx += 1;
        }
        dy += 1;
    }
}

/// Adds the value `v` of `block`'s sample `sample` to the sum of the pixel it landed in
/// ([`sample_pixel`]; `[r, g, b, count]`, row-major, rows from `first_row`): the samples pass's
/// per-pixel output, which each pixel's history takes its samples from. Both hosts add a block's
/// samples in sample order.
pub fn add_to_pixel_sum(
    sums: &mut [[f32; 4]],
    first_row: u32,
    frame: &FrameParams,
    block: &OwnedBlock,
    sample: u32,
    v: Vec3,
) {
    let i = pixel_index(frame, first_row, sample_pixel(frame, block, sample));
    let s = sums[i];
    sums[i] = [s[0] + v.x, s[1] + v.y, s[2] + v.z, s[3] + 1.0];
}

/// Sample `sample` of `block`'s camera ray, jittered over the pixel it lands in, and the random
/// numbers its path goes on with.
#[inline]
#[must_use]
fn camera_sample(frame: &FrameParams, block: &OwnedBlock, sample: u32) -> (Ray, SampleRng) {
    let mut rng = SampleRng::new(
        block.origin,
        frame.frame_index,
        sample,
        block.region,
        frame.seed,
    );
    let film = pixel_sample_position(sample_pixel(frame, block, sample), rng.next_2d());
    let ray = frame.camera.generate_ray(film, frame.width, frame.height);
    (ray, rng)
}

/// [`render_block_sample`] for samples `first .. first + out.len()` of `block` (at most
/// [`crate::bvh::packet::PACKET_SIZE`]), their camera rays traced as one packet over the CPU's 8-wide
/// tree ([`crate::bvh::packet`]): `out[k]` is sample `first + k`'s value, the same as
/// [`render_block_sample`] gives it (up to which of two triangles hit at exactly the same distance a
/// camera ray reports).
///
/// # Panics
/// If `out` holds more than [`crate::bvh::packet::PACKET_SIZE`] values.
#[cfg(not(target_arch = "spirv"))]
pub fn render_block_samples_packet<F: crate::scene::Features>(
    scene: &SceneView<F>,
    frame: &FrameParams,
    block: &OwnedBlock,
    first: u32,
    out: &mut [Vec3],
) {
    use crate::bvh::packet::{closest_hits_packet, PACKET_SIZE};
    use crate::bvh::Hit;
    use arrayvec::ArrayVec;
    let mut rngs: ArrayVec<SampleRng, PACKET_SIZE> = ArrayVec::new();
    let mut rays: ArrayVec<Ray, PACKET_SIZE> = ArrayVec::new();
    for k in 0..out.len() as u32 {
        let (ray, rng) = camera_sample(frame, block, first + k);
        rays.push(ray);
        rngs.push(rng);
    }
    let mut hits = [Hit::miss(); PACKET_SIZE];
    closest_hits_packet(
        scene,
        &SceneSlices,
        &rays,
        crate::lights::INFINITE_DISTANCE,
        &mut hits,
    );
    for (k, value) in out.iter_mut().enumerate() {
        *value = path::trace_path_from_hit(
            scene,
            &SceneSlices,
            rays[k],
            cone_spread(frame, block),
            hits[k],
            &mut rngs[k],
            &frame.integrator,
        );
    }
}

/// The sum of samples `0 .. spp` of `block`, in sample order, each also added to the sum of the pixel
/// it landed in ([`add_to_pixel_sum`]; the block's pixels zeroed first): the CPU host's samples pass
/// with per-pixel sums, as the kernel's `reduce_blocks` writes them.
#[cfg(not(target_arch = "spirv"))]
#[must_use]
pub fn block_sample_sum_into_pixels<F: crate::scene::Features>(
    scene: &SceneView<F>,
    frame: &FrameParams,
    block: &OwnedBlock,
    spp: u32,
    sums: &mut [[f32; 4]],
    first_row: u32,
) -> Vec3 {
    use crate::bvh::packet::PACKET_SIZE;
    clear_block_pixel_sums(sums, first_row, frame, block);
    let mut values = [Vec3::ZERO; PACKET_SIZE];
    let mut sum = Vec3::ZERO;
    let mut next = 0;
    while next < spp {
        let n = (spp - next).min(PACKET_SIZE as u32) as usize;
        render_block_samples_packet(scene, frame, block, next, &mut values[..n]);
        for (k, v) in values[..n].iter().enumerate() {
            sum += *v;
            add_to_pixel_sum(sums, first_row, frame, block, next + k as u32, *v);
        }
        next += n as u32;
    }
    sum
}

/// The sum of samples `0 .. spp` of `block`, in sample order, their camera rays traced eight at a time
/// by [`render_block_samples_packet`]: the CPU host's value of a block is this over `spp`.
#[cfg(not(target_arch = "spirv"))]
#[must_use]
pub fn block_sample_sum<F: crate::scene::Features>(
    scene: &SceneView<F>,
    frame: &FrameParams,
    block: &OwnedBlock,
    spp: u32,
) -> Vec3 {
    block_sample_range_sum(scene, frame, block, 0, spp)
}

/// The sum of samples `first .. end` of `block`, in sample order, traced as
/// [`block_sample_sum`] traces them: a part of a render split by samples (`fovea render --samples`).
/// Each sample's value depends only on its own key, so the parts of a split hold exactly the samples
/// one render would.
#[cfg(not(target_arch = "spirv"))]
#[must_use]
pub fn block_sample_range_sum<F: crate::scene::Features>(
    scene: &SceneView<F>,
    frame: &FrameParams,
    block: &OwnedBlock,
    first: u32,
    end: u32,
) -> Vec3 {
    use crate::bvh::packet::PACKET_SIZE;
    let mut values = [Vec3::ZERO; PACKET_SIZE];
    let mut sum = Vec3::ZERO;
    let mut next = first;
    while next < end {
        let n = (end - next).min(PACKET_SIZE as u32) as usize;
        render_block_samples_packet(scene, frame, block, next, &mut values[..n]);
        for v in &values[..n] {
            sum += *v;
        }
        next += n as u32;
    }
    sum
}

/// Renders samples `first`, `first + stride`, `first + 2 stride`, ... below `block_count · spp` of a
/// dispatch chunk, one after the other, into `out[i]` (rgb, `w` = 0): sample `i` is sample `i % spp` of
/// block `blocks[i / spp]`, with the value [`render_block_sample_with`] gives it.
///
/// The GPU kernel runs each invocation over a few samples ([`crate::kernel_abi::SAMPLES_PER_INVOCATION`])
/// rather than one: lavapipe pays a per-workgroup cost (it allocates every SIMD group's frame) that a
/// path tracer's large frames make noticeable (big.obj frames 15 % faster with 4 samples each). The
/// neighbouring lanes of a SIMD group still trace samples of one pixel or block side by side, which
/// keeps their first rays coherent; starting each lane's next sample as soon as its own path ends (path
/// regeneration) lost that and made Lost Empire frames 10 % slower there.
pub fn render_sample_stream<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    frame: &FrameParams,
    blocks: &[OwnedBlock],
    block_count: u32,
    spp: u32,
    first: u32,
    stride: u32,
    out: &mut [[f32; 4]],
) {
    let total = block_count * spp;
    let mut i = first;
    while i < total {
        let block = blocks[(i / spp) as usize];
        let c = render_block_sample_with(scene, source, frame, &block, i % spp);
        out[i as usize] = [c.x, c.y, c.z, 0.0];
        if stride == 0 {
            return;
        }
        i += stride;
    }
}
