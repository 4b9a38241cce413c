//! Stiff scenes: `cornell_stiff` (a 0.047 × 0.038 light of radiance 1700, a mirror box and a
//! near-specular metal box) and the Veach MIS plates, rendered with MIS, light sampling alone and BSDF
//! sampling alone; and the precision of accumulating 4096 samples per pixel in f32.
//!
//! Figures are printed (`-- --nocapture`). `FOVEA_HEAVY=1` renders a reference of 32768 spp and 16 seeds per strategy.
use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::Instant;

use fovea_core::camera::Camera;
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::foveation::OwnedBlock;
use fovea_core::glam::{DVec3, Vec3};
use fovea_core::integrator::path::{
    IntegratorSettings, INTEGRATOR_FLAG_NO_FINAL_GUARD, STRATEGY_BSDF_ONLY, STRATEGY_LIGHT_ONLY,
    STRATEGY_MIS,
};
use fovea_core::integrator::{render_block_sample, FrameParams};
use fovea_scene::environment::Environment;
use fovea_scene::load_scene;
use fovea_scene::mesh::LoadOptions;
use fovea_scene::pack::PackedScene;
use fovea_tests::stability::{pack, pick, quantile, rel_mse};
use rayon::prelude::*;

/// One rendered image: per-pixel means (f64 accumulation), every sample's luminance, and what the hosts'
/// f32 accumulation (`sum += sample`, in sample order from zero, `sum / spp`) gives.
struct Render {
    mean: Vec<[f32; 4]>,
    mean_f32: Vec<[f32; 4]>,
    sample_luminance: Vec<f32>,
    non_finite: usize,
}

/// One image row: f64 means, f32 means, sample luminances, non-finite samples.
type RenderRow = (Vec<[f32; 4]>, Vec<[f32; 4]>, Vec<f32>, usize);

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Renders `spp` samples of every pixel (uniform 1-pixel blocks, exactly as the hosts do) with the
/// final guard off.
fn render(scene: &PackedScene, frame: &FrameParams, spp: u32, keep_samples: bool) -> Render {
    let view = scene.view();
    let (w, h) = (frame.width, frame.height);
    let rows: Vec<RenderRow> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut mean = Vec::with_capacity(w as usize);
            let mut mean32 = Vec::with_capacity(w as usize);
            let mut samples = Vec::new();
            let mut bad = 0;
            for x in 0..w {
                let block = OwnedBlock {
                    region: 0,
                    size: 1,
                    origin: [x, y],
                };
                let mut sum = DVec3::ZERO;
                let mut sum32 = Vec3::ZERO;
                for s in 0..spp {
                    let c = render_block_sample(&view, frame, &block, s);
                    if !c.is_finite() {
                        bad += 1;
                        continue;
                    }
                    sum += c.as_dvec3();
                    sum32 += c;
                    if keep_samples {
                        samples.push(luminance(c));
                    }
                }
                let m = (sum / f64::from(spp)).as_vec3();
                let m32 = sum32 / spp as f32;
                mean.push([m.x, m.y, m.z, 1.0]);
                mean32.push([m32.x, m32.y, m32.z, 1.0]);
            }
            (mean, mean32, samples, bad)
        })
        .collect();
    let mut r = Render {
        mean: Vec::new(),
        mean_f32: Vec::new(),
        sample_luminance: Vec::new(),
        non_finite: 0,
    };
    for (m, m32, s, bad) in rows {
        r.mean.extend(m);
        r.mean_f32.extend(m32);
        r.sample_luminance.extend(s);
        r.non_finite += bad;
    }
    r
}

struct Stiff {
    name: &'static str,
    scene: PackedScene,
    camera: Camera,
    /// The `max_bounces` it is rendered at.
    depths: &'static [u32],
}

/// A scene the repository bundles (`assets/`).
fn bundled(rel: &str) -> PathBuf {
    fovea_tests::bundled_scenes().join(rel)
}

const W: u32 = 48;
const H: u32 = 36;

fn size() -> (u32, u32) {
    (W, H)
}

fn stiff_scenes() -> Vec<Stiff> {
    let (w, h) = size();
    let aspect = w as f32 / h as f32;
    let mut out = Vec::new();
    {
        let p = bundled("cornell_stiff/cornell_stiff.gltf");
        let loaded = load_scene(&p, &LoadOptions::default()).expect("cornell_stiff");
        let scene = pack(loaded, &Environment::None);
        // From above the glossy short box, where its top mirrors the light: the highlight that a
        // tiny light on a near-specular surface (alpha 1e-3) makes, which light sampling alone renders
        // with high variance.
        out.push(Stiff {
            name: "cornell_stiff (highlight view)",
            scene: scene.clone(),
            camera: Camera::look_at(
                Vec3::new(0.56, 1.57, 0.6),
                Vec3::new(0.2, 0.45, 0.2),
                Vec3::Y,
                30f32.to_radians(),
                aspect,
            ),
            // Direct light only: at 3 bounces this view adds nothing the front view does not test.
            depths: &[1],
        });
        out.push(Stiff {
            name: "cornell_stiff",
            scene,
            camera: fovea_tests::cornell_camera(w, h),
            depths: &[1, 3],
        });
    }
    {
        let p = bundled("veach_mis_pema99/VeachMIS.glb");
        let mut loaded = load_scene(&p, &LoadOptions::default()).expect("VeachMIS");
        equal_power_spheres(&mut loaded);
        // The plates' lit side: from +x +z (the file has no camera; from -z the plates show their
        // unlit backs).
        out.push(Stiff {
            name: "veach_mis_pema99 (equal power)",
            camera: Camera::look_at(
                Vec3::new(18.0, 0.0, 8.4),
                Vec3::new(5.0, 0.0, 3.0),
                Vec3::Y,
                50f32.to_radians(),
                aspect,
            ),
            scene: pack(loaded, &Environment::None),
            depths: &[1, 3],
        });
    }
    out
}

/// Gives each emissive sphere of the Veach scene its own material with radiance ∝ 1 / r² (radius 1:
/// radiance 1, radius 0.05: 400), as in Veach's scene, where the lights have equal power (the file gives
/// all three the same radiance). Spheres are the connected components of the emissive triangles.
fn equal_power_spheres(scene: &mut fovea_scene::mesh::LoadedScene) {
    let emissive: Vec<usize> = (0..scene.triangles.len())
        .filter(|&t| scene.materials[scene.triangle_materials[t] as usize].is_emissive())
        .collect();
    let mut parent: Vec<usize> = (0..scene.positions.len()).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for &t in &emissive {
        let [a, b, c] = scene.triangles[t].map(|v| v as usize);
        for (x, y) in [(a, b), (b, c)] {
            let (rx, ry) = (find(&mut parent, x), find(&mut parent, y));
            parent[rx] = ry;
        }
    }
    let mut components: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for &t in &emissive {
        let root = find(&mut parent, scene.triangles[t][0] as usize);
        components.entry(root).or_default().push(t);
    }
    assert_eq!(components.len(), 3, "three emissive spheres");
    for tris in components.values() {
        let verts: Vec<Vec3> = tris
            .iter()
            .flat_map(|&t| scene.triangles[t])
            .map(|v| Vec3::from(scene.positions[v as usize]))
            .collect();
        let centre = verts.iter().copied().sum::<Vec3>() / verts.len() as f32;
        let r = verts.iter().map(|v| (*v - centre).length()).sum::<f32>() / verts.len() as f32;
        let mut m = scene.materials[scene.triangle_materials[tris[0]] as usize];
        let radiance = 1.0 / (r * r);
        m.emission = [radiance, radiance, radiance, 0.0];
        scene.materials.push(m);
        scene.material_names.push(format!("emitter r {r:.2}"));
        let index = (scene.materials.len() - 1) as u32;
        for &t in tris {
            scene.triangle_materials[t] = index;
        }
    }
}

/// Samples per pixel of the references: 4096 in CI, 32768 with `FOVEA_HEAVY=1`.
fn reference_spp() -> u32 {
    pick(4096, 32768)
}

/// The MIS reference of scene `name` at `max_bounces` (seed 1000), rendered once per test binary and
/// shared by the tests (the first caller renders all of them); with the seconds it took.
fn reference(name: &str, max_bounces: u32) -> (&'static Render, f64) {
    static REFERENCES: OnceLock<Vec<(&'static str, u32, Render, f64)>> = OnceLock::new();
    let all = REFERENCES.get_or_init(|| {
        let mut out = Vec::new();
        for stiff in stiff_scenes() {
            for &depth in stiff.depths {
                let start = Instant::now();
                let r = render(
                    &stiff.scene,
                    &frame_depth(stiff.camera, STRATEGY_MIS, 1000, depth),
                    reference_spp(),
                    false,
                );
                assert_eq!(r.non_finite, 0, "{}: reference", stiff.name);
                out.push((stiff.name, depth, r, start.elapsed().as_secs_f64()));
            }
        }
        out
    });
    let (_, _, r, s) = all
        .iter()
        .find(|(n, d, ..)| *n == name && *d == max_bounces)
        .expect("a reference of every scene and depth");
    (r, *s)
}

fn frame_depth(camera: Camera, strategy: u32, seed: u32, max_bounces: u32) -> FrameParams {
    let (w, h) = size();
    let mut f = fovea_tests::frame_params(camera, FoveationParams::uniform(1), w, h, seed);
    f.integrator = IntegratorSettings {
        max_bounces,
        strategy,
        flags: INTEGRATOR_FLAG_NO_FINAL_GUARD,
        ..Default::default()
    };
    f
}

const STRATEGIES: [(u32, &str); 3] = [
    (STRATEGY_MIS, "MIS"),
    (STRATEGY_LIGHT_ONLY, "light only"),
    (STRATEGY_BSDF_ONLY, "BSDF only"),
];

/// `eps` of the relative MSE, relative to the reference's mean luminance squared: pixels darker than
/// 10 % of the image mean are not compared relatively any more (black pixels).
const REL_MSE_EPS: f64 = 1e-2;

/// MIS against light sampling alone and BSDF sampling alone, against a converged MIS reference, at
/// `max_bounces` 1 (direct light) and 3 (the paper's depth).
///
/// The reference is MIS at `ref_spp` (4096 in CI, 32768 heavy) with its own seed; each strategy
/// renders `seeds` independent images at 64 spp (16 seeds in CI, 64 heavy). relMSE is
/// `mean((x - ref)² / (ref² + 0.01 mean(ref)²))` over pixel luminance. Significance: the per-seed relMSE
/// of MIS must be smaller than the other strategy's by a one-sided Mann-Whitney U test at 1 % (z below
/// -2.326); a rank test, because relMSE is heavy-tailed (one caustic firefly of luminance 1e3 adds about
/// 14 to an image's relMSE), so that per-seed extremes or means would be decided by a few fireflies. The
/// reference's own error, about 64 / 4096 of MIS's, is negligible. No NaN or infinite sample anywhere (with the final
/// guard off). Firefly statistics: the 99.99th percentile and the maximum of sample luminance per
/// strategy (the maximum is usually the light seen directly: 1248.5 for cornell_stiff).
///
/// **Asserted:** MIS below BSDF sampling alone everywhere, and below light sampling alone on the Veach
/// plates (lights of equal power, radiance 1 to 400) and on `cornell_stiff` seen from above the glossy
/// short box (alpha 1e-3), whose top mirrors the tiny light: there BSDF sampling is the better strategy
/// for the highlight, light sampling for the rest, and MIS wins (measured z = -3.69 against light only,
/// -4.82 against BSDF only; relMSE mean 0.0015 vs 0.0046 and 24.4). **Not asserted:** MIS against
/// light sampling alone on `cornell_stiff`'s front view, where it does not hold at any affordable sample
/// count, for two measured reasons:
/// - at `max_bounces` 1 the two estimates coincide (relMSE equal to 4 digits): the light is so small that
///   the power heuristic gives a BSDF-sampled hit of it a weight of about 1e-7 on every surface the
///   camera sees (the mirror does not show the light from this view);
/// - at `max_bounces` 3 the caustic paths light → mirror (alpha 2e-4) → diffuse are found by BSDF
///   sampling (probability about 1e-4 per sample, luminance about 1e3 each), so MIS and BSDF sampling
///   pay for them with fireflies (MIS relMSE from 0.03 to several hundred across 16 seeds). Light
///   sampling alone finds them only when a light sample from the mirror lands in its lobe: far rarer,
///   but then with a luminance of 2e4 .. 3e4. Measured over 16 seeds: one light-only image caught such a
///   sample (relMSE about 6e4), so light-only's *mean* relMSE (about 4000) is far above MIS's (about
///   90), while its typical image has none and only the bias of the missing caustic (relMSE 0.03),
///   below MIS's median; the rank test leans to light sampling (z ≈ +2.5). Neither ordering is robust at
///   affordable sample counts (MIS would need on the order of 1e5 spp before its variance fell below
///   that bias), so it is printed, not asserted.
#[test]
fn mis_beats_either_strategy_on_stiff_scenes() {
    let ref_spp = reference_spp();
    let spp = 64u32;
    let seeds = pick(16u32, 64);
    for (stiff, depth) in stiff_scenes()
        .iter()
        .flat_map(|s| s.depths.iter().map(move |&d| (s, d)))
    {
        let start = Instant::now();
        let (reference, ref_time) = reference(stiff.name, depth);
        let ref_mean = reference
            .mean
            .iter()
            .map(|p| f64::from(luminance(Vec3::new(p[0], p[1], p[2]))))
            .sum::<f64>()
            / reference.mean.len() as f64;
        let eps = REL_MSE_EPS * ref_mean * ref_mean;
        let mut results = Vec::new();
        for (strategy, label) in STRATEGIES {
            let mut errors = Vec::new();
            let mut samples = Vec::new();
            let mut non_finite = 0;
            for seed in 0..seeds {
                let r = render(
                    &stiff.scene,
                    &frame_depth(stiff.camera, strategy, seed, depth),
                    spp,
                    true,
                );
                non_finite += r.non_finite;
                errors.push(rel_mse(&r.mean, &reference.mean, eps));
                samples.extend(r.sample_luminance);
            }
            let n = samples.len();
            let p9999 = quantile(&mut samples, 0.9999);
            let max = samples[n - 1];
            let mean_lum = samples.iter().map(|&x| f64::from(x)).sum::<f64>() / n as f64;
            results.push((label, errors, p9999, max, mean_lum, non_finite, n));
        }
        eprintln!(
            "\n{} max_bounces {depth}, {}x{}: reference MIS {ref_spp} spp ({ref_time:.1} s); {seeds} seeds x {spp} spp per \
             strategy; relMSE eps {REL_MSE_EPS} x mean² (mean {ref_mean:.4})",
            stiff.name,
            size().0,
            size().1
        );
        eprintln!(
            "| {:<10} | {:>10} | {:>10} | {:>10} | {:>12} | {:>12} | {:>10} | {:>10} |",
            "strategy",
            "relMSE min",
            "relMSE mean",
            "relMSE max",
            "p99.99 lum",
            "max lum",
            "mean lum",
            "non-finite"
        );
        for (label, errors, p9999, max, mean_lum, non_finite, _) in &results {
            let (lo, hi) = (
                errors.iter().cloned().fold(f64::MAX, f64::min),
                errors.iter().cloned().fold(0.0, f64::max),
            );
            let mean = errors.iter().sum::<f64>() / errors.len() as f64;
            eprintln!(
                "| {label:<10} | {lo:>10.4} | {mean:>11.4} | {hi:>10.4} | {p9999:>12.3} | {max:>12.3} | \
                 {mean_lum:>10.4} | {non_finite:>10} |"
            );
        }
        eprintln!("{:.1} s", start.elapsed().as_secs_f64());
        for (label, _, _, _, _, non_finite, n) in &results {
            assert_eq!(
                *non_finite, 0,
                "{} {label}: {non_finite} of {n}",
                stiff.name
            );
        }
        for (label, errors, ..) in &results[1..] {
            let z = mann_whitney_z(&results[0].1, errors);
            // cornell_stiff's front view: light sampling alone is not compared (see the test's
            // documentation).
            if stiff.name == "cornell_stiff" && *label == "light only" {
                eprintln!(
                    "{} max_bounces {depth}: MIS vs {label}: z = {z:.2} (not asserted)",
                    stiff.name
                );
                continue;
            }
            eprintln!(
                "{} max_bounces {depth}: MIS vs {label}: z = {z:.2}",
                stiff.name
            );
            assert!(
                z < Z_ONE_PERCENT,
                "{} max_bounces {depth}: MIS relMSE not significantly below {label}'s (z = {z})",
                stiff.name
            );
        }
    }
}

/// One-sided 1 % critical value of the standard normal distribution.
const Z_ONE_PERCENT: f64 = -2.326;

/// The Mann-Whitney U statistic of `a` against `b` (pairs with `a > b`, ties counting half) as a z-score
/// under the null hypothesis that neither tends to be smaller (normal approximation, good for
/// n, m >= 8; Mann and Whitney 1947). Very negative: `a` is stochastically smaller. Rank-based, so a
/// firefly-ridden image counts once, not by its magnitude.
fn mann_whitney_z(a: &[f64], b: &[f64]) -> f64 {
    let mut u = 0.0;
    for x in a {
        for y in b {
            if x > y {
                u += 1.0;
            } else if x == y {
                u += 0.5;
            }
        }
    }
    let (n, m) = (a.len() as f64, b.len() as f64);
    (u - n * m / 2.0) / (n * m * (n + m + 1.0) / 12.0).sqrt()
}

/// Accumulation precision: the hosts sum a pixel's samples in f32 (`sum += sample` in order, then
/// `sum / spp`; CPU `render_frame` and the kernel's `reduce_blocks`). At 4096 spp (32768 heavy; the MIS
/// references, `max_bounces` 3) of `cornell_stiff` (fireflies up to 1e3 next to pixels of 0.1, the worst
/// case for absorption) and the Veach plates, the f32 mean is compared with an f64 accumulation of the
/// same samples.
///
/// The bound of a recursive f32 sum of n non-negative terms is (n - 1) u ≈ 2.4e-4 relative at n = 4096
/// (u = 2^-24), and typically about √n u ≈ 4e-6. One 8-bit display step is 1/255 ≈ 4e-3 of the range,
/// and fovea's largest per-pixel count is the fovea's spp (32 in the paper): compensated summation is
/// needed only if the measured error approaches 1e-3. Asserted: max relative error < 1e-3.
#[test]
fn f32_accumulation_of_4096_samples_is_precise_enough() {
    let spp = reference_spp();
    for stiff in stiff_scenes().iter().filter(|s| s.depths.contains(&3)) {
        let (r, seconds) = reference(stiff.name, 3);
        let mut max_rel = 0.0f64;
        let mut sum_rel = 0.0f64;
        let mut counted = 0usize;
        for (a, b) in r.mean_f32.iter().zip(&r.mean) {
            for c in 0..3 {
                let (x, y) = (f64::from(a[c]), f64::from(b[c]));
                if y > 1e-6 {
                    let rel = (x - y).abs() / y;
                    max_rel = max_rel.max(rel);
                    sum_rel += rel;
                    counted += 1;
                }
            }
        }
        eprintln!(
            "{}: f32 vs f64 accumulation of {spp} spp over {} channels: max relative difference \
             {max_rel:.3e}, mean {:.3e} ({:.1} s)",
            stiff.name,
            counted,
            sum_rel / counted.max(1) as f64,
            seconds
        );
        assert!(counted > 0);
        assert!(max_rel < 1e-3, "{}: {max_rel}", stiff.name);
    }
}
