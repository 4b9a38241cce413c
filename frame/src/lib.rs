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

/// A frame as a host returns it: the images its request asked for (one type for every host and the
/// command line).
#[derive(Clone, Debug)]
pub struct RenderedFrame {
    pub width: u32,
    pub height: u32,
    /// Linear HDR: the CPU host always has it, a device reads it back when asked.
    pub hdr: Option<FrameImage>,
    /// The tone-mapped 8-bit image, RGBA8 packed in `u32` with R in the low byte (core's
    /// `tonemap_to_rgba8`), where the frame was tone-mapped and read back.
    pub rgba8: Option<Vec<u32>>,
    /// The HDR image before the denoiser's passes, when asked for and they ran.
    pub raw_hdr: Option<FrameImage>,
}

impl RenderedFrame {
    /// The 8-bit image as sRGB RGB bytes (what a PNG stores), where there is one.
    #[must_use]
    pub fn rgb8(&self) -> Option<Vec<u8>> {
        self.rgba8.as_deref().map(rgba8_to_rgb8)
    }
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

/// Two renders of one frame agree on a channel when they differ by at most this share of the larger
/// magnitude...
pub const AGREEMENT_RELATIVE: f32 = 1e-3;
/// ...or by at most this much (values near zero). The cross-backend tests' tolerance, and `fovea
/// compare`'s.
pub const AGREEMENT_ABSOLUTE: f32 = 1e-4;

/// Whether two HDR pixels agree on every channel ([`AGREEMENT_RELATIVE`], [`AGREEMENT_ABSOLUTE`]; a NaN
/// or an infinity agrees with nothing), and their largest finite absolute channel difference.
#[must_use]
pub fn pixels_agree(a: &[f32; 4], b: &[f32; 4]) -> (bool, f32) {
    let mut ok = true;
    let mut max_abs = 0f32;
    for c in 0..3 {
        let d = (a[c] - b[c]).abs();
        if d.is_finite() {
            max_abs = max_abs.max(d);
        }
        if !(d <= AGREEMENT_ABSOLUTE || d / a[c].abs().max(b[c].abs()) <= AGREEMENT_RELATIVE) {
            ok = false;
        }
    }
    (ok, max_abs)
}

/// The fraction of pixels of two HDR images that agree ([`pixels_agree`]) and the largest absolute
/// channel difference.
#[must_use]
pub fn agreement(a: &FrameImage, b: &FrameImage) -> (f64, f32) {
    let mut within = 0usize;
    let mut max_abs = 0f32;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let (ok, d) = pixels_agree(p, q);
        within += usize::from(ok);
        max_abs = max_abs.max(d);
    }
    (within as f64 / a.pixels.len().max(1) as f64, max_abs)
}
