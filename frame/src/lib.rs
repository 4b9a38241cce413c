//! # fovea-frame
//!
//! What a host returns for a frame: the linear HDR image ([`FrameImage`]) and what rendering it cost
//! ([`RenderStats`]). Both hosts (`fovea-cpu`, `fovea-vulkan`) and the command line use these types;
//! they live here, below the hosts, so that neither host depends on the other.

/// A rendered frame in linear HDR (`[r, g, b, 1]` per pixel, row-major, top row first).
#[derive(Clone, Debug)]
pub struct FrameImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

/// What rendering a frame cost.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    /// Time for the passes (samples, cell means, fill; on a device also the tone map and read-back).
    pub render_ms: f64,
    /// Camera samples traced, in total and per region.
    pub primary_samples: u64,
    pub samples_per_region: [u64; 3],
    /// Blocks rendered per region.
    pub blocks_per_region: [u64; 3],
    /// Feature mask of the compiled path that rendered the samples (the CPU's specialised path, the
    /// GPU's specialization constant).
    pub path_features: u32,
    /// Milliseconds of each pass of the frame pipeline, in order (`samples`, `cell_means`, `fill`, and
    /// with temporal reuse `gbuffer` and `temporal`), where the host timed them one by one.
    pub passes: Vec<(&'static str, f64)>,
}

/// The 8-bit sRGB RGB bytes (what a PNG stores) of packed RGBA8 pixels, R in the low byte (core's
/// `tonemap_to_rgba8` layout, which both hosts' tone map writes).
#[must_use]
pub fn rgba8_to_rgb8(pixels: &[u32]) -> Vec<u8> {
    pixels
        .iter()
        .flat_map(|p| [*p as u8, (*p >> 8) as u8, (*p >> 16) as u8])
        .collect()
}
