//! Chi-square goodness-of-fit tests for direction samplers (test builds only), after pbrt-v3's
//! `chi2.cpp` and Mitsuba 3's `ChiSquareTest`.
//!
//! A [`Grid`] partitions the sphere into cells bounded by circles of constant angle θ' from an axis
//! (the rows, i.e. constant cos θ') and meridians of constant φ' (the columns). Samples are binned; each
//! cell's expected count is `N ∫_cell pdf dω`, integrated by nested adaptive Gauss-Legendre quadrature in
//! (θ', φ') with dω = sin θ' dθ' dφ'. Cells are pooled, smallest first, until each has an expected count of
//! at least 5; the statistic Σ (O - E)² / E is compared with a χ² distribution of (cells - 1) degrees of
//! freedom (p-value from `statrs`, not a hand-written special function). A test passes when its p-value
//! is at least the Šidák-corrected level [`sidak_threshold`] for the whole family of
//! [`FAMILY_SIZE`] tests at overall significance [`SIGNIFICANCE`].
//!
//! Hard failures, independent of the statistic: a sample in a cell whose pdf integral is exactly zero (or
//! outside the grid, or on the wrong side of a clip plane), and a pdf integral above 1 + [`INTEGRAL_EPS`].
//!
//! Quadrature: pdfs are smooth inside a cell except where they drop to zero on a great circle (the
//! horizon of a BSDF, the edges of a triangle light). Those boundaries are declared as clip planes and
//! removed analytically from each φ' interval, so the integrands the quadrature sees are smooth. Each 1D
//! integral is the 7-point Gauss-Legendre rule, bisected until the two halves agree with the whole to a
//! relative 2e-5 (inner, φ') and 5e-5 (outer, θ'), just above the resolution of f32 directions for the
//! steepest lobes tested, or until the error of the expected count E is below 5 % of its Poisson spread
//! √E (so it adds at most 0.0025 to χ² per cell), whichever is looser. The second bound matters where
//! the pdf itself is noisy at fine scales (half vectors of nearly opposite grazing directions lose
//! precision in f32), where bisection would otherwise chase the noise. Bisection stops at depth 12; how
//! often it did is reported.
//!
//! Narrow lobes get rows spaced geometrically in θ' around the lobe's axis (a (cos θ', φ') grid with
//! non-uniform row spacing), so that a lobe of width α spans many rows. A grid whose first edge is above
//! zero excludes the cap θ' < edges[0]: the test is then conditional on the sample lying outside the cap
//! (expected counts scaled to the observed total outside; still a valid multinomial test), used where a
//! near-delta lobe makes the cap's content untestable.
extern crate std;

use std::format;
use std::println;
use std::string::String;
use std::vec;
use std::vec::Vec;

use glam::Vec3;
use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::SplitMix64;

/// Overall significance of the family of chi-square tests.
pub(crate) const SIGNIFICANCE: f64 = 0.01;

/// Number of chi-square tests in the family, for the Šidák correction, by part; each test asserts its
/// share with [`family_share`]. Cosine hemisphere 1; GGX VNDF 20 (alpha 0.01, 0.1, 0.5, 1 × 5 incident
/// angles; alpha 1e-4 is a near-delta, not chi-square tested); Disney lobes 18 (specular 4 roughnesses ×
/// 3 angles, clearcoat 2 glosses × 3 angles); Disney full BSDF 112 (the 96 corners less the 8 pure
/// near-delta mirrors, and the 24 corners with a Lambertian diffuse lobe); lights 4 (2 triangle
/// configurations, 2 environment maps); rough dielectric 12 (4 roughness and index pairs × 3 incident
/// angles).
pub(crate) const FAMILY_PARTS: [(&str, u32); 6] = [
    ("cosine hemisphere", 1),
    ("ggx vndf", 20),
    ("disney lobes", 18),
    ("disney full bsdf", 112),
    ("lights", 4),
    ("rough dielectric", 12),
];

/// Total number of chi-square tests in the family.
pub(crate) const FAMILY_SIZE: u32 = {
    let mut n = 0;
    let mut i = 0;
    while i < FAMILY_PARTS.len() {
        n += FAMILY_PARTS[i].1;
        i += 1;
    }
    n
};

/// Tolerance on pdf integrals above one (quadrature error is far smaller).
pub(crate) const INTEGRAL_EPS: f64 = 1e-3;

/// Per-test significance level with Šidák's correction: 1 - (1 - α)^(1/m).
pub(crate) fn sidak_threshold() -> f64 {
    1.0 - (1.0 - SIGNIFICANCE).powf(1.0 / FAMILY_SIZE as f64)
}

/// The number of tests `part` of [`FAMILY_PARTS`] declares.
pub(crate) fn family_share(part: &str) -> u32 {
    let mut i = 0;
    while i < FAMILY_PARTS.len() {
        if FAMILY_PARTS[i].0 == part {
            return FAMILY_PARTS[i].1;
        }
        i += 1;
    }
    panic!("unknown family part {part}");
}

/// Whether `FOVEA_HEAVY=1` asks for the heavy (nightly / manual) sample counts.
pub(crate) fn heavy() -> bool {
    std::env::var("FOVEA_HEAVY").is_ok_and(|v| v == "1")
}

/// `ci` samples normally, `heavy` under `FOVEA_HEAVY=1`.
pub(crate) fn sample_count(ci: usize, heavy_count: usize) -> usize {
    if heavy() {
        heavy_count
    } else {
        ci
    }
}

/// Row edges uniform in cos θ' from `t0` to `t1` (angles in radians), `n` rows (`n + 1` edges).
pub(crate) fn uniform_cos(t0: f64, t1: f64, n: usize) -> Vec<f64> {
    let (c0, c1) = (t0.cos(), t1.cos());
    (0..=n)
        .map(|i| {
            (c0 + (c1 - c0) * i as f64 / n as f64)
                .clamp(-1.0, 1.0)
                .acos()
        })
        .collect()
}

/// Row edges geometric in θ' from `t0 > 0` to `t1`, `n` rows, preceded by the edge 0 when `with_pole`
/// (the cap [0, t0) then is the first row; otherwise it is excluded).
pub(crate) fn geometric(t0: f64, t1: f64, n: usize, with_pole: bool) -> Vec<f64> {
    let mut e = Vec::new();
    if with_pole {
        e.push(0.0);
    }
    let r = (t1 / t0).ln() / n as f64;
    for i in 0..=n {
        e.push(t0 * (r * i as f64).exp());
    }
    *e.last_mut().unwrap() = t1;
    e
}

/// `a` followed by `b` (whose first edge must equal `a`'s last).
pub(crate) fn join(mut a: Vec<f64>, b: Vec<f64>) -> Vec<f64> {
    assert!((a.last().unwrap() - b[0]).abs() < 1e-12);
    a.extend_from_slice(&b[1..]);
    a
}

type V3 = [f64; 3];

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(v: Vec3) -> V3 {
    let v = [v.x as f64, v.y as f64, v.z as f64];
    let l = dot(v, v).sqrt();
    [v[0] / l, v[1] / l, v[2] / l]
}

/// A (cos θ', φ') partition of the sphere around an axis.
pub(crate) struct Grid {
    x: V3,
    y: V3,
    z: V3,
    /// Row edges in θ', increasing, last at most π. A first edge above 0 excludes the cap below it.
    edges: Vec<f64>,
    n_phi: usize,
    /// Unit normals `n` of half-spaces `n · w >= 0` outside which the pdf is zero.
    clip: Vec<V3>,
}

impl Grid {
    /// A grid around `axis` with row edges `edges` (θ') and `n_phi` columns.
    pub(crate) fn new(axis: Vec3, edges: Vec<f64>, n_phi: usize) -> Self {
        assert!(edges.windows(2).all(|w| w[1] > w[0]) && *edges.last().unwrap() <= PI + 1e-12);
        let z = unit(axis);
        // Duff et al. 2017 orthonormal basis, in f64.
        let sign = if z[2] >= 0.0 { 1.0 } else { -1.0 };
        let a = -1.0 / (sign + z[2]);
        let b = z[0] * z[1] * a;
        let x = [1.0 + sign * z[0] * z[0] * a, sign * b, -sign * z[0]];
        let y = [b, sign + z[1] * z[1] * a, -z[1]];
        Self {
            x,
            y,
            z,
            edges,
            n_phi,
            clip: Vec::new(),
        }
    }

    /// The whole +z hemisphere, `nt` rows uniform in cos θ and `np` columns.
    pub(crate) fn hemisphere(nt: usize, np: usize) -> Self {
        Self::new(Vec3::Z, uniform_cos(0.0, PI / 2.0, nt), np)
    }

    /// Declares that the pdf is zero where `n · w < 0`.
    pub(crate) fn clip(mut self, n: Vec3) -> Self {
        self.clip.push(unit(n));
        self
    }

    fn rows(&self) -> usize {
        self.edges.len() - 1
    }

    fn direction(&self, theta: f64, phi: f64) -> Vec3 {
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        let l = [st * cp, st * sp, ct];
        let w = |i: usize| self.x[i] * l[0] + self.y[i] * l[1] + self.z[i] * l[2];
        Vec3::new(w(0) as f32, w(1) as f32, w(2) as f32)
    }

    /// The φ' sub-intervals of [pa, pb] at polar angle θ' that lie inside every clip half-space.
    fn clipped(&self, theta: f64, pa: f64, pb: f64, out: &mut Vec<(f64, f64)>) {
        out.clear();
        out.push((pa, pb));
        let (st, ct) = theta.sin_cos();
        for n in &self.clip {
            // n · w = c0 + R cos(φ - ψ).
            let c0 = ct * dot(*n, self.z);
            let (c1, c2) = (st * dot(*n, self.x), st * dot(*n, self.y));
            let r = c1.hypot(c2);
            if c0 >= r {
                continue;
            }
            if c0 <= -r {
                out.clear();
                return;
            }
            let psi = c2.atan2(c1);
            let beta = (-c0 / r).acos();
            let mut next = Vec::new();
            for &(a, b) in out.iter() {
                for k in -1..=1 {
                    let lo = (psi - beta + 2.0 * PI * k as f64).max(a);
                    let hi = (psi + beta + 2.0 * PI * k as f64).min(b);
                    if hi > lo {
                        next.push((lo, hi));
                    }
                }
            }
            *out = next;
        }
    }

    /// ∫ over cell (row, col) of `pdf` dω.
    fn cell_integral(
        &self,
        row: usize,
        col: usize,
        pdf: &mut impl FnMut(Vec3) -> f64,
        n: usize,
        depth_hits: &mut usize,
    ) -> f64 {
        let (ta, tb) = (self.edges[row], self.edges[row + 1]);
        let stat = if n > 0 { 1.0 / n as f64 } else { 0.0 };
        let dphi = 2.0 * PI / self.n_phi as f64;
        let (pa, pb) = (col as f64 * dphi, (col + 1) as f64 * dphi);
        let mut intervals = Vec::new();
        let mut inner_hits = 0;
        let mut outer = |theta: f64| {
            self.clipped(theta, pa, pb, &mut intervals);
            let mut s = 0.0;
            // The inner integral is weighted by about sin θ' (tb - ta) in the cell's integral.
            let inner_stat = stat / (theta.sin() * (tb - ta)).max(1e-300);
            for &(a, b) in &intervals {
                let mut f = |phi: f64| pdf(self.direction(theta, phi));
                s += integrate(
                    &mut f,
                    a,
                    b,
                    INNER_REL_TOL,
                    1e-14,
                    inner_stat,
                    12,
                    &mut inner_hits,
                );
            }
            s * theta.sin()
        };
        // Split θ' where the clipped φ' set of this column changes shape (a clip circle becomes tangent
        // to a row circle or crosses a column edge), so each piece's integrand is smooth and no sliver
        // of the cell falls between quadrature nodes.
        let mut cuts = vec![ta, tb];
        for n in &self.clip {
            let (nx, ny, nz) = (dot(*n, self.x), dot(*n, self.y), dot(*n, self.z));
            let gamma = nz.clamp(-1.0, 1.0).acos();
            cuts.push(0.5 * PI - gamma);
            cuts.push(0.5 * PI + gamma);
            for phi in [pa, pb] {
                // n · w(θ', φ) = cos θ' nz + sin θ' (nx cos φ + ny sin φ) = 0.
                let mut t = (-nz).atan2(nx * phi.cos() + ny * phi.sin());
                if t < 0.0 {
                    t += PI;
                }
                cuts.push(t);
            }
        }
        cuts.retain(|&t| t >= ta && t <= tb);
        cuts.sort_by(f64::total_cmp);
        let mut v = 0.0;
        for k in 1..cuts.len() {
            if cuts[k] > cuts[k - 1] {
                v += integrate(
                    &mut outer,
                    cuts[k - 1],
                    cuts[k],
                    OUTER_REL_TOL,
                    1e-13,
                    stat,
                    12,
                    depth_hits,
                );
            }
        }
        *depth_hits += inner_hits;
        v
    }
}

const PI: f64 = core::f64::consts::PI;

/// Relative tolerances of the inner (φ') and outer (θ') quadratures. The pdfs see f32 directions, so at
/// fine scales a steep lobe is a staircase (steps of about 6e-8 rad, i.e. relative jumps of up to ~1e-5
/// for alpha 0.01); asking for more than that only makes bisection run to its depth limit.
const INNER_REL_TOL: f64 = 2e-5;
const OUTER_REL_TOL: f64 = 5e-5;

/// 7-point Gauss-Legendre nodes and weights on [-1, 1].
const GL_X: [f64; 7] = [
    -0.949_107_912_342_758_5,
    -0.741_531_185_599_394_4,
    -0.405_845_151_377_397_2,
    0.0,
    0.405_845_151_377_397_2,
    0.741_531_185_599_394_4,
    0.949_107_912_342_758_5,
];
const GL_W: [f64; 7] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
    0.381_830_050_505_118_9,
    0.279_705_391_489_276_7,
    0.129_484_966_168_869_7,
];

fn gauss_legendre(f: &mut impl FnMut(f64) -> f64, a: f64, b: f64) -> f64 {
    let (m, h) = (0.5 * (a + b), 0.5 * (b - a));
    let mut s = 0.0;
    for i in 0..7 {
        s += GL_W[i] * f(m + h * GL_X[i]);
    }
    s * h
}

/// Adaptive bisection of the 7-point Gauss-Legendre rule to `max(abs, rel |I|, 0.05 √(|I| stat))`: the
/// last term is the statistical tolerance, 5 % of the Poisson spread of the expected count when an
/// error in I changes it by `1 / stat` times as much (`stat` = 0: none).
fn integrate(
    f: &mut impl FnMut(f64) -> f64,
    a: f64,
    b: f64,
    rel: f64,
    abs: f64,
    stat: f64,
    max_depth: u32,
    depth_hits: &mut usize,
) -> f64 {
    let whole = gauss_legendre(f, a, b);
    let tol = abs
        .max(rel * whole.abs())
        .max(0.05 * (whole.abs() * stat).sqrt());
    bisect(f, a, b, whole, tol, max_depth, depth_hits)
}

fn bisect(
    f: &mut impl FnMut(f64) -> f64,
    a: f64,
    b: f64,
    whole: f64,
    tol: f64,
    depth: u32,
    depth_hits: &mut usize,
) -> f64 {
    let m = 0.5 * (a + b);
    let (l, r) = (gauss_legendre(f, a, m), gauss_legendre(f, m, b));
    if (l + r - whole).abs() <= tol {
        return l + r;
    }
    if depth == 0 {
        *depth_hits += 1;
        return l + r;
    }
    // tol / √2 per half (rather than tol / 2): the errors of the halves add in quadrature when they are
    // not systematic, and it keeps bisection from chasing the f32 staircase.
    let t = tol * core::f64::consts::FRAC_1_SQRT_2;
    bisect(f, a, m, l, t, depth - 1, depth_hits) + bisect(f, m, b, r, t, depth - 1, depth_hits)
}

/// The outcome of one chi-square test.
pub(crate) struct Chi2Outcome {
    pub name: String,
    pub samples: usize,
    /// Samples the sampler rejected (`None`).
    pub failed: usize,
    /// Samples in the excluded cap (conditional tests).
    pub excluded: usize,
    /// Samples in zero-pdf cells, outside the grid or behind a clip plane.
    pub in_zero_pdf: usize,
    pub chi2: f64,
    pub dof: usize,
    pub p_value: f64,
    /// ∫ pdf over the grid (without the excluded cap).
    pub integral: f64,
    /// Quadrature intervals that stopped at the depth limit.
    pub depth_hits: usize,
    /// The cell with the largest |O - E| / √E, for diagnosis.
    pub worst_cell: String,
    /// Wall time of sampling and quadrature.
    pub seconds: f64,
}

impl Chi2Outcome {
    /// Prints the outcome (visible with `--nocapture`) and asserts it.
    pub(crate) fn check(&self) {
        let threshold = sidak_threshold();
        println!(
            "chi2 [{}]: p = {:.3e} (Šidák threshold {:.3e}), chi2 = {:.1}, dof = {}, pdf integral = {:.6}, \
             N = {}, failed = {}, excluded cap = {}, zero-pdf = {}, depth-limited quadrature = {}, {:.2} s, worst {}",
            self.name,
            self.p_value,
            threshold,
            self.chi2,
            self.dof,
            self.integral,
            self.samples,
            self.failed,
            self.excluded,
            self.in_zero_pdf,
            self.depth_hits,
            self.seconds,
            self.worst_cell
        );
        assert_eq!(
            self.in_zero_pdf, 0,
            "{}: samples where the pdf is zero",
            self.name
        );
        assert!(
            self.integral <= 1.0 + INTEGRAL_EPS,
            "{}: pdf integral {}",
            self.name,
            self.integral
        );
        assert!(
            self.dof >= 5,
            "{}: only {} degrees of freedom",
            self.name,
            self.dof
        );
        assert!(
            self.p_value >= threshold,
            "{}: p = {:e} < {:e} (chi2 {} dof {}, worst {})",
            self.name,
            self.p_value,
            threshold,
            self.chi2,
            self.dof,
            self.worst_cell
        );
    }
}

/// Runs a chi-square test of `n` samples from `sample` (None = a rejected sample) against `pdf` (solid-
/// angle density of the returned directions) on `grid`. `seed` seeds the generator passed to `sample`.
pub(crate) fn chi2_test(
    name: &str,
    grid: &Grid,
    n: usize,
    seed: u64,
    mut sample: impl FnMut(&mut SplitMix64) -> Option<Vec3>,
    mut pdf: impl FnMut(Vec3) -> f64,
) -> Chi2Outcome {
    let start = std::time::Instant::now();
    let (rows, cols) = (grid.rows(), grid.n_phi);
    let mut counts = vec![0u64; rows * cols];
    let mut rng = SplitMix64(seed);
    let (mut failed, mut excluded, mut bad) = (0, 0, 0);
    let t_max = *grid.edges.last().unwrap();
    for _ in 0..n {
        let Some(w) = sample(&mut rng) else {
            failed += 1;
            continue;
        };
        let w = unit(w);
        if grid.clip.iter().any(|c| dot(*c, w) < -1e-5) {
            bad += 1;
            continue;
        }
        let (lx, ly, lz) = (dot(w, grid.x), dot(w, grid.y), dot(w, grid.z));
        let theta = lx.hypot(ly).atan2(lz);
        if theta < grid.edges[0] {
            excluded += 1;
            continue;
        }
        if theta > t_max + 1e-6 {
            bad += 1;
            continue;
        }
        let row = (grid.edges.partition_point(|&e| e <= theta).max(1) - 1).min(rows - 1);
        let mut phi = ly.atan2(lx);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let col = ((phi / (2.0 * PI) * cols as f64) as usize).min(cols - 1);
        counts[row * cols + col] += 1;
    }

    let mut depth_hits = 0;
    let mut integrals = vec![0.0f64; rows * cols];
    for r in 0..rows {
        for c in 0..cols {
            integrals[r * cols + c] = grid.cell_integral(r, c, &mut pdf, n, &mut depth_hits);
        }
    }
    let integral: f64 = integrals.iter().sum();
    let observed_in_grid: u64 = counts.iter().sum();
    let scale = if grid.edges[0] > 0.0 {
        observed_in_grid as f64 / integral
    } else {
        n as f64
    };

    // Cells: (expected, observed, index); samples in zero-integral cells are hard failures.
    let mut cells = Vec::new();
    for i in 0..rows * cols {
        if integrals[i] <= 0.0 {
            bad += counts[i] as usize;
        } else {
            cells.push((integrals[i] * scale, counts[i] as f64, i));
        }
    }
    cells.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut pooled: Vec<(f64, f64, usize)> = Vec::new();
    let (mut pe, mut po) = (0.0, 0.0);
    for &(e, o, i) in &cells {
        if e < 5.0 {
            pe += e;
            po += o;
            if pe >= 5.0 {
                pooled.push((pe, po, usize::MAX));
                (pe, po) = (0.0, 0.0);
            }
        } else if pe > 0.0 {
            pooled.push((e + pe, o + po, i));
            (pe, po) = (0.0, 0.0);
        } else {
            pooled.push((e, o, i));
        }
    }
    if pe > 0.0 {
        match pooled.last_mut() {
            Some(last) => {
                last.0 += pe;
                last.1 += po;
            }
            None => pooled.push((pe, po, usize::MAX)),
        }
    }
    let mut chi2 = 0.0;
    let mut worst = (0.0, String::new());
    for &(e, o, i) in &pooled {
        let d = o - e;
        chi2 += d * d / e;
        let z = d.abs() / e.sqrt();
        if z > worst.0 {
            let place = if i == usize::MAX {
                String::from("pooled")
            } else {
                let (r, c) = (i / cols, i % cols);
                format!(
                    "row {r} (θ' {:.3e}..{:.3e}) col {c}",
                    grid.edges[r],
                    grid.edges[r + 1]
                )
            };
            worst = (z, format!("{place}: O {o} E {e:.1}"));
        }
    }
    let dof = pooled.len().saturating_sub(1);
    let p_value = if dof == 0 {
        1.0
    } else {
        ChiSquared::new(dof as f64).unwrap().sf(chi2)
    };
    Chi2Outcome {
        name: String::from(name),
        samples: n,
        failed,
        excluded,
        in_zero_pdf: bad,
        chi2,
        dof,
        p_value,
        integral,
        depth_hits,
        worst_cell: worst.1,
        seconds: start.elapsed().as_secs_f64(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The harness itself: exact for a uniform sphere sampler, and it rejects a slightly wrong density.
    #[test]
    fn harness_accepts_truth_and_rejects_a_biased_sampler() {
        let grid = Grid::new(Vec3::new(0.3, 0.4, 0.5), uniform_cos(0.0, PI, 16), 32);
        let uniform = |rng: &mut SplitMix64| {
            let z = 1.0 - 2.0 * rng.uniform();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * core::f32::consts::PI * rng.uniform();
            Some(Vec3::new(r * phi.cos(), r * phi.sin(), z))
        };
        let inv4pi = 1.0 / (4.0 * PI);
        let ok = chi2_test("uniform sphere", &grid, 200_000, 1, uniform, |_| inv4pi);
        assert!((ok.integral - 1.0).abs() < 1e-9, "{}", ok.integral);
        assert!(ok.p_value > 1e-4 && ok.in_zero_pdf == 0, "{}", ok.p_value);
        // A density off by 5% in each hemisphere (same integral) must be rejected.
        let biased = chi2_test("biased", &grid, 200_000, 1, uniform, |w| {
            inv4pi * if w.z > 0.0 { 1.05 } else { 0.95 }
        });
        assert!(biased.p_value < 1e-6, "{}", biased.p_value);
        // A hemisphere clip with samples below it: hard failures.
        let clipped = chi2_test(
            "clipped",
            &Grid::hemisphere(8, 16).clip(Vec3::Z),
            1000,
            2,
            uniform,
            |_| inv4pi,
        );
        assert!(clipped.in_zero_pdf > 400 && (clipped.integral - 0.5).abs() < 1e-9);
        // Clip-plane quadrature: the integral of 1 over a spherical lune cut by two planes.
        let lune = Grid::new(Vec3::new(0.2, -0.1, 1.0), uniform_cos(0.0, PI, 8), 16)
            .clip(Vec3::Z)
            .clip(Vec3::X);
        let area = chi2_test("lune", &lune, 0, 3, |_| None, |_| 1.0).integral;
        assert!((area - PI).abs() < 1e-5, "{area}");
    }
}
