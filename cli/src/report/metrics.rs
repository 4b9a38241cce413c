//! Error against the reference, per foveation region: mean FLIP (Andersson et al. 2020, through the
//! `nv-flip` crate) on the tone-mapped 8-bit sRGB images, and relMSE on the linear HDR images.
//!
//! A pixel's region is the region of the block that owns it under the paper's foveation
//! ([`fovea_core::foveation::blocks::owning_block`], the rule both renderers use), so every configuration
//! is measured over the same pixel sets.
use fovea_core::foveation::blocks::owning_block;
use fovea_core::foveation::regions::FoveationParams;
use fovea_cpu::FrameImage;

/// The ε of relMSE: `(x - r)² / (r² + ε)`.
pub const REL_MSE_EPSILON: f64 = 1.0e-2;

/// The region (0 fovea, 1 intermediate, 2 periphery) of every pixel, row-major.
pub struct RegionMap {
    pub region: Vec<u8>,
    /// Pixels per region.
    pub pixels: [u64; 3],
}

impl RegionMap {
    /// The regions of a `width × height` image under `foveation`.
    #[must_use]
    pub fn new(width: u32, height: u32, foveation: &FoveationParams) -> Self {
        let mut region = Vec::with_capacity(width as usize * height as usize);
        let mut pixels = [0u64; 3];
        for y in 0..height {
            for x in 0..width {
                let r = owning_block(x, y, foveation).region.min(2) as u8;
                pixels[r as usize] += 1;
                region.push(r);
            }
        }
        Self { region, pixels }
    }
}

/// A mean over the whole image and over each region; NaN for a region without pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionMeans {
    pub all: f64,
    pub fovea: f64,
    pub intermediate: f64,
    pub periphery: f64,
}

impl RegionMeans {
    /// Exact (f64-accumulated) means of the per-pixel `values`.
    #[must_use]
    pub fn of(values: &[f32], map: &RegionMap) -> Self {
        assert_eq!(values.len(), map.region.len(), "one value per pixel");
        let mut sum = [0.0f64; 3];
        for (v, r) in values.iter().zip(&map.region) {
            sum[*r as usize] += f64::from(*v);
        }
        let mean = |s: f64, n: u64| if n == 0 { f64::NAN } else { s / n as f64 };
        Self {
            all: mean(sum.iter().sum(), map.pixels.iter().sum()),
            fovea: mean(sum[0], map.pixels[0]),
            intermediate: mean(sum[1], map.pixels[1]),
            periphery: mean(sum[2], map.pixels[2]),
        }
    }

    /// The four values in the order all, fovea, intermediate, periphery.
    #[must_use]
    pub fn to_array(self) -> [f64; 4] {
        [self.all, self.fovea, self.intermediate, self.periphery]
    }
}

/// Per-pixel relMSE, the mean over the three channels of `(x - r)² / (r² + ε)` (linear HDR).
#[must_use]
pub fn rel_mse_map(test: &FrameImage, reference: &FrameImage) -> Vec<f32> {
    assert_eq!(test.pixels.len(), reference.pixels.len(), "same size");
    test.pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(x, r)| {
            let mut s = 0.0f64;
            for c in 0..3 {
                let (x, r) = (f64::from(x[c]), f64::from(r[c]));
                s += (x - r) * (x - r) / (r * r + REL_MSE_EPSILON);
            }
            (s / 3.0) as f32
        })
        .collect()
}

/// The FLIP error map (values in [0, 1]) of `test` against `reference`, both 8-bit sRGB RGB bytes, at
/// `pixels_per_degree`.
#[must_use]
pub fn flip_map(
    reference: &[u8],
    test: &[u8],
    width: u32,
    height: u32,
    pixels_per_degree: f32,
) -> Vec<f32> {
    let r = nv_flip::FlipImageRgb8::with_data(width, height, reference);
    let t = nv_flip::FlipImageRgb8::with_data(width, height, test);
    nv_flip::flip(r, t, pixels_per_degree).to_vec()
}

/// The FLIP error map coloured with FLIP's magma map, as RGB bytes (like the paper's Figure 3).
#[must_use]
pub fn flip_map_rgb8(error: &[f32], width: u32, height: u32) -> Vec<u8> {
    nv_flip::FlipImageFloat::with_data(width, height, error)
        .apply_color_lut(&nv_flip::magma_lut())
        .to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> FrameImage {
        FrameImage {
            width: w,
            height: h,
            pixels: (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| {
                    let v = f(x, y);
                    [v, v, v, 1.0]
                })
                .collect(),
        }
    }

    #[test]
    fn region_map_follows_block_ownership() {
        let p = FoveationParams::paper([16.0, 16.0], 4.0, 10.0);
        let map = RegionMap::new(32, 24, &p);
        assert_eq!(map.pixels.iter().sum::<u64>(), 32 * 24);
        for y in 0..24 {
            for x in 0..32 {
                assert_eq!(
                    u32::from(map.region[(y * 32 + x) as usize]),
                    owning_block(x, y, &p).region
                );
            }
        }
        assert!(map.pixels.iter().all(|&n| n > 0));
        let uniform = RegionMap::new(8, 8, &FoveationParams::uniform(4));
        assert_eq!(uniform.pixels, [64, 0, 0]);
    }

    #[test]
    fn region_means_are_exact_and_nan_when_empty() {
        let p = FoveationParams::paper([2.0, 2.0], 1.5, 1.5);
        let map = RegionMap::new(8, 4, &p);
        let values: Vec<f32> = map.region.iter().map(|&r| 1.0 + f32::from(r)).collect();
        let m = RegionMeans::of(&values, &map);
        assert_eq!(m.fovea, 1.0);
        assert!(m.intermediate.is_nan(), "radii equal: no intermediate ring");
        assert_eq!(m.periphery, 3.0);
        let expected = (map.pixels[0] + 3 * map.pixels[2]) as f64 / 32.0;
        assert!((m.all - expected).abs() < 1e-12);
    }

    #[test]
    fn rel_mse_of_known_images() {
        let r = image(4, 2, |_, _| 1.0);
        let x = image(4, 2, |x, _| if x == 0 { 2.0 } else { 1.0 });
        let e = rel_mse_map(&x, &r);
        assert!((e[0] - (1.0 / 1.01) as f32).abs() < 1e-6);
        assert_eq!(e[1], 0.0);
        // Dark reference pixels are guarded by ε.
        let e = rel_mse_map(&image(1, 1, |_, _| 0.1), &image(1, 1, |_, _| 0.0));
        assert!((e[0] - 1.0).abs() < 1e-6);
    }

    #[test]
    fn flip_is_zero_for_equal_images_and_grows_with_difference() {
        let (w, h) = (32, 24);
        let a: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 200) as u8).collect();
        let zero = flip_map(&a, &a, w, h, 10.0);
        assert_eq!(zero.len(), (w * h) as usize);
        assert!(zero.iter().all(|&v| v == 0.0));
        let b: Vec<u8> = a.iter().map(|&v| v.saturating_add(40)).collect();
        let c: Vec<u8> = a.iter().map(|&v| v.saturating_add(120)).collect();
        let mean = |m: Vec<f32>| m.iter().map(|&v| f64::from(v)).sum::<f64>() / m.len() as f64;
        let (small, large) = (
            mean(flip_map(&a, &b, w, h, 10.0)),
            mean(flip_map(&a, &c, w, h, 10.0)),
        );
        assert!(
            0.0 < small && small < large && large <= 1.0,
            "{small} {large}"
        );
        let colours = flip_map_rgb8(&zero, w, h);
        assert_eq!(colours.len(), (w * h * 3) as usize);
    }
}
