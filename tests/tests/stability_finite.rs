//! Finite everywhere: random and adversarial inputs to every core function return finite values, on the
//! CPU and (through the kernel's `probe` entry point and whole frames) on the Vulkan device.
//!
//! Inputs: cos θ from exactly 0 and 1e-7 up to 1 and below the horizon, roughness exactly 0, non-unit,
//! zero and degenerate normals and directions, zero-area, collinear and needle triangles, coordinates
//! from 1e-6 to 1e6 (1e-30 to 1e30 for the ray offset), emission 1e6, HDR values up to `f32::MAX`, `inf`
//! and NaN (tone mapping only).
//!
//! Counts: 2^20 (1 M) items per probe function in CI, 10 M with `FOVEA_HEAVY=1`, on each backend; the
//! scene-based functions (light and environment sampling, solid-angle and environment pdfs) take 1 M /
//! 10 M shading points, whole paths 200 k / 2 M per scene and strategy, and the device frames 96 × 72 at
//! 16 / 64 spp.
//!
//! The integrator's final guard ([`INTEGRATOR_FLAG_NO_FINAL_GUARD`]) is switched off wherever paths are
//! traced here, so a non-finite value anywhere in a path would show.
//!
//! Without a Vulkan device the device tests print a note and pass, except with `CI=true`.
use std::time::Instant;

use fovea_core::glam::{Vec2, Vec3};
use fovea_core::integrator::path::{
    IntegratorSettings, INTEGRATOR_FLAG_NO_FINAL_GUARD, STRATEGY_BSDF_ONLY, STRATEGY_LIGHT_ONLY,
    STRATEGY_MIS,
};
use fovea_core::integrator::{trace_path, FrameParams};
use fovea_core::kernel_abi::*;
use fovea_core::lights::{environment, power_heuristic, sample_light, triangle};
use fovea_core::post::tonemap::tonemap_linear;
use fovea_core::rng::SampleRng;
use fovea_core::scene::{Material, SceneView, MATERIAL_DOUBLE_SIDED_EMISSION};
use fovea_core::scene::{SceneSlices, SceneSource};
use fovea_scene::environment::Environment;
use fovea_scene::pack::PackedScene;
use fovea_tests::stability::{
    heavy, icosphere, loaded_scene, ordered, pack, pick, push_probe_item as push, Rng,
};
use rayon::prelude::*;

const STRIDE: usize = PROBE_INPUT_RECORDS as usize;
const OUT: usize = PROBE_OUTPUT_RECORDS as usize;
/// Probe items per chunk (32 MiB of input records).
const CHUNK: usize = 1 << 18;
/// Items per probe function: 1 M in CI, 10 M with `FOVEA_HEAVY=1`.
fn fuzz_count() -> usize {
    pick(1 << 20, 10_000_000)
}

fn finite4(r: [f32; 4]) -> bool {
    r.iter().all(|x| x.is_finite())
}

/// Checks one item's outputs (see [`Case::check`]).
type Check = fn(&[[f32; 4]], &[[f32; 4]]) -> Result<bool, String>;

/// One probe function under test: how to make an item and what its outputs must satisfy.
struct Case {
    name: &'static str,
    selector: u32,
    /// Appends one item (exactly `STRIDE` records).
    gen: fn(&mut Rng, &mut Vec<[f32; 4]>),
    /// `Err(why)` if the outputs of an item are not acceptable; `Ok(true)` if the item "did something"
    /// (a hit, a non-zero value), for the coverage figure.
    check: Check,
}

fn rec(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

fn disney_head(rng: &mut Rng) -> [[f32; 4]; 3] {
    let rough = match rng.below(4) {
        0 => 0.0,
        _ => rng.unit_param(),
    };
    [
        [
            rng.unit_param(),
            rng.unit_param(),
            rng.unit_param(),
            rng.unit_param(),
        ],
        [rough, rng.unit_param(), rng.unit_param(), rng.unit_param()],
        [
            rng.unit_param(),
            rng.unit_param(),
            rng.unit_param(),
            rng.unit_param(),
        ],
    ]
}

fn gen_disney_eval(rng: &mut Rng, v: &mut Vec<[f32; 4]>) {
    let head = disney_head(rng);
    let wo = rng.adversarial_dir();
    let wi = match rng.below(6) {
        // The mirror direction (the specular peak; a delta at roughness 0).
        0 => Vec3::new(-wo.x, -wo.y, wo.z),
        1 => wo,
        2 => -wo,
        3 => Vec3::new(-wo.x, -wo.y, wo.z) + rng.dir() * 1e-6,
        _ => rng.adversarial_dir(),
    };
    push(v, &[head[0], head[1], head[2], rec(wo, 0.0), rec(wi, 0.0)]);
}

fn gen_disney_sample(rng: &mut Rng, v: &mut Vec<[f32; 4]>) {
    let head = disney_head(rng);
    let wo = rng.adversarial_dir();
    let edge = [0.0, 1.0 - f32::EPSILON / 2.0, 0.5, f32::EPSILON];
    let mut u = [rng.f(), rng.f(), rng.f()];
    for x in &mut u {
        if rng.below(4) == 0 {
            *x = edge[rng.below(4) as usize];
        }
    }
    push(
        v,
        &[
            head[0],
            head[1],
            head[2],
            rec(wo, 0.0),
            [u[0], u[1], u[2], 0.0],
        ],
    );
}

fn check_disney_eval(_: &[[f32; 4]], out: &[[f32; 4]]) -> Result<bool, String> {
    let o = out[0];
    if !finite4(o) || o.iter().any(|&x| x < 0.0) {
        return Err("f or pdf not finite and non-negative".into());
    }
    Ok(o[3] > 0.0)
}

fn check_disney_sample(_: &[[f32; 4]], out: &[[f32; 4]]) -> Result<bool, String> {
    let (a, b) = (out[0], out[1]);
    if !finite4(a) || !finite4(b) || a[3] < 0.0 {
        return Err("non-finite output or negative pdf".into());
    }
    if a[3] > 0.0 {
        let wi = Vec3::new(a[0], a[1], a[2]);
        if (wi.length() - 1.0).abs() > 1e-4 || wi.z <= 0.0 || wi.z.is_nan() {
            return Err(format!("sampled wi {wi:?} not unit or below the surface"));
        }
        if b[0] < 0.0 || b[1] < 0.0 || b[2] < 0.0 {
            return Err("negative f".into());
        }
    }
    Ok(a[3] > 0.0)
}

fn gen_triangle(rng: &mut Rng, v: &mut Vec<[f32; 4]>) {
    let scale = rng.log_uniform(1e-6, 1e6);
    let centre = match rng.below(3) {
        0 => Vec3::ZERO,
        1 => rng.dir() * scale * rng.range(0.0, 3.0),
        _ => rng.dir() * rng.log_uniform(1e-6, 1e6),
    };
    let vert = |rng: &mut Rng| centre + rng.dir() * scale * rng.range(0.05, 1.0);
    let (v0, v1) = (vert(rng), vert(rng));
    let v2 = match rng.below(8) {
        0 => v0,                                                             // two equal vertices
        1 => v0.lerp(v1, rng.f()),                                           // collinear
        2 => v0 + (v1 - v0) * 2.0, // collinear, outside the segment
        3 => v0 + rng.dir() * scale * 1e-6, // needle
        4 if rng.below(4) == 0 => return push_tri(rng, v, [v0, v0, v0], v0), // a point
        _ => vert(rng),
    };
    let (b1, b2) = match rng.below(6) {
        0 => (0.0, rng.f()),
        1 => (0.0, 0.0),
        2 => {
            let b = rng.f();
            (b, 1.0 - b)
        }
        3 => (rng.range(-0.5, 1.5), rng.range(-0.5, 1.5)),
        _ => {
            let (a, b) = (rng.f(), rng.f());
            if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            }
        }
    };
    let target = v0 * (1.0 - b1 - b2) + v1 * b1 + v2 * b2;
    push_tri(rng, v, [v0, v1, v2], target);
}

/// A ray at `target` of triangle `t`, with adversarial direction and `t_max`.
fn push_tri(rng: &mut Rng, v: &mut Vec<[f32; 4]>, t: [Vec3; 3], target: Vec3) {
    let mut dir = match rng.below(8) {
        0 => (t[1] - t[0]).normalize_or_zero(), // in the triangle's plane
        1 => {
            let mut d = Vec3::ZERO;
            d[rng.below(3) as usize] = rng.sign();
            d
        }
        2 => {
            let mut d = rng.dir();
            d[rng.below(3) as usize] = 0.0;
            d.normalize_or_zero()
        }
        3 if rng.below(8) == 0 => Vec3::ZERO,
        _ => rng.dir(),
    };
    let size = (t[1] - t[0]).length().max((t[2] - t[0]).length()).max(1e-6);
    let dist = size * rng.log_uniform(1e-3, 1e3);
    let origin = target - dir * dist;
    if rng.below(4) == 0 {
        dir *= rng.log_uniform(1e-6, 1e6);
    }
    let t_max = match rng.below(4) {
        0 => f32::INFINITY,
        1 => 3.0e38,
        2 => dist / dir.length().max(1e-30),
        _ => rng.log_uniform(1e-6, 1e6),
    };
    push(
        v,
        &[
            rec(origin, t_max),
            rec(dir, 0.0),
            rec(t[0], 0.0),
            rec(t[1], 0.0),
            rec(t[2], 0.0),
        ],
    );
}

fn check_triangle(_: &[[f32; 4]], out: &[[f32; 4]]) -> Result<bool, String> {
    let [t, b1, b2, hit] = out[0];
    if hit == 1.0 {
        let ok = t.is_finite()
            && t > 0.0
            && b1.is_finite()
            && b2.is_finite()
            && (0.0..=1.0).contains(&b1)
            && (0.0..=1.0).contains(&b2)
            && b1 + b2 <= 1.0 + 1e-5;
        if !ok {
            return Err("hit with a non-finite or out-of-range t / barycentric".into());
        }
        Ok(true)
    } else if hit == 0.0 {
        // A miss reports t = +inf by contract (`TriangleHit::miss`) and zero barycentrics.
        if t != f32::INFINITY || b1 != 0.0 || b2 != 0.0 {
            return Err("miss with t != inf or non-zero barycentrics".into());
        }
        Ok(false)
    } else {
        Err("hit flag neither 0 nor 1".into())
    }
}

fn gen_offset(rng: &mut Rng, v: &mut Vec<[f32; 4]>) {
    let mut p = Vec3::ZERO;
    for k in 0..3 {
        p[k] = match rng.below(6) {
            0 => rng.wide(-30.0, 30.0),
            1 => rng.sign() * fovea_core::geometry::offset::ORIGIN,
            2 => -0.0,
            _ => rng.wide(-6.0, 6.0),
        };
    }
    let n = match rng.below(6) {
        0 => {
            let mut a = Vec3::ZERO;
            a[rng.below(3) as usize] = rng.sign();
            a
        }
        1 => rng.dir() * rng.log_uniform(1e-6, 1e6), // non-unit
        2 => Vec3::ZERO,
        _ => rng.dir(),
    };
    // The triangle's magnitude: at least |p| (p lies on it), often exactly that, sometimes far larger,
    // zero or below the smallest normal float.
    let magnitude = match rng.below(6) {
        0 => 0.0,
        1 => f32::from_bits(1),
        2 => p.abs().max_element(),
        _ => p.abs().max_element() * rng.log_uniform(1.0, 1e6),
    };
    push(v, &[rec(p, magnitude), rec(n, 0.0)]);
}

fn check_offset(inp: &[[f32; 4]], out: &[[f32; 4]]) -> Result<bool, String> {
    let q = out[0];
    if !finite4(q) {
        return Err("non-finite offset point".into());
    }
    // Each coordinate moves by at most 256 ulps or 2^-16 times the magnitude (clamped to at most 1).
    let scale = inp[0][3].clamp(fovea_core::geometry::offset::MIN_MAGNITUDE, 1.0);
    for k in 0..3 {
        let p = inp[0][k];
        let ulps = (ordered(q[k]) - ordered(p)).unsigned_abs();
        let step = (q[k] - p).abs();
        // (`p + 2^-16 n` rounds, so allow the step a relative 1e-3 above 2^-16.)
        if ulps > 256 && step > fovea_core::geometry::offset::FLOAT_SCALE * scale * 1.001 {
            return Err(format!("coordinate {k} moved by {step} ({ulps} ulps)"));
        }
    }
    Ok(q[..3] != inp[0][..3])
}

fn gen_tonemap(rng: &mut Rng, v: &mut Vec<[f32; 4]>) {
    let mut c = [0.0f32; 3];
    for x in &mut c {
        *x = match rng.below(12) {
            0 => 0.0,
            1 => rng.log_uniform(1e-30, 1e-6),
            2 => rng.log_uniform(1e6, 1e30),
            3 => f32::MAX,
            4 => f32::INFINITY,
            5 => f32::NAN,
            6 => -rng.log_uniform(1e-6, 1e6),
            7 => f32::NEG_INFINITY,
            _ => rng.range(0.0, 4.0),
        };
    }
    let ev = match rng.below(5) {
        0 => 0.0,
        1 => rng.range(-200.0, 200.0),
        _ => rng.range(-8.0, 8.0),
    };
    push(v, &[[c[0], c[1], c[2], ev]]);
}

fn check_tonemap(inp: &[[f32; 4]], out: &[[f32; 4]]) -> Result<bool, String> {
    let packed = out[0][0].to_bits();
    if packed >> 24 != 255 {
        return Err(format!("alpha of {packed:#x} is not 255"));
    }
    // CPU only (the probe returns the packed value): the linear result is in [0, 1].
    let i = inp[0];
    let lin = tonemap_linear(Vec3::new(i[0], i[1], i[2]), i[3]);
    if !(lin.cmpge(Vec3::ZERO).all() && lin.cmple(Vec3::ONE).all()) {
        return Err(format!("tonemap_linear {lin:?} outside [0, 1]"));
    }
    Ok(packed & 0x00ff_ffff != 0)
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "Disney eval_and_pdf",
            selector: PROBE_DISNEY_EVAL,
            gen: gen_disney_eval,
            check: check_disney_eval,
        },
        Case {
            name: "Disney sample",
            selector: PROBE_DISNEY_SAMPLE,
            gen: gen_disney_sample,
            check: check_disney_sample,
        },
        Case {
            name: "watertight triangle test",
            selector: PROBE_TRIANGLE,
            gen: gen_triangle,
            check: check_triangle,
        },
        Case {
            name: "offset_ray_origin",
            selector: PROBE_OFFSET_RAY_ORIGIN,
            gen: gen_offset,
            check: check_offset,
        },
        Case {
            name: "tonemap_to_rgba8",
            selector: PROBE_TONEMAP,
            gen: gen_tonemap,
            check: check_tonemap,
        },
    ]
}

/// The inputs of chunk `chunk` of a case (deterministic).
fn chunk_inputs(case: &Case, chunk: usize, items: usize) -> Vec<[f32; 4]> {
    // Sub-chunks generated in parallel, each from its own seed.
    const SUB: usize = 4096;
    let parts: Vec<Vec<[f32; 4]>> = (0..items.div_ceil(SUB))
        .into_par_iter()
        .map(|s| {
            let mut rng = Rng((u64::from(case.selector) << 48)
                ^ ((chunk as u64) << 20)
                ^ (s as u64 * 0x9e37));
            let n = SUB.min(items - s * SUB);
            let mut v = Vec::with_capacity(n * STRIDE);
            for _ in 0..n {
                (case.gen)(&mut rng, &mut v);
            }
            v
        })
        .collect();
    parts.concat()
}

/// Figures of one case on one backend.
struct Figures {
    items: usize,
    active: usize,
    failures: usize,
    examples: Vec<String>,
    seconds: f64,
}

fn check_outputs(case: &Case, inputs: &[[f32; 4]], outputs: &[[f32; 4]], f: &mut Figures) {
    let results: Vec<Result<bool, String>> = (0..inputs.len() / STRIDE)
        .into_par_iter()
        .map(|i| {
            (case.check)(
                &inputs[i * STRIDE..(i + 1) * STRIDE],
                &outputs[i * OUT..(i + 1) * OUT],
            )
        })
        .collect();
    for (i, r) in results.into_iter().enumerate() {
        f.items += 1;
        match r {
            Ok(true) => f.active += 1,
            Ok(false) => {}
            Err(why) => {
                f.failures += 1;
                if f.examples.len() < 5 {
                    f.examples.push(format!(
                        "{}: {why}; input {:?} output {:?}",
                        case.name,
                        &inputs[i * STRIDE..i * STRIDE + 5],
                        &outputs[i * OUT..(i + 1) * OUT]
                    ));
                }
            }
        }
    }
}

/// Runs every case through `eval` (the CPU's `probe_eval` or the device's `probe`) and asserts that no
/// item fails; prints a table.
fn run_cases(
    backend: &str,
    mut eval: impl FnMut(u32, &[[f32; 4]]) -> Vec<[f32; 4]>,
) -> Vec<(&'static str, Figures)> {
    let total = fuzz_count();
    let mut rows = Vec::new();
    for case in cases() {
        let start = Instant::now();
        let mut f = Figures {
            items: 0,
            active: 0,
            failures: 0,
            examples: Vec::new(),
            seconds: 0.0,
        };
        let mut done = 0;
        let mut chunk = 0;
        while done < total {
            let items = CHUNK.min(total - done);
            let inputs = chunk_inputs(&case, chunk, items);
            let outputs = eval(case.selector, &inputs);
            assert_eq!(outputs.len(), items * OUT);
            check_outputs(&case, &inputs, &outputs, &mut f);
            done += items;
            chunk += 1;
        }
        f.seconds = start.elapsed().as_secs_f64();
        rows.push((case.name, f));
    }
    eprintln!(
        "\nfinite everywhere on {backend} ({} items per function{})",
        total,
        if heavy() { ", FOVEA_HEAVY" } else { "" }
    );
    eprintln!(
        "| {:<26} | {:>10} | {:>9} | {:>8} | {:>7} |",
        "function", "items", "non-zero", "failures", "s"
    );
    for (name, f) in &rows {
        eprintln!(
            "| {:<26} | {:>10} | {:>8.2}% | {:>8} | {:>7.2} |",
            name,
            f.items,
            100.0 * f.active as f64 / f.items as f64,
            f.failures,
            f.seconds
        );
    }
    let examples: Vec<&String> = rows.iter().flat_map(|(_, f)| &f.examples).collect();
    assert!(
        examples.is_empty(),
        "non-finite or invalid outputs: {examples:#?}"
    );
    for (name, f) in &rows {
        // The generators are not degenerate: a good share of items do something.
        assert!(
            f.active as f64 > 0.05 * f.items as f64,
            "{name}: only {} of {} items non-trivial",
            f.active,
            f.items
        );
    }
    rows
}

#[test]
fn probe_functions_are_finite_on_cpu() {
    let frame: FrameParams = fovea_tests::frame_params(
        fovea_tests::cornell_camera(4, 4),
        fovea_core::foveation::regions::FoveationParams::uniform(1),
        4,
        4,
        0,
    );
    run_cases("the CPU", |selector, inputs| {
        let items = inputs.len() / STRIDE;
        (0..items)
            .into_par_iter()
            .flat_map_iter(|i| probe_eval(selector, inputs, i as u32, &frame, &[], &[]))
            .collect()
    });
}

#[test]
fn probe_functions_are_finite_on_vulkan() {
    let Some(mut ctx) = fovea_tests::vulkan_context_or_skip("the Vulkan finite-everywhere test")
    else {
        return;
    };
    let log = ctx.validation_log();
    let device = ctx.device_description();
    run_cases(&device, |selector, inputs| {
        ctx.run_probe(selector, inputs)
            .unwrap_or_else(|e| panic!("probe {selector}: {e}"))
    });
    drop(ctx);
    let messages = log.lock().unwrap().clone();
    assert!(messages.is_empty(), "validation messages: {messages:#?}");
}

// ---------------------------------------------------------------------------------------------------------
// Scene-based functions (CPU): light and environment sampling, MIS weights, whole paths.
// ---------------------------------------------------------------------------------------------------------

fn material(base: f32, metallic: f32, roughness: f32) -> Material {
    Material {
        base_color: [base, base, base, 1.0],
        metallic,
        roughness,
        ..Default::default()
    }
}

fn emitter(radiance: f32, double_sided: bool) -> Material {
    Material {
        base_color: [0.0, 0.0, 0.0, 1.0],
        emission: [radiance, radiance, radiance, 0.0],
        flags: if double_sided {
            MATERIAL_DOUBLE_SIDED_EMISSION
        } else {
            0
        },
        ..Default::default()
    }
}

/// A scene built to break things: a closed room (diffuse, mirror and rough-metal walls), mirror and
/// glossy and glass (rough, and smooth with index 4) icospheres, emitters of size 1e-6 to 1e3 with radiance up to 1e6 (one-sided and two-sided,
/// needles and a collinear "triangle" among them), a stack of coplanar triangles, a huge far triangle,
/// tiny triangles far from the origin, adversarial vertex normals (non-unit, flipped, opposite at the
/// corners of one triangle) and a constant sky through an opening.
fn adversarial_scene(environment: &Environment) -> PackedScene {
    let mut rng = Rng(0xad5e);
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut normals: Vec<[f32; 3]> = Vec::new();
    let mut triangles = Vec::new();
    let mut mats = Vec::new();
    let materials = vec![
        material(0.8, 0.0, 1.0),  // 0 diffuse
        material(1.0, 1.0, 0.0),  // 1 mirror
        material(0.9, 1.0, 0.05), // 2 glossy metal
        emitter(1e6, false),      // 3
        emitter(1e6, true),       // 4
        emitter(1.0, true),       // 5
        Material {
            clearcoat: 1.0,
            clearcoat_gloss: 1.0,
            sheen: 1.0,
            anisotropic: 0.99,
            roughness: 0.0,
            ..material(1.0, 0.0, 0.0)
        }, // 6 everything at once
        Material {
            transmission: 1.0,
            ior: 1.5,
            ..material(1.0, 0.0, 0.3)
        }, // 7 rough glass
        Material {
            transmission: 0.7,
            ior: 4.0,
            flags: fovea_core::scene::MATERIAL_THIN_WALLED,
            ..material(0.9, 0.3, 0.0)
        }, // 8 smooth thin wall, partly metallic, extreme index
    ];
    let mut tri = |p: [Vec3; 3], n: [Vec3; 3], m: u32| {
        let base = positions.len() as u32;
        for k in 0..3 {
            positions.push(p[k].to_array());
            normals.push(n[k].to_array());
        }
        triangles.push([base, base + 1, base + 2]);
        mats.push(m);
    };
    let z3 = [Vec3::ZERO; 3];
    // A room [-1, 1]^3 with an opening in the ceiling.
    let quad = |tri: &mut dyn FnMut([Vec3; 3], [Vec3; 3], u32), c: [Vec3; 4], m: u32| {
        tri([c[0], c[1], c[2]], z3, m);
        tri([c[0], c[2], c[3]], z3, m);
    };
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    quad(
        &mut tri,
        [
            v(-1., -1., -1.),
            v(1., -1., -1.),
            v(1., -1., 1.),
            v(-1., -1., 1.),
        ],
        0,
    );
    quad(
        &mut tri,
        [
            v(-1., -1., -1.),
            v(-1., 1., -1.),
            v(1., 1., -1.),
            v(1., -1., -1.),
        ],
        1,
    );
    quad(
        &mut tri,
        [
            v(-1., -1., -1.),
            v(-1., -1., 1.),
            v(-1., 1., 1.),
            v(-1., 1., -1.),
        ],
        2,
    );
    quad(
        &mut tri,
        [
            v(1., -1., -1.),
            v(1., 1., -1.),
            v(1., 1., 1.),
            v(1., -1., 1.),
        ],
        6,
    );
    quad(
        &mut tri,
        [
            v(-1., 1., -1.),
            v(-1., 1., 0.),
            v(1., 1., 0.),
            v(1., 1., -1.),
        ],
        0,
    );
    // Spheres with smooth normals (mirror, everything-at-once, rough glass, extreme glass).
    for (c, r, m) in [
        (v(-0.4, -0.5, -0.2), 0.4, 1u32),
        (v(0.5, -0.6, 0.3), 0.3, 6),
        (v(0.1, -0.3, -0.6), 0.25, 7),
        (v(-0.5, 0.3, 0.45), 0.2, 8),
    ] {
        let (p, t) = icosphere(c, r, 2);
        for f in t {
            let q = [0, 1, 2].map(|k| Vec3::from(p[f[k] as usize]));
            let n = q.map(|x| (x - c).normalize());
            tri(q, n, m);
        }
    }
    // Emitters of every size: 1e-6 .. 1e-1 near the ceiling, facing down; needles and a collinear one.
    for (i, size) in [1e-6f32, 1e-4, 1e-2, 1e-1].iter().enumerate() {
        let c = v(-0.6 + 0.4 * i as f32, 0.95, -0.5);
        let m = if i % 2 == 0 { 3 } else { 4 };
        tri([c, c + v(0.0, 0.0, *size), c + v(*size, 0.0, 0.0)], z3, m);
    }
    let c = v(0.0, 0.9, 0.5);
    tri([c, c + v(0.5, 0.0, 0.0), c + v(0.0, 0.0, 1e-7)], z3, 4); // needle
    tri([c, c + v(0.2, 0.0, 0.0), c + v(0.4, 0.0, 0.0)], z3, 4); // collinear
                                                                 // Coplanar stack (z-fighting) on the floor.
    for _ in 0..4 {
        tri(
            [
                v(-0.9, -0.999, 0.5),
                v(-0.2, -0.999, 0.9),
                v(-0.5, -0.999, 0.2),
            ],
            z3,
            rng.below(3),
        );
    }
    // Adversarial shading normals: non-unit, flipped, opposite at the corners, grazing.
    let p3 = [v(0.2, -0.9, -0.8), v(0.8, -0.9, -0.8), v(0.5, -0.3, -0.8)];
    tri(
        p3,
        [v(0.0, 0.0, 5.0), v(0.0, 0.0, 1e-3), v(0.0, 0.0, -1.0)],
        0,
    );
    tri(
        [
            p3[0] + v(0.0, 0.0, 0.1),
            p3[1] + v(0.0, 0.0, 0.1),
            p3[2] + v(0.0, 0.0, 0.1),
        ],
        [v(0.0, 0.0, 1.0), v(0.0, 0.0, -1.0), v(1.0, 0.0, 1e-6)],
        2,
    );
    // A huge far triangle and tiny far ones (outside the room, seen through the opening).
    tri(
        [v(-1e6, 1e3, -1e6), v(1e6, 1e3, -1e6), v(0.0, 1e3, 1e6)],
        z3,
        0,
    );
    for _ in 0..8 {
        let c = rng.dir() * 1e5 + v(0.0, 2e5, 0.0);
        tri(
            [c, c + rng.dir() * 1e-2, c + rng.dir() * 1e-2],
            z3,
            rng.below(5),
        );
    }
    let mut scene = loaded_scene(positions, triangles, mats, materials);
    scene.normals = normals;
    pack(scene, environment)
}

/// Adversarial shading points: inside the room, on the emitters, in their planes, far away.
fn shading_point(rng: &mut Rng, scene: &SceneView) -> Vec3 {
    match rng.below(6) {
        0 => {
            let t =
                SceneSlices.triangle(scene, rng.below(scene.geometry.triangle_lanes.len() as u32));
            let (a, b) = (rng.f(), rng.f());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let v0 = Vec3::new(t.v0[0], t.v0[1], t.v0[2]);
            let v1 = Vec3::new(t.v1[0], t.v1[1], t.v1[2]);
            let v2 = Vec3::new(t.v2[0], t.v2[1], t.v2[2]);
            v0 * (1.0 - a - b) + v1 * a + v2 * b
        }
        1 => Vec3::new(rng.range(-1.0, 1.0), 0.95, rng.range(-1.0, 1.0)),
        2 => rng.dir() * rng.log_uniform(1e-6, 1e6),
        _ => Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ),
    }
}

fn adversarial_u(rng: &mut Rng) -> f32 {
    match rng.below(8) {
        0 => 0.0,
        1 => 1.0 - f32::EPSILON / 2.0,
        _ => rng.f(),
    }
}

/// An environment map with black rows, single bright texels (1e6) and zeros at the poles.
fn adversarial_map() -> Environment {
    let (w, h) = (32u32, 16u32);
    let mut texels = vec![[0.0f32; 4]; (w * h) as usize];
    let mut rng = Rng(77);
    for y in 1..h - 1 {
        if y == 5 {
            continue; // a black row
        }
        for x in 0..w {
            let v = if rng.below(50) == 0 { 1e6 } else { rng.f() };
            texels[(y * w + x) as usize] = [v, v * 0.5, v * 0.25, 0.0];
        }
    }
    Environment::Map {
        width: w,
        height: h,
        texels,
        scale: [1.0, 1.0, 1.0],
    }
}

#[test]
fn light_sampling_and_mis_weights_are_finite_on_cpu() {
    let total = pick(1usize << 20, 10_000_000);
    let start = Instant::now();
    for (env_name, env) in [
        ("constant sky", Environment::Constant([1.0, 1.0, 1.0])),
        ("adversarial map", adversarial_map()),
    ] {
        let packed = adversarial_scene(&env);
        let scene = packed.view();
        let emissive = fovea_tests::emissive_triangles(&packed);
        assert!(emissive.len() >= 6, "{} emitters", emissive.len());
        let failures: Vec<String> = (0..total / 1024)
            .into_par_iter()
            .flat_map_iter(|block| {
                let mut rng = Rng(0x11_9474 ^ (block as u64) << 16);
                let mut bad = Vec::new();
                for _ in 0..1024 {
                    let p = shading_point(&mut rng, &scene);
                    let u = Vec2::new(adversarial_u(&mut rng), adversarial_u(&mut rng));
                    let u_select = adversarial_u(&mut rng);
                    // The whole light list and each emitter directly.
                    let tri = emissive[rng.below(emissive.len() as u32) as usize];
                    for (what, s) in [
                        ("sample_light", sample_light(&scene, &SceneSlices, p, u_select, u)),
                        ("triangle::sample", triangle::sample(&scene, &SceneSlices, tri, p, u)),
                        ("environment::sample", environment::sample(&scene, u)),
                    ] {
                        let ok = s.pdf.is_finite()
                            && s.pdf >= 0.0
                            && (s.pdf == 0.0
                                || (s.direction.is_finite()
                                    && (s.direction.length() - 1.0).abs() < 1e-3
                                    && s.radiance.is_finite()
                                    && s.radiance.min_element() >= 0.0
                                    && (s.is_infinite || s.target.is_finite())));
                        if !ok && bad.len() < 3 {
                            bad.push(format!(
                                "{env_name} {what}: p {p:?} u {u:?} sel {u_select} tri {tri} -> {s:?}"
                            ));
                        }
                    }
                    // Densities a BSDF-sampled ray needs.
                    let q = shading_point(&mut rng, &scene);
                    let pdf_t = triangle::solid_angle_pdf(&scene, &SceneSlices, tri, p, q);
                    let d = rng.adversarial_dir();
                    let pdf_e = environment::pdf(&scene, d);
                    let le = environment::radiance(&scene, d);
                    let ok = pdf_t.is_finite()
                        && pdf_t >= 0.0
                        && pdf_e.is_finite()
                        && pdf_e >= 0.0
                        && le.is_finite();
                    if !ok && bad.len() < 3 {
                        bad.push(format!(
                            "{env_name}: solid_angle_pdf(tri {tri}, {p:?}, {q:?}) = {pdf_t}, \
                             environment pdf({d:?}) = {pdf_e}, radiance {le:?}"
                        ));
                    }
                }
                bad
            })
            .collect();
        assert!(failures.is_empty(), "{failures:#?}");
    }
    // MIS weights over every pair of adversarial densities (including +inf, which a far or grazing
    // emitter's solid-angle density may overflow to).
    let pdfs = [
        0.0f32,
        f32::from_bits(1),
        1e-30,
        1e-7,
        1.0,
        3e7,
        1e19,
        1e30,
        f32::MAX,
        f32::INFINITY,
    ];
    for &a in &pdfs {
        for &b in &pdfs {
            let w = power_heuristic(a, b);
            assert!((0.0..=1.0).contains(&w), "power_heuristic({a}, {b}) = {w}");
        }
    }
    eprintln!(
        "light / environment sampling, solid-angle and environment pdfs: 2 x {total} points, {:.2} s",
        start.elapsed().as_secs_f64()
    );
}

/// The scene inputs of the device test: shading points, random numbers, an emitter and a second point
/// per item, laid out for every `PROBE_SCENE_*` selector at once (`in[0]` = (p, triangle bits),
/// `in[1]` = (u_select, u.x, u.y) for `sample_light` and (u.x, u.y) otherwise, `in[2]` = q).
fn scene_probe_inputs(
    scene: &SceneView,
    emissive: &[u32],
    selector: u32,
    chunk: usize,
    items: usize,
) -> Vec<[f32; 4]> {
    let mut rng = Rng(0x0005_ce9e ^ (u64::from(selector) << 40) ^ ((chunk as u64) << 20));
    let mut v = Vec::with_capacity(items * STRIDE);
    for _ in 0..items {
        let p = shading_point(&mut rng, scene);
        let tri = emissive[rng.below(emissive.len() as u32) as usize];
        let (a, b, c) = (
            adversarial_u(&mut rng),
            adversarial_u(&mut rng),
            adversarial_u(&mut rng),
        );
        let q = shading_point(&mut rng, scene);
        let d = rng.adversarial_dir();
        match selector {
            PROBE_SCENE_SAMPLE_LIGHT => push(&mut v, &[rec(p, 0.0), [a, b, c, 0.0]]),
            PROBE_SCENE_TRIANGLE_LIGHT => push(
                &mut v,
                &[rec(p, f32::from_bits(tri)), [a, b, 0.0, 0.0], rec(q, 0.0)],
            ),
            PROBE_SCENE_ENVIRONMENT => push(&mut v, &[rec(d, 0.0), [a, b, 0.0, 0.0]]),
            // Traversal: from a shading point in an adversarial direction, unbounded or to q.
            _ => {
                let t_max = if rng.below(2) == 0 {
                    f32::INFINITY
                } else {
                    (q - p).length()
                };
                let dir = if rng.below(2) == 0 {
                    d
                } else {
                    (q - p).normalize_or_zero()
                };
                push(&mut v, &[rec(p, t_max), rec(dir, 0.0)]);
            }
        }
    }
    v
}

/// `Err(why)` unless a light sample's records (direction xyz, pdf), (radiance rgb, _) are valid: a
/// finite, non-negative pdf and, where it is non-zero, a unit direction and finite, non-negative
/// radiance.
fn check_light_sample(out: &[[f32; 4]]) -> Result<bool, String> {
    let (d, pdf) = (Vec3::new(out[0][0], out[0][1], out[0][2]), out[0][3]);
    let l = Vec3::new(out[1][0], out[1][1], out[1][2]);
    if !(pdf.is_finite() && pdf >= 0.0) {
        return Err(format!("pdf {pdf}"));
    }
    if pdf > 0.0
        && !(d.is_finite()
            && (d.length() - 1.0).abs() < 1e-3
            && l.is_finite()
            && l.min_element() >= 0.0)
    {
        return Err("invalid sample".into());
    }
    Ok(pdf > 0.0)
}

/// The scene functions of the adversarial scene through the kernel's `probe_scene` entry point (BVH
/// traversal, light selection and sampling, triangle-light and environment densities), 1 M items per
/// function (10 M heavy), and the power heuristic over adversarial densities through `probe`.
#[test]
fn scene_functions_are_finite_on_vulkan() {
    let Some(mut ctx) = fovea_tests::vulkan_context_or_skip("the Vulkan scene finite test") else {
        return;
    };
    let log = ctx.validation_log();
    let device = ctx.device_description();
    let total = pick(1usize << 20, 10_000_000);
    let start = Instant::now();
    for (env_name, env) in [
        ("constant sky", Environment::Constant([1.0, 1.0, 1.0])),
        ("adversarial map", adversarial_map()),
    ] {
        let packed = adversarial_scene(&env);
        let scene = packed.view();
        let emissive = fovea_tests::emissive_triangles(&packed);
        let gpu_scene = ctx.upload_scene(&packed).expect("upload");
        for selector in [
            PROBE_SCENE_CLOSEST_HIT,
            PROBE_SCENE_ANY_HIT,
            PROBE_SCENE_SAMPLE_LIGHT,
            PROBE_SCENE_TRIANGLE_LIGHT,
            PROBE_SCENE_ENVIRONMENT,
        ] {
            let (mut done, mut chunk, mut active) = (0, 0, 0usize);
            let mut bad = Vec::new();
            while done < total {
                let items = CHUNK.min(total - done);
                let inputs = scene_probe_inputs(&scene, &emissive, selector, chunk, items);
                let out = ctx
                    .run_scene_probe(&gpu_scene, selector, &inputs)
                    .unwrap_or_else(|e| panic!("scene probe {selector}: {e}"));
                for i in 0..items {
                    let o = &out[i * OUT..(i + 1) * OUT];
                    let verdict = match selector {
                        PROBE_SCENE_CLOSEST_HIT => {
                            let t = o[0][0];
                            let tri = o[0][3].to_bits();
                            if t == f32::INFINITY {
                                Ok(false)
                            } else if t > 0.0
                                && t.is_finite()
                                && (tri as usize) < scene.geometry.triangle_lanes.len()
                                && o[0][1].is_finite()
                                && o[0][2].is_finite()
                            {
                                Ok(true)
                            } else {
                                Err(format!("hit {:?}", o[0]))
                            }
                        }
                        PROBE_SCENE_ANY_HIT => match o[0][0] {
                            0.0 => Ok(false),
                            1.0 => Ok(true),
                            x => Err(format!("any_hit {x}")),
                        },
                        PROBE_SCENE_SAMPLE_LIGHT => check_light_sample(o),
                        PROBE_SCENE_TRIANGLE_LIGHT => check_light_sample(o).and_then(|a| {
                            let pdf_q = o[1][3];
                            if pdf_q.is_finite() && pdf_q >= 0.0 {
                                Ok(a)
                            } else {
                                Err(format!("solid_angle_pdf {pdf_q}"))
                            }
                        }),
                        _ => {
                            let (le, pdf) = (o[0], o[0][3]);
                            let sample = [o[1], [1.0, 1.0, 1.0, 0.0]];
                            if finite4(le) && pdf >= 0.0 && le[..3].iter().all(|&x| x >= 0.0) {
                                check_light_sample(&sample)
                            } else {
                                Err(format!("environment {le:?}"))
                            }
                        }
                    };
                    match verdict {
                        Ok(a) => active += usize::from(a),
                        Err(why) if bad.len() < 5 => bad.push(format!(
                            "{env_name} selector {selector}: {why}; input {:?}",
                            &inputs[i * STRIDE..i * STRIDE + 3]
                        )),
                        Err(_) => {}
                    }
                }
                done += items;
                chunk += 1;
            }
            eprintln!(
                "{device} {env_name} scene probe {selector}: {total} items, {:.1} % non-trivial, {} invalid",
                100.0 * active as f64 / total as f64,
                bad.len()
            );
            assert!(bad.is_empty(), "{bad:#?}");
            assert!(
                active > total / 100,
                "selector {selector}: only {active} items non-trivial"
            );
        }
    }
    // MIS weights over every pair of adversarial densities, as compiled for the device.
    let pdfs = [
        0.0f32,
        f32::from_bits(1),
        1e-30,
        1e-7,
        1.0,
        3e7,
        1e19,
        1e30,
        f32::MAX,
        f32::INFINITY,
    ];
    let mut inputs = Vec::new();
    for &a in &pdfs {
        for &b in &pdfs {
            push(&mut inputs, &[[a, b, 0.0, 0.0]]);
        }
    }
    let out = ctx
        .run_probe(PROBE_POWER_HEURISTIC, &inputs)
        .expect("power heuristic probe");
    for (i, pair) in inputs.chunks(STRIDE).enumerate() {
        let w = out[i * OUT][0];
        assert!(
            (0.0..=1.0).contains(&w),
            "power_heuristic({}, {}) = {w} on {device}",
            pair[0][0],
            pair[0][1]
        );
    }
    eprintln!(
        "scene functions on {device}: 5 x 2 x {total} items, {:.1} s",
        start.elapsed().as_secs_f64()
    );
    drop(ctx);
    let messages = log.lock().unwrap().clone();
    assert!(messages.is_empty(), "validation messages: {messages:#?}");
}

/// Traces `count` paths from random origins in random directions through `scene` with the final guard
/// off; returns the number of non-finite estimates (with examples) and of non-zero ones.
fn trace_random_paths(
    scene: &SceneView,
    count: usize,
    strategy: u32,
) -> (usize, usize, Vec<String>) {
    let settings = IntegratorSettings {
        max_bounces: 6,
        strategy,
        flags: INTEGRATOR_FLAG_NO_FINAL_GUARD,
        ..Default::default()
    };
    let results: Vec<(usize, usize, Vec<String>)> = (0..count / 256)
        .into_par_iter()
        .map(|block| {
            let mut rng = Rng(0x7a7e ^ (block as u64) << 20 ^ u64::from(strategy));
            let (mut bad, mut nonzero, mut ex) = (0, 0, Vec::new());
            for i in 0..256u32 {
                let origin = match rng.below(4) {
                    0 => shading_point(&mut rng, scene),
                    _ => Vec3::new(
                        rng.range(-0.99, 0.99),
                        rng.range(-0.99, 0.99),
                        rng.range(-0.99, 0.99),
                    ),
                };
                let dir = rng.dir();
                let mut sample_rng = SampleRng::new([block as u32, 0], 0, i, 0, 1);
                let l = trace_path(
                    scene,
                    fovea_core::geometry::Ray::new(origin, dir),
                    &mut sample_rng,
                    &settings,
                );
                if !l.is_finite() || l.min_element() < 0.0 {
                    bad += 1;
                    if ex.len() < 3 {
                        ex.push(format!("origin {origin:?} dir {dir:?} sample {i} -> {l:?}"));
                    }
                } else if l != Vec3::ZERO {
                    nonzero += 1;
                }
            }
            (bad, nonzero, ex)
        })
        .collect();
    results.into_iter().fold((0, 0, Vec::new()), |mut a, b| {
        a.0 += b.0;
        a.1 += b.1;
        a.2.extend(b.2);
        a
    })
}

#[test]
fn paths_are_finite_without_the_final_guard_on_cpu() {
    let count = pick(200_000usize, 2_000_000);
    let start = Instant::now();
    for (env_name, env) in [
        ("constant sky", Environment::Constant([1.0, 1.0, 1.0])),
        ("adversarial map", adversarial_map()),
    ] {
        let packed = adversarial_scene(&env);
        for strategy in [STRATEGY_MIS, STRATEGY_LIGHT_ONLY, STRATEGY_BSDF_ONLY] {
            let (bad, nonzero, ex) = trace_random_paths(&packed.view(), count, strategy);
            eprintln!(
                "adversarial scene, {env_name}, strategy {strategy}: {count} paths, {bad} non-finite, \
                 {nonzero} non-zero"
            );
            assert_eq!(bad, 0, "{ex:#?}");
            assert!(nonzero > count / 10);
        }
    }
    eprintln!("{:.2} s", start.elapsed().as_secs_f64());
}

/// Whole frames of the adversarial scene (and of `cornell_stiff` with its light at radiance 1.7e6) on
/// the device with the final guard off: a non-finite sample anywhere would make its pixel non-finite
/// (the block mean and the fill propagate NaN and infinity). This covers light sampling, the BVH,
/// shading and MIS as compiled for the GPU together (the scene probe above checks their parts one by one).
#[test]
fn frames_are_finite_without_the_final_guard_on_vulkan() {
    let Some(mut ctx) = fovea_tests::vulkan_context_or_skip("the Vulkan finite-frame test") else {
        return;
    };
    let log = ctx.validation_log();
    let (w, h) = (96u32, 72u32);
    let spp = pick(16u32, 64);
    let mut scenes: Vec<(&str, PackedScene, fovea_core::camera::Camera)> = Vec::new();
    for (name, env) in [
        ("adversarial, sky", Environment::Constant([1.0, 1.0, 1.0])),
        ("adversarial, map", adversarial_map()),
    ] {
        let cam = fovea_core::camera::Camera::look_at(
            Vec3::new(0.3, 0.2, 0.95),
            Vec3::new(-0.2, -0.3, -0.5),
            Vec3::Y,
            80f32.to_radians(),
            w as f32 / h as f32,
        );
        scenes.push((name, adversarial_scene(&env), cam));
    }
    let stiff = fovea_tests::bundled_scenes().join("cornell_stiff/cornell_stiff.gltf");
    if stiff.exists() {
        let mut loaded = fovea_scene::load_scene(&stiff, &Default::default()).unwrap();
        for m in &mut loaded.materials {
            for c in 0..3 {
                m.emission[c] *= 1000.0;
            }
        }
        let packed = pack(loaded, &Environment::None);
        let cam = fovea_tests::cornell_camera(w, h);
        scenes.push(("cornell_stiff x1000", packed, cam));
    }
    for (name, packed, cam) in &scenes {
        for strategy in [STRATEGY_MIS, STRATEGY_LIGHT_ONLY, STRATEGY_BSDF_ONLY] {
            let start = Instant::now();
            let mut frame = fovea_tests::frame_params(
                *cam,
                fovea_core::foveation::regions::FoveationParams::uniform(spp),
                w,
                h,
                3,
            );
            frame.integrator = IntegratorSettings {
                max_bounces: 6,
                strategy,
                flags: INTEGRATOR_FLAG_NO_FINAL_GUARD,
                ..Default::default()
            };
            let gpu_scene = ctx.upload_scene(packed).expect("upload");
            let (gpu, _) = ctx
                .render_frame(
                    &gpu_scene,
                    &frame,
                    fovea_core::foveation::fill::FILL_BILINEAR,
                    0.0,
                    true,
                )
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            let hdr = gpu.hdr.expect("HDR requested");
            let bad = hdr.pixels.iter().filter(|p| !finite4(**p)).count();
            let lit = hdr
                .pixels
                .iter()
                .filter(|p| p[0] + p[1] + p[2] > 0.0)
                .count();
            eprintln!(
                "{} {name}, strategy {strategy}: {w}x{h} x {spp} spp, {bad} non-finite pixels, {lit} lit, {:.2} s",
                ctx.device_description(),
                start.elapsed().as_secs_f64()
            );
            assert_eq!(bad, 0, "{name} strategy {strategy}");
            // BSDF sampling alone rarely finds cornell_stiff's tiny light: only require some light.
            let min_lit = if strategy == STRATEGY_BSDF_ONLY {
                1
            } else {
                (w * h / 4) as usize
            };
            assert!(lit >= min_lit, "{name}: only {lit} lit pixels");
        }
    }
    drop(ctx);
    let messages = log.lock().unwrap().clone();
    assert!(messages.is_empty(), "validation messages: {messages:#?}");
}
