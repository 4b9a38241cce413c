//! Counter-based random numbers: every random number is a hash of where it is used, never a stream that
//! threads share, so an image does not depend on the thread count or the order in which work is done.
//!
//! The hash is PCG4D (Jarzynski and Olano 2020, "Hash Functions for GPU Rendering", JCGT 9(3)): four 32-bit
//! words in, four well-mixed words out, in integer arithmetic only, so the CPU and the GPU produce
//! bit-identical sequences.
use glam::{Vec2, Vec3};

/// PCG4D: hashes four words into four.
#[inline]
#[must_use]
pub fn pcg4d(v: [u32; 4]) -> [u32; 4] {
    let mut x = v[0].wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
    let mut y = v[1].wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
    let mut z = v[2].wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
    let mut w = v[3].wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
    x = x.wrapping_add(y.wrapping_mul(w));
    y = y.wrapping_add(z.wrapping_mul(x));
    z = z.wrapping_add(x.wrapping_mul(y));
    w = w.wrapping_add(y.wrapping_mul(z));
    x ^= x >> 16;
    y ^= y >> 16;
    z ^= z >> 16;
    w ^= w >> 16;
    x = x.wrapping_add(y.wrapping_mul(w));
    y = y.wrapping_add(z.wrapping_mul(x));
    z = z.wrapping_add(x.wrapping_mul(y));
    w = w.wrapping_add(y.wrapping_mul(z));
    [x, y, z, w]
}

/// Maps 32 random bits to a float uniform in [0, 1) (the top 24 bits, so 1.0 is never returned).
#[inline]
#[must_use]
pub fn u32_to_unit_float(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The seed of view `view` of a frame seeded `seed`: view 0 keeps it (a single view renders as it
/// always has), the others get their own, so two eyes never draw the same random numbers for the same
/// pixel (correlated noise would look like a pattern on the screen's plane).
#[inline]
#[must_use]
pub const fn view_seed(seed: u32, view: u32) -> u32 {
    seed.wrapping_add(view.wrapping_mul(0x85eb_ca6b))
}

/// The random numbers of one camera sample: a hash of (pixel, frame, sample, region, seed) and a counter
/// of draws.
///
/// The key is the final pixel that owns the sample (for a block, its top-left pixel), the frame index, the
/// sample index within its pixel or block, and the region, so the three regions never share streams (the
/// reference code seeded from the launch index and reused streams across regions).
#[derive(Clone, Copy, Debug)]
pub struct SampleRng {
    key: [u32; 4],
    counter: u32,
}

impl SampleRng {
    /// The sequence for one camera sample.
    #[inline]
    #[must_use]
    pub fn new(pixel: [u32; 2], frame: u32, sample: u32, region: u32, seed: u32) -> Self {
        // Hash the key once so that nearby pixels and samples start from unrelated states.
        let key = pcg4d([
            pixel[0],
            pixel[1],
            frame ^ seed.wrapping_mul(0x9e37_79b9),
            sample.wrapping_mul(4).wrapping_add(region),
        ]);
        Self { key, counter: 0 }
    }

    /// Four fresh uniform 32-bit words.
    #[inline]
    #[must_use]
    pub fn next_u32x4(&mut self) -> [u32; 4] {
        let out = pcg4d([
            self.key[0],
            self.key[1],
            self.key[2],
            self.key[3].wrapping_add(self.counter),
        ]);
        self.counter = self.counter.wrapping_add(1);
        out
    }

    /// One uniform float in [0, 1).
    #[inline]
    #[must_use]
    pub fn next_1d(&mut self) -> f32 {
        u32_to_unit_float(self.next_u32x4()[0])
    }

    /// Two uniform floats in [0, 1).
    #[inline]
    #[must_use]
    pub fn next_2d(&mut self) -> Vec2 {
        let r = self.next_u32x4();
        Vec2::new(u32_to_unit_float(r[0]), u32_to_unit_float(r[1]))
    }

    /// Three uniform floats in [0, 1).
    #[inline]
    #[must_use]
    pub fn next_3d(&mut self) -> Vec3 {
        let r = self.next_u32x4();
        Vec3::new(
            u32_to_unit_float(r[0]),
            u32_to_unit_float(r[1]),
            u32_to_unit_float(r[2]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_floats_stay_below_one() {
        assert_eq!(u32_to_unit_float(0), 0.0);
        assert!(u32_to_unit_float(u32::MAX) < 1.0);
    }

    #[test]
    fn streams_differ_by_every_key_component() {
        let base = SampleRng::new([10, 20], 0, 3, 0, 0).next_u32x4();
        let variants = [
            SampleRng::new([11, 20], 0, 3, 0, 0),
            SampleRng::new([10, 21], 0, 3, 0, 0),
            SampleRng::new([10, 20], 1, 3, 0, 0),
            SampleRng::new([10, 20], 0, 4, 0, 0),
            SampleRng::new([10, 20], 0, 3, 1, 0),
            SampleRng::new([10, 20], 0, 3, 0, 1),
        ];
        for mut v in variants {
            assert_ne!(v.next_u32x4(), base);
        }
    }

    #[test]
    fn uniform_mean_and_variance() {
        let mut sum = 0.0f64;
        let mut sum2 = 0.0f64;
        let n = 200_000;
        for i in 0..n {
            let mut r = SampleRng::new([i % 512, i / 512], 7, i % 32, 1, 42);
            let x = r.next_1d() as f64;
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / n as f64;
        let var = sum2 / n as f64 - mean * mean;
        assert!((mean - 0.5).abs() < 0.005, "mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 0.002, "variance {var}");
    }
}
