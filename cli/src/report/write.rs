//! The report's text outputs: Markdown tables, JSON and CSV.
use std::fmt::Write as _;
use std::path::Path;

use serde_json::{json, Value};

use super::metrics::RegionMeans;
use super::sequence::SequenceReport;
use super::{ConfigResult, SceneReport};
use crate::error::Result;
use crate::output::write_atomically;

/// Writes `text` to `path` atomically.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    write_atomically(path, |tmp| {
        std::fs::write(tmp, text.as_bytes()).map_err(|e| e.to_string())
    })
}

/// `x`, or `null` when it is not finite.
fn finite_or_null(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

/// `{all, fovea, intermediate, periphery}`; a region without pixels is `null`.
fn region_json(m: &RegionMeans) -> Value {
    let v = finite_or_null;
    json!({
        "all": v(m.all),
        "fovea": v(m.fovea),
        "intermediate": v(m.intermediate),
        "periphery": v(m.periphery),
    })
}

fn config_json(c: &ConfigResult) -> Value {
    json!({
        "config": c.spec.name,
        "kind": c.spec.kind.as_str(),
        "denoised": c.spec.denoise,
        "spp": &c.spec.foveation.spp[..3],
        "blocks": &c.spec.foveation.block_size[..3],
        "radii_px": if c.spec.foveation.radius_fovea == f32::MAX {
            Value::Null
        } else {
            json!([c.spec.foveation.radius_fovea, c.spec.foveation.radius_intermediate])
        },
        "render_ms": c.render_ms,
        "render_ms_runs": c.runs_ms,
        "primary_samples": c.primary_samples,
        "samples_per_region": {
            "fovea": c.samples_per_region[0],
            "intermediate": c.samples_per_region[1],
            "periphery": c.samples_per_region[2],
        },
        "speedup": c.speedup,
        "sample_ratio": c.sample_ratio,
        "flip": region_json(&c.flip),
        "rel_mse": region_json(&c.rel_mse),
        "image": c.image,
        "flip_map": c.flip_map,
    })
}

/// The JSON document (`ppd`, `reference` and `configs` at the top level, as the issue specifies).
#[must_use]
pub fn report_json(r: &SceneReport) -> Value {
    json!({
        "scene": r.scene,
        "backend": r.backend,
        "device": r.device,
        "resolution": r.resolution,
        "gaze": r.gaze,
        "radii_px": r.radii_px,
        "display_cm": r.display_cm,
        "distance_cm": r.distance_cm,
        "ppd": r.ppd,
        "reference": r.reference,
        "reference_spp": r.reference_spp,
        "reference_cache": r.reference_cache,
        "reference_cached": r.reference_cached,
        "reference_render_ms": r.reference_render_ms,
        "regions": r.regions,
        "region_pixels": {
            "fovea": r.region_pixels[0],
            "intermediate": r.region_pixels[1],
            "periphery": r.region_pixels[2],
        },
        "runs": r.runs,
        "seed": r.seed,
        "equal_time_spp": r.equal_time_spp,
        "equal_time_fit_spp": finite_or_null(r.equal_time_fit),
        "rel_mse_epsilon": super::metrics::REL_MSE_EPSILON,
        "wall_ms": r.wall_ms,
        "fovea_version": env!("CARGO_PKG_VERSION"),
        "configs": r.configs.iter().map(config_json).collect::<Vec<_>>(),
        "sequence": r.sequence.as_ref().map(sequence_json),
    })
}

/// The gaze-trace sequence: per configuration its frame time, region means, `eccentricity_bands`
/// (degrees, FLIP, relMSE and flicker per band), `flicker` (per region) and `fovvideovdp`.
fn sequence_json(q: &SequenceReport) -> Value {
    json!({
        "trace": q.trace,
        "camera_path": q.camera_path,
        "frames": q.frames,
        "fps": q.fps,
        "band_deg": q.band_deg,
        "region_bounds_deg": q.region_bounds_deg,
        "flicker_definition": "mean over pixels and consecutive frame pairs of ((Y_t - R_t) - (Y_{t-1} - R_{t-1}))^2 / (R_t^2 + 0.01), Y the frame's and R the reference's luminance (one reference while the camera is still)",
        "saccade_frames": q.saccades,
        "fovea_lag_definition": "per saccade (a gaze step beyond the fovea's radius), on the fovea's mean FLIP relative to uniform 32 spp without history on the same frame: frames until it is within 10 % of its mean over the 3 frames before; jump: the saccade frame's value over that mean",
        "configs": q.results.iter().map(|c| json!({
            "name": c.spec.name,
            "slug": c.spec.slug,
            "kind": c.spec.kind.as_str(),
            "spp": c.spec.spp,
            "foveated": c.spec.foveated,
            "history": c.spec.history,
            "frames": c.frames,
            "frame_ms": finite_or_null(c.frame_ms),
            "primary_samples_per_frame": c.primary_samples_per_frame,
            "flip": region_json(&c.flip),
            "rel_mse": region_json(&c.rel_mse),
            "flicker": region_json(&c.flicker),
            "eccentricity_bands": c.bands.iter().map(|b| json!({
                "from_deg": b.from_deg,
                "to_deg": b.to_deg,
                "pixels": b.pixels,
                "flip": finite_or_null(b.flip),
                "rel_mse": finite_or_null(b.rel_mse),
                "flicker": finite_or_null(b.flicker),
            })).collect::<Vec<_>>(),
            "fovvideovdp": c.fovvideovdp.as_ref().map(|v| json!({
                "jod": finite_or_null(v.jod),
                "info": v.info,
                "seconds": v.seconds,
                "seconds_per_frame": v.seconds / f64::from(c.frames.max(1)),
            })),
            "fovea_lag": c.fovea_lag.as_ref().map(|l| json!({
                "saccades": l.saccades,
                "recovered": l.recovered,
                "median_frames": finite_or_null(l.median_frames),
                "median_jump": finite_or_null(l.median_jump),
            })),
            "evaluation_ms_per_frame": finite_or_null(c.evaluation_ms),
        })).collect::<Vec<_>>(),
        "fovvideovdp_note": q.fovvideovdp_note,
    })
}

/// The sequence's Markdown: per configuration frame time, FLIP and flicker by region, FovVideoVDP.
fn sequence_md(s: &mut String, q: &SequenceReport) {
    let _ = writeln!(
        s,
        "### Sequence: {} frames of `{}`{}
",
        q.frames,
        q.trace,
        q.camera_path.as_ref().map_or_else(String::new, |c| format!(
            ", the camera moving along `{c}` (each camera scored against its own reference)"
        ))
    );
    let _ = writeln!(
        s,
        "Each frame is scored against the reference and pooled around that frame's gaze: by the \
         32/16/8 regions at the gaze (their edges at {:.2}° and {:.2}° of eccentricity) and in {}° \
         bands of eccentricity (`sequence.svg`, `report.json` `sequence.configs[].eccentricity_bands`). \
         Flicker: mean of ((Y_t − R_t) − (Y_t−1 − R_t−1))² / (R_t² + 0.01) over consecutive frames \
         (Y the frame's, R the reference's luminance).\n",
        q.region_bounds_deg[0], q.region_bounds_deg[1], q.band_deg
    );
    s.push_str(
        "| Configuration | Frame ms | FLIP fovea | FLIP intermediate | FLIP periphery | \
         Flicker fovea | Flicker periphery | FovVideoVDP JOD |\n",
    );
    s.push_str("|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for c in &q.results {
        let jod = c
            .fovvideovdp
            .as_ref()
            .map_or("–".to_string(), |v| md_number(v.jod, 3));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            c.spec.name,
            md_number(c.frame_ms, 1),
            md_number(c.flip.fovea, 4),
            md_number(c.flip.intermediate, 4),
            md_number(c.flip.periphery, 4),
            md_sci(c.flicker.fovea),
            md_sci(c.flicker.periphery),
            jod,
        );
    }
    let _ = writeln!(s, "\n{}\n", q.fovvideovdp_note);
    sequence_cost_and_lag_md(s, q);
}

/// The fovea's recovery after saccades and the evaluation's own cost, per configuration.
fn sequence_cost_and_lag_md(s: &mut String, q: &SequenceReport) {
    let _ = writeln!(
        s,
        "**After a saccade** ({} in the trace: gaze steps beyond the fovea's {:.2}°): the fovea's FLIP, \
         relative to uniform 32 spp on the same frame (the new point of gaze may see harder content), \
         on the saccade's frame against the 3 frames before (jump), and frames until it is back within \
         10 % (lag; its regions follow the gaze on the same frame, its quality may not). **Evaluation \
         cost**: fovea's own scoring per frame, and FovVideoVDP's.\n",
        q.saccades.len(),
        q.region_bounds_deg[0]
    );
    s.push_str(
        "| Configuration | Jump | Lag (frames, median) | Recovered | Scoring ms/frame | FovVideoVDP s/frame |\n",
    );
    s.push_str("|---|---:|---:|---:|---:|---:|\n");
    for c in &q.results {
        let (jump, lag, recovered) = c.fovea_lag.as_ref().map_or(
            ("–".to_string(), "–".to_string(), "–".to_string()),
            |l| {
                (
                    md_number(l.median_jump, 2),
                    md_number(l.median_frames, 1),
                    format!("{}/{}", l.recovered, l.saccades),
                )
            },
        );
        let fvvdp = c.fovvideovdp.as_ref().map_or("–".to_string(), |v| {
            md_number(v.seconds / f64::from(c.frames.max(1)), 3)
        });
        let _ = writeln!(
            s,
            "| {} | {jump} | {lag} | {recovered} | {} | {fvvdp} |",
            c.spec.name,
            md_number(c.evaluation_ms, 1),
        );
    }
    s.push('\n');
}

fn csv_number(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        String::new()
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The CSV: one row per configuration, the same values as the JSON.
#[must_use]
pub fn report_csv(r: &SceneReport) -> String {
    let mut out = String::from(
        "config,kind,render_ms,primary_samples,speedup,sample_ratio,\
         flip_all,flip_fovea,flip_intermediate,flip_periphery,\
         rel_mse_all,rel_mse_fovea,rel_mse_intermediate,rel_mse_periphery,image,flip_map\n",
    );
    for c in &r.configs {
        let mut fields = vec![
            csv_field(&c.spec.name),
            c.spec.kind.as_str().to_string(),
            csv_number(c.render_ms),
            c.primary_samples.to_string(),
            csv_number(c.speedup),
            csv_number(c.sample_ratio),
        ];
        fields.extend(c.flip.to_array().map(csv_number));
        fields.extend(c.rel_mse.to_array().map(csv_number));
        fields.push(csv_field(&c.image));
        fields.push(csv_field(&c.flip_map));
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}

fn md_number(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$}")
    } else {
        "–".to_string()
    }
}

/// A relMSE with three significant digits (values span several decades).
fn md_sci(x: f64) -> String {
    if !x.is_finite() {
        "–".to_string()
    } else if x == 0.0 {
        "0".to_string()
    } else if (1.0e-3..1.0e3).contains(&x.abs()) {
        let digits = (2 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.digits$}")
    } else {
        format!("{x:.2e}")
    }
}

/// The Markdown report: a header with the setup, then time, FLIP and relMSE tables.
#[must_use]
pub fn report_md(r: &SceneReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## {}\n", r.scene_name);
    let _ = writeln!(
        s,
        "{}×{} on {} ({}); gaze ({:.1}, {:.1}); fovea / intermediate radii {:.2} / {:.2} px \
         (5.2° / 17° on a {}×{} cm display at {} cm); FLIP at {:.2} pixels per degree; \
         reference {} spp ({}); render times are medians of {} run{}.\n",
        r.resolution[0],
        r.resolution[1],
        r.backend,
        r.device,
        r.gaze[0],
        r.gaze[1],
        r.radii_px[0],
        r.radii_px[1],
        r.display_cm[0],
        r.display_cm[1],
        r.distance_cm,
        r.ppd,
        r.reference_spp,
        if r.reference_cached {
            "cached"
        } else {
            "rendered now"
        },
        r.runs,
        if r.runs == 1 { "" } else { "s" },
    );

    s.push_str("### Time and samples\n\n");
    s.push_str(
        "| Configuration | spp (F/I/P) | Primary samples | Render ms | Speed-up | Sample ratio |\n",
    );
    s.push_str("|---|---|---:|---:|---:|---:|\n");
    for c in &r.configs {
        let spp = c.spec.foveation.spp;
        let spp = if spp[0] == spp[1] && spp[1] == spp[2] {
            format!("{}", spp[0])
        } else {
            format!("{}/{}/{}", spp[0], spp[1], spp[2])
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {}× | {}× |",
            c.spec.name,
            spp,
            c.primary_samples,
            md_number(c.render_ms, 1),
            md_number(c.speedup, 2),
            md_number(c.sample_ratio, 2),
        );
    }
    s.push_str(
        "\nSpeed-up: uniform 32 spp render time / this render time. Sample ratio: uniform 32 spp \
         primary samples / this configuration's.\n\n",
    );

    let table = |s: &mut String,
                 title: &str,
                 get: &dyn Fn(&ConfigResult) -> RegionMeans,
                 fmt: &dyn Fn(f64) -> String| {
        let _ = writeln!(s, "### {title}\n");
        s.push_str("| Configuration | All | Fovea | Intermediate | Periphery |\n");
        s.push_str("|---|---:|---:|---:|---:|\n");
        for c in &r.configs {
            let m = get(c).to_array();
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} |",
                c.spec.name,
                fmt(m[0]),
                fmt(m[1]),
                fmt(m[2]),
                fmt(m[3])
            );
        }
        s.push('\n');
    };
    table(
        &mut s,
        "Mean FLIP against the reference (lower is better)",
        &|c| c.flip,
        &|x| md_number(x, 4),
    );
    table(
        &mut s,
        "relMSE against the reference (linear HDR, lower is better)",
        &|c| c.rel_mse,
        &md_sci,
    );
    let _ = writeln!(
        s,
        "Regions: {} / {} / {} pixels (fovea / intermediate / periphery) by the block ownership of \
         foveated 32/16/8, for every configuration. relMSE = mean over pixels and channels of \
         (x − r)² / (r² + 0.01). The reference's own noise adds about relMSE(uniform) · 32 / {} \
         to every relMSE.\n",
        r.region_pixels[0], r.region_pixels[1], r.region_pixels[2], r.reference_spp
    );
    if let Some(spp) = r.equal_time_spp {
        let fit = if !r.equal_time_fit.is_finite() {
            " (too few sweep points for a line: the sweep point closest in time)".to_string()
        } else if r.equal_time_fit < 0.5 {
            format!(
                " (the line gives {:.2} spp, clamped to {spp}: even 1 spp uniform is slower than 32/16/8)",
                r.equal_time_fit
            )
        } else if (r.equal_time_fit.round() - f64::from(spp)).abs() > 0.0 {
            format!(
                " (the line gives {:.2} spp, clamped to {spp})",
                r.equal_time_fit
            )
        } else {
            format!(" (the line gives {:.2} spp)", r.equal_time_fit)
        };
        let _ = writeln!(
            s,
            "Equal time: {spp} spp uniform, from a least-squares line through the sweep's render times \
             at the 32/16/8 render time{fit}.\n"
        );
    }
    if let Some(q) = &r.sequence {
        sequence_md(&mut s, q);
    }
    s.push_str(
        "Files: `reference.png`, `regions.png` (fovea green, intermediate amber, periphery blue), \
         `images/*.png`, `flip/*.png` (FLIP error maps, magma), `plot.svg`, `report.json`, `report.csv`.\n",
    );
    if r.sequence.is_some() {
        s.push_str("Sequence: `sequence.svg` (error and flicker against eccentricity, error against frame time).\n");
    }
    s
}
