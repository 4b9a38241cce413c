//! `fovea bench`: the benchmark figures the README quotes, measured by the project itself.
//!
//! - `fovea bench build [SCENE]`: BVH build throughput (triangles per second, median of several builds)
//!   on a scene, by default the bundled Lost Empire.
//! - `fovea bench rays [SCENE]`: ray-traversal throughput alone, closest-hit and occlusion queries
//!   without shading, on generated rays or on a ray file ([`rays`]).
//! - `fovea bench scale`: a procedurally generated scene of N triangles (default 10 M, San Miguel's
//!   scale) is generated, validated, built, packed and rendered foveated at 3840×2160 on the CPU; prints
//!   the time of each step and the process's peak resident memory per triangle.
//!
//! The Mitsuba 3 comparison runs both renderers side by side and lives in `scripts/bench-peer.sh`; the
//! CPU-vs-Vulkan comparison in `scripts/bench-vulkan.sh`. No test asserts any of these timings.
mod rays;

use std::path::Path;
use std::time::Instant;

use fovea_core::camera::Camera;
use fovea_core::foveation::display::{paper_params_for_display, DisplayGeometry};
use fovea_scene::bvh::{build_bvh_indexed, BvhBuildOptions};
use fovea_scene::environment::Environment;
use fovea_scene::load_scene;
use fovea_scene::mesh::LoadOptions;
use fovea_scene::pack::pack_scene;
use fovea_scene::procedural::city_scene;
use glam::Vec3;
use serde_json::json;

use crate::args::{BenchArgs, BenchCommand};
use crate::error::{FoveaError, Result};
use crate::scene_setup::default_scene_path;

/// Runs `fovea bench`.
pub fn run(args: &BenchArgs) -> Result<()> {
    if let Some(path) = &args.json {
        // Checked before the work, which can take minutes.
        crate::output::check_json_path(path, "--json")?;
        let inputs: Vec<&Path> = match &args.what {
            BenchCommand::Build { scene, .. } => scene.iter().map(|p| p.as_path()).collect(),
            BenchCommand::Rays { scene, rays, .. } => {
                scene.iter().chain(rays).map(|p| p.as_path()).collect()
            }
            BenchCommand::Scale { .. } => Vec::new(),
            BenchCommand::Paths(paths) => paths.scene.iter().map(|p| p.as_path()).collect(),
        };
        crate::output::refuse_overwriting_inputs(&[("--json", path)], &inputs)?;
    }
    let pool = crate::backend::cpu_pool(args.threads)?;
    let figures = pool.install(|| match &args.what {
        BenchCommand::Build { scene, runs } => bench_build(scene.as_deref(), *runs),
        BenchCommand::Rays {
            scene,
            rays,
            count,
            seed,
            runs,
        } => bench_rays(scene.as_deref(), rays.as_deref(), *count, *seed, *runs),
        BenchCommand::Scale {
            triangles,
            resolution,
        } => bench_scale(*triangles, resolution.0),
        BenchCommand::Paths(paths) => bench_paths(paths, args.threads),
    })?;
    let threads = pool.current_num_threads();
    let mut figures = figures;
    figures["threads"] = json!(threads);
    println!(
        "{}",
        serde_json::to_string_pretty(&figures).expect("JSON values serialise")
    );
    if let Some(path) = &args.json {
        crate::stats::write_json(path, &figures)?;
    }
    Ok(())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median BVH build time over `runs` builds of the scene's triangles.
fn bench_build(scene: Option<&Path>, runs: u32) -> Result<serde_json::Value> {
    if runs == 0 || runs > 1000 {
        return Err(FoveaError::option("--runs", "must be 1 to 1000"));
    }
    let path = scene
        .map(Path::to_path_buf)
        .unwrap_or_else(default_scene_path);
    let loaded = load_scene(&path, &LoadOptions::default())?;
    let (positions, triangles) = (&loaded.positions, &loaded.triangles);
    let mut times = Vec::new();
    let mut bvh_stats = None;
    for _ in 0..runs {
        let start = Instant::now();
        let bvh = build_bvh_indexed(positions, triangles, &BvhBuildOptions::default());
        times.push(start.elapsed().as_secs_f64() * 1e3);
        bvh_stats = Some(bvh.stats);
    }
    let bvh_stats = bvh_stats.unwrap_or_default();
    let ms = median(times.clone());
    let n = triangles.len();
    eprintln!(
        "BVH build: {n} triangles, median {ms:.1} ms of {runs} -> {:.2} M triangles/s, SAH cost {:.2}",
        n as f64 / ms / 1e3,
        bvh_stats.sah_cost
    );
    Ok(json!({
        "scene": path.display().to_string(),
        "triangles": n,
        "nodes": bvh_stats.node_count,
        "sah_cost": bvh_stats.sah_cost,
        "max_node_depth": bvh_stats.max_depth,
        "build_ms": times,
        "median_build_ms": ms,
        "triangles_per_second": n as f64 / (ms / 1e3),
    }))
}

/// Closest-hit and occlusion throughput on a ray file or on generated rays (see [`rays`]).
fn bench_rays(
    scene: Option<&Path>,
    ray_file: Option<&Path>,
    count: usize,
    seed: u32,
    runs: u32,
) -> Result<serde_json::Value> {
    if runs == 0 || runs > 1000 {
        return Err(FoveaError::option("--runs", "must be 1 to 1000"));
    }
    if ray_file.is_none() && !(1..=rays::MAX_RAYS).contains(&count) {
        return Err(FoveaError::option(
            "--count",
            format!("must be 1 to {}", rays::MAX_RAYS),
        ));
    }
    let from_file = ray_file.map(rays::read_ray_file).transpose()?;
    let path = scene
        .map(Path::to_path_buf)
        .unwrap_or_else(default_scene_path);
    let loaded = load_scene(&path, &LoadOptions::default())?;
    let n = loaded.triangle_count();
    let origin = loaded.origin;
    let set = from_file
        .map(|set| set.in_scene(origin))
        .unwrap_or_else(|| {
            let (lo, hi) = loaded.bounds();
            rays::generate_rays(Vec3::from(lo), Vec3::from(hi), count, seed)
        });
    let packed = pack_scene(loaded, &Environment::None, &BvhBuildOptions::default());
    let view = packed.view().with_features(packed.features());
    // The untimed warm-up pass; every pass finds the same.
    let (_, _, counts) = rays::trace(&view, &set);
    let (mut closest_s, mut occlusion_s) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let (c, o, _) = rays::trace(&view, &set);
        closest_s.push(c);
        occlusion_s.push(o);
    }
    let rate = |rays: usize, s: f64| if s > 0.0 { rays as f64 / s } else { 0.0 };
    let closest_rate = rate(set.closest.len(), median(closest_s.clone()));
    let occlusion_rate = rate(set.occlusion.len(), median(occlusion_s.clone()));
    eprintln!(
        "rays: {n} triangles; {} closest-hit rays, {} hit: {:.2} M rays/s; {} occlusion rays, {} \
         occluded: {:.2} M rays/s (medians of {runs})",
        set.closest.len(),
        counts.closest_hits,
        closest_rate / 1e6,
        set.occlusion.len(),
        counts.occluded,
        occlusion_rate / 1e6,
    );
    Ok(json!({
        "scene": path.display().to_string(),
        "triangles": n,
        "ray_file": ray_file.map(|f| f.display().to_string()),
        "closest_rays": set.closest.len(),
        "closest_hits": counts.closest_hits,
        "closest_s": closest_s,
        "closest_rays_per_second": closest_rate,
        "occlusion_rays": set.occlusion.len(),
        "occluded": counts.occluded,
        "occlusion_s": occlusion_s,
        "occlusion_rays_per_second": occlusion_rate,
    }))
}

/// Peak resident memory of this process in bytes (Linux `VmHWM`), if known.
fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// `fovea bench paths`: the specialised and the general CPU path on one frame, alternated, each
/// `rounds` times: their median render times, the ratio, and whether every image was identical.
fn bench_paths(args: &crate::args::PathsArgs, threads: Option<usize>) -> Result<serde_json::Value> {
    let crate::args::PathsArgs {
        scene,
        resolution,
        rounds,
        foveation,
        camera,
        lighting,
        materials,
        path,
    } = args;
    if *rounds == 0 || *rounds > 1000 {
        return Err(FoveaError::option("--rounds", "must be 1 to 1000"));
    }
    let size = resolution.0;
    let (foveation, _, _) = crate::render::foveation_of(foveation, size)?;
    let lighting = crate::scene_setup::Lighting::from_args(lighting)?;
    let prepared = crate::scene_setup::prepare_scene(
        scene.as_deref(),
        materials.mtl.as_deref(),
        materials.mtl_diffuse.into(),
        &lighting.environment(scene.is_none()),
        &lighting.point_lights,
        true,
    )?;
    let settings = crate::schedule::FrameSettings::new(
        size,
        path,
        &crate::args::ImageArgs {
            exposure: 0.0,
            seed: 0,
        },
    );
    let (eye, target, up) = camera.points();
    let cam = crate::scene_setup::choose_camera(
        &prepared,
        eye,
        target,
        up,
        camera.fov,
        settings.aspect(),
    )?;
    let frame = settings.frame(0, cam, foveation);
    let request = settings.request(false, false, crate::backend::FrameOutput::Hdr);
    let target = crate::args::BackendArgs {
        backend: crate::args::Backend::Cpu,
        device: None,
        traversal: crate::args::Traversal::Auto,
        threads,
    };
    let mut specialised = crate::backend::Renderer::new(&target, true)?;
    specialised.set_scene(&prepared.packed, true)?;
    let mut general = crate::backend::Renderer::new(&target, true)?;
    general.set_scene(&prepared.packed, false)?;
    let (mut times_s, mut times_g) = (Vec::new(), Vec::new());
    let mut identical = true;
    let mut path_features = [0u32; 2];
    for round in 0..*rounds {
        let one = |r: &mut crate::backend::Renderer| {
            r.render(&prepared.packed, &frame, &request, &|_| {})
        };
        let (s, g) = if round % 2 == 0 {
            let s = one(&mut specialised)?;
            (s, one(&mut general)?)
        } else {
            let g = one(&mut general)?;
            (one(&mut specialised)?, g)
        };
        times_s.push(s.stats.render_ms);
        times_g.push(g.stats.render_ms);
        path_features = [s.stats.path_features, g.stats.path_features];
        let pixels = |r: &crate::backend::Rendered| {
            r.image.hdr.as_ref().map(|h| {
                h.pixels
                    .iter()
                    .flatten()
                    .map(|v| v.to_bits())
                    .collect::<Vec<_>>()
            })
        };
        identical &= pixels(&s) == pixels(&g);
    }
    let (ms_s, ms_g) = (median(times_s.clone()), median(times_g.clone()));
    Ok(json!({
        "scene": scene.as_deref().map_or_else(|| default_scene_path().display().to_string(), |p| p.display().to_string()),
        "resolution": size,
        "rounds": rounds,
        "specialised_features": crate::stats::feature_names(path_features[0]),
        "specialised_ms": ms_s,
        "general_ms": ms_g,
        "speedup": ms_g / ms_s,
        "specialised_ms_each": times_s,
        "general_ms_each": times_g,
        "identical": identical,
    }))
}

/// The 10 M-triangle scale run: generate, validate, build + pack, render foveated.
fn bench_scale(triangles: u64, resolution: [u32; 2]) -> Result<serde_json::Value> {
    if !(1..=200_000_000).contains(&triangles) {
        return Err(FoveaError::option("--triangles", "must be 1 to 200000000"));
    }
    let [w, h] = resolution;
    let start = Instant::now();
    let mut scene = city_scene(triangles, 7);
    scene.validate(Path::new("procedural city"))?;
    let generate_ms = start.elapsed().as_secs_f64() * 1e3;
    let n = scene.triangle_count();
    let start = Instant::now();
    let packed = pack_scene(
        scene,
        &Environment::Constant([0.3, 0.35, 0.45]),
        &BvhBuildOptions::default(),
    );
    let pack_total_ms = start.elapsed().as_secs_f64() * 1e3;
    let bvh_ms = packed.stats.bvh.build_ms;
    let memory_after_build = peak_memory_bytes();

    let camera = Camera::look_at(
        Vec3::new(0.0, 12.0, 45.0),
        Vec3::ZERO,
        Vec3::Y,
        60f32.to_radians(),
        w as f32 / h as f32,
    );
    let foveation = paper_params_for_display(
        [w as f32 * 0.5, h as f32 * 0.5],
        &DisplayGeometry::default(),
        w,
    );
    let frame = crate::schedule::FrameSettings::defaults([w, h], 1).frame(0, camera, foveation);
    let view = packed.view();
    let (_image, stats) = fovea_cpu::render_frame(
        &view,
        &frame,
        fovea_core::foveation::fill::FILL_BILINEAR,
        &|_| {},
    );
    let peak = peak_memory_bytes();
    let per_triangle = peak.map(|p| p as f64 / n as f64);
    eprintln!(
        "scale: {n} triangles; generate {generate_ms:.0} ms, BVH {bvh_ms:.0} ms, pack total \
         {pack_total_ms:.0} ms ({:.2} M tris/s), packed {:.0} MB; render {w}x{h} foveated {:.0} ms; \
         peak memory {} ({} bytes/triangle)",
        n as f64 / pack_total_ms / 1e3,
        packed.memory_bytes() as f64 / 1e6,
        stats.render_ms,
        peak.map_or("unknown".into(), |p| format!("{:.0} MB", p as f64 / 1e6)),
        per_triangle.map_or("unknown".into(), |b| format!("{b:.0}")),
    );
    Ok(json!({
        "triangles": n,
        "generate_ms": generate_ms,
        "bvh_build_ms": bvh_ms,
        "pack_total_ms": pack_total_ms,
        "packed_bytes": packed.memory_bytes(),
        "peak_memory_after_build_bytes": memory_after_build,
        "render_ms": stats.render_ms,
        "primary_samples": stats.primary_samples,
        "resolution": [w, h],
        "peak_memory_bytes": peak,
        "peak_bytes_per_triangle": per_triangle,
    }))
}
