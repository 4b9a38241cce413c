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
