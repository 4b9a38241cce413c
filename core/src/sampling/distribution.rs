//! Piecewise-constant 1D and 2D distributions over tabulated cumulative tables (light selection, the
//! environment map). Tables are built on the host; sampling and pdf lookups run here on both backends.
//!
//! A table for `n` bins has `n + 1` non-decreasing entries from 0 to 1; bin `i` has probability
//! `cdf[i + 1] - cdf[i]`.
use glam::Vec2;

/// The result of sampling a tabulated 1D distribution.
#[derive(Clone, Copy, Debug)]
pub struct CdfSample {
    /// The chosen bin.
    pub index: u32,
    /// Probability of that bin.
    pub pmf: f32,
    /// The input `u` rescaled to [0, 1) within the chosen bin, so it can be reused.
    pub u_remapped: f32,
}

/// Samples bin `i` of the table `cdf[offset .. offset + count + 1]` with `cdf[i] <= u < cdf[i + 1]`
/// (binary search; bins of zero probability are never returned for `u` in [0, 1)).
#[must_use]
pub fn sample_cdf(cdf: &[f32], offset: u32, count: u32, u: f32) -> CdfSample {
    // Find the last i in [0, count) with cdf[i] <= u.
    let mut lo = 0u32;
    let mut hi = count; // invariant: answer in [lo, hi)
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if cdf[(offset + mid) as usize] <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    // Skip zero-width bins that share the same cdf value as their successor (u == cdf[lo + 1]).
    let mut index = lo;
    while index + 1 < count && cdf[(offset + index + 1) as usize] <= u {
        index += 1;
    }
    let c0 = cdf[(offset + index) as usize];
    let c1 = cdf[(offset + index + 1) as usize];
    let pmf = c1 - c0;
    let u_remapped = if pmf > 0.0 {
        ((u - c0) / pmf).clamp(0.0, 0.999_999_94)
    } else {
        0.0
    };
    CdfSample {
        index,
        pmf,
        u_remapped,
    }
}

/// Probability of bin `index` of the table at `offset`.
#[inline]
#[must_use]
pub fn cdf_pmf(cdf: &[f32], offset: u32, index: u32) -> f32 {
    cdf[(offset + index + 1) as usize] - cdf[(offset + index) as usize]
}

/// A sample of a 2D piecewise-constant distribution on the unit square.
#[derive(Clone, Copy, Debug)]
pub struct Distribution2dSample {
    /// Continuous position in [0, 1)².
    pub uv: Vec2,
    /// Density with respect to area on the unit square.
    pub pdf: f32,
}

/// Samples a `width` × `height` 2D distribution stored as a marginal table over rows (`height + 1` entries)
/// and one conditional table per row (`width + 1` entries each, row after row).
#[must_use]
pub fn sample_2d(
    marginal: &[f32],
    conditional: &[f32],
    width: u32,
    height: u32,
    u: Vec2,
) -> Distribution2dSample {
    let row = sample_cdf(marginal, 0, height, u.y);
    let col = sample_cdf(conditional, row.index * (width + 1), width, u.x);
    let uv = Vec2::new(
        (col.index as f32 + col.u_remapped) / width as f32,
        (row.index as f32 + row.u_remapped) / height as f32,
    );
    let pdf = row.pmf * col.pmf * (width * height) as f32;
    Distribution2dSample { uv, pdf }
}

/// Density of [`sample_2d`] at `uv` (area measure on the unit square).
#[must_use]
pub fn pdf_2d(marginal: &[f32], conditional: &[f32], width: u32, height: u32, uv: Vec2) -> f32 {
    let x = ((uv.x * width as f32) as u32).min(width - 1);
    let y = ((uv.y * height as f32) as u32).min(height - 1);
    cdf_pmf(marginal, 0, y) * cdf_pmf(conditional, y * (width + 1), x) * (width * height) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_follows_the_table_and_skips_empty_bins() {
        let cdf = [0.0, 0.25, 0.25, 1.0];
        let s = sample_cdf(&cdf, 0, 3, 0.1);
        assert_eq!(s.index, 0);
        assert!((s.pmf - 0.25).abs() < 1e-7 && (s.u_remapped - 0.4).abs() < 1e-6);
        let s = sample_cdf(&cdf, 0, 3, 0.25);
        assert_eq!(s.index, 2, "a zero-probability bin is never chosen");
        let s = sample_cdf(&cdf, 0, 3, 0.999_999);
        assert_eq!(s.index, 2);
        assert_eq!(sample_cdf(&[0.0, 1.0], 0, 1, 0.7).index, 0);
    }

    #[test]
    fn pdf_2d_matches_sample_2d() {
        // 2 x 2 with weights 1 2 / 3 4.
        let marginal = [0.0, 0.3, 1.0];
        let conditional = [0.0, 1.0 / 3.0, 1.0, 0.0, 3.0 / 7.0, 1.0];
        for &(ux, uy) in &[(0.1f32, 0.1f32), (0.9, 0.1), (0.2, 0.8), (0.7, 0.95)] {
            let s = sample_2d(&marginal, &conditional, 2, 2, Vec2::new(ux, uy));
            let p = pdf_2d(&marginal, &conditional, 2, 2, s.uv);
            assert!((s.pdf - p).abs() < 1e-5, "{} vs {}", s.pdf, p);
        }
        // The density of cell (1, 1) is 0.4 / 0.25 = 1.6.
        assert!((pdf_2d(&marginal, &conditional, 2, 2, Vec2::new(0.75, 0.75)) - 1.6).abs() < 1e-5);
    }
}
