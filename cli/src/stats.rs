//! `--stats`: the JSON record of a run.
use std::path::{Path, PathBuf};

use fovea_core::foveation::regions::FoveationParams;
use fovea_cpu::RenderStats;
use serde_json::{json, Value};

use crate::error::Result;
use crate::output::write_atomically;
use crate::scene_setup::PreparedScene;

/// One rendered frame.
pub struct FrameStats {
    pub frame: u32,
    /// The eye's point of gaze (image pixels): the trace's for this frame, also in a uniform run,
    /// whose samples do not follow it (a scorer takes it as the frame's fixation).
    pub gaze: [f32; 2],
    pub output: PathBuf,
    pub render: RenderStats,
    /// Backend-specific figures (Vulkan: chunks, idle invocations, upload time, validation messages).
    pub extra: Option<Value>,
    /// With `--history`: whether this frame started every pixel's history afresh (the first frame,
    /// or one whose history the backend could not continue).
    pub history_restarted: Option<bool>,
    /// The eye of a stereo frame (`left`, `right`); `None` for a single view.
    pub view: Option<&'static str>,
}

/// "AMD EPYC ... (2 threads)" from /proc/cpuinfo where available.
pub fn cpu_device_name(threads: usize) -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    format!("{model} ({threads} threads)")
}

/// The stats document (one frame: top-level fields; a gaze trace adds `frames`).
#[allow(clippy::too_many_arguments)]
pub fn build_report(
    backend: &str,
    device: &str,
    foveation: &FoveationParams,
    uniform: bool,
    radii_px: [f32; 2],
    resolution: [u32; 2],
    scene: &PreparedScene,
    run_warnings: &[String],
    frames: &[FrameStats],
    wall_ms: f64,
) -> Value {
    let first = &frames[0];
    let render_ms = first.render.render_ms;
    let frame_list: Vec<Value> = frames
        .iter()
        .map(|f| {
            let mut frame = json!({
                "frame": f.frame,
                "gaze": f.gaze,
                "output": f.output,
                "render_ms": f.render.render_ms,
                "primary_samples": f.render.primary_samples,
                "samples_per_region": region_object(f.render.samples_per_region),
                "pass_ms": pass_object(&f.render.passes),
            });
            if let Some(restarted) = f.history_restarted {
                frame["history_restarted"] = json!(restarted);
            }
            if let Some(view) = f.view {
                frame["view"] = json!(view);
            }
            frame
        })
        .collect();
    let backend_details = first.extra.clone().unwrap_or(Value::Null);
    let uniform_samples = resolution[0] as u64 * resolution[1] as u64 * foveation.spp[0] as u64;
    json!({
        "backend": backend,
        "device": device,
        "mode": if uniform { "uniform" } else { "foveated" },
        "resolution": resolution,
        "gaze": first.gaze,
        "radii_px": if uniform { json!(null) } else { json!(radii_px) },
        "spp": &foveation.spp[..3],
        "blocks": &foveation.block_size[..3],
        "primary_samples": first.render.primary_samples,
        "samples_per_region": region_object(first.render.samples_per_region),
        "blocks_per_region": region_object(first.render.blocks_per_region),
        "ideal_speedup": uniform_samples as f64 / first.render.primary_samples.max(1) as f64,
        "features": feature_names(scene.packed.features().0),
        "path_features": feature_names(first.render.path_features),
        "triangles": scene.triangle_count,
        "lights": scene.packed.lights.list.len(),
        "load_ms": scene.load_ms,
        "bvh_ms": scene.bvh_ms,
        "pack_ms": scene.pack_ms,
        "bvh_nodes": scene.packed.stats.bvh.node_count,
        "bvh_wide_nodes": scene.packed.stats.bvh.wide_node_count,
        "bvh_max_depth": scene.packed.stats.bvh.max_depth,
        "scene_bytes": scene.packed.stats.memory_bytes,
        "render_ms": render_ms,
        "wall_ms": wall_ms,
        "paths_per_second": first.render.primary_samples as f64 / (render_ms / 1e3).max(1e-9),
        "frames": frame_list,
        // Every warning the run printed: the command line's first, then the scene's.
        "warnings": run_warnings.iter().chain(&scene.warnings).collect::<Vec<_>>(),
        // What the scene file gives that fovea's mapping of its format does not use.
        "unused_scene_values": &scene.unused,
        "backend_details": backend_details,
    })
}

/// Each pass's milliseconds by name (empty where the backend timed only the whole frame).
pub fn pass_object(passes: &[(&'static str, f64)]) -> Value {
    Value::Object(
        passes
            .iter()
            .map(|(name, ms)| (name.to_string(), json!(ms)))
            .collect(),
    )
}

/// The names of the `FEATURE_*` bits set in `mask`.
pub fn feature_names(mask: u32) -> Vec<&'static str> {
    fovea_core::scene::features::FEATURE_NAMES
        .iter()
        .enumerate()
        .filter(|(i, _)| mask & (1 << i) != 0)
        .map(|(_, name)| *name)
        .collect()
}

fn region_object(v: [u64; 3]) -> Value {
    json!({ "fovea": v[0], "intermediate": v[1], "periphery": v[2] })
}

/// Writes the report (atomically).
pub fn write_json(path: &Path, report: &Value) -> Result<()> {
    let text = serde_json::to_string_pretty(report).expect("JSON values always serialise");
    write_atomically(path, |tmp| {
        std::fs::write(tmp, text.as_bytes()).map_err(|e| e.to_string())
    })
}
