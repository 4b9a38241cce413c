//! `fovea xr` against a real OpenXR runtime: Monado's null compositor and simulated headset, headless
//! and in this process's child (no service), on lavapipe (`scripts/setup-monado.sh` builds Monado
//! from the pinned snapshot in `../shared/vendor`). Each backend runs a session with the Vulkan
//! validation layer on, records each frame's eye poses, gaze and images, and `render --stereo-views`
//! of the same poses must give the same images.
//!
//! Without the runtime the test is skipped with a note, except under CI (`CI=true`), where that is a
//! failure.
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

mod support;
use support::read_exr;

const CAMERA: [&str; 6] = ["--eye", "0,1,3.9", "--target", "0,1,0", "--fov", "38"];
const FRAMES: u32 = 24;

fn fovea() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fovea"))
}

fn cornell() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/cornell_box/CornellBox-Original.obj")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fovea-xr-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Monado's runtime manifest where `scripts/setup-monado.sh` builds it, or `None` (skip) outside CI.
fn monado_manifest() -> Option<PathBuf> {
    let dir = std::env::var_os("FOVEA_MONADO_DIR")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("XDG_CACHE_HOME")
                .filter(|v| !v.is_empty())
                .map(|c| PathBuf::from(c).join("fovea/monado"))
        })
        .or_else(|| {
            std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/fovea/monado"))
        })?;
    let manifest = dir.join("build/openxr_monado-dev.json");
    if manifest.is_file() {
        return Some(manifest);
    }
    let why = format!(
        "no OpenXR runtime at {} (bash scripts/setup-monado.sh builds Monado)",
        manifest.display()
    );
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "CI=true: {why}"
    );
    eprintln!("note: skipping the headset test: {why}");
    None
}

/// `fovea xr` on Monado's simulated headset, headless, with validation on.
fn xr(manifest: &Path, runtime_dir: &Path) -> Command {
    let mut c = fovea();
    c.arg("xr")
        .env("XR_RUNTIME_JSON", manifest)
        .env("XRT_COMPOSITOR_NULL", "1")
        .env("XRT_LOG", "error")
        .env("XDG_RUNTIME_DIR", runtime_dir)
        .env("FOVEA_VULKAN_VALIDATION", "1");
    c
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The share of pixels of two EXR files within 1e-3 of each other (relative, or 1e-4 absolute).
fn agreement(a: &Path, b: &Path) -> f64 {
    let (a, b) = (read_exr(a), read_exr(b));
    assert_eq!(a.len(), b.len());
    let within = a
        .iter()
        .zip(&b)
        .filter(|(p, q)| {
            (0..3).all(|c| {
                let d = (p[c] - q[c]).abs();
                d <= 1e-4 || d <= 1e-3 * p[c].abs().max(q[c].abs())
            })
        })
        .count();
    within as f64 / a.len() as f64
}

/// A session of [`FRAMES`] frames on each backend: every frame is submitted, validation is silent,
/// each eye has its own gaze, radii and history, and the eyes' images are `render --stereo-views` of
/// the poses the runtime gave (the same on the CPU; within 1e-3 on 99.9 % of pixels on lavapipe).
#[test]
fn a_headset_session_submits_every_frame_and_render_reproduces_its_eyes() {
    let Some(manifest) = monado_manifest() else {
        return;
    };
    for backend in ["cpu", "vulkan"] {
        let dir = temp_dir(backend);
        let runtime_dir = dir.join("xdg");
        std::fs::create_dir_all(&runtime_dir).unwrap();
        let record = dir.join("record");
        let stats = dir.join("xr.json");
        let frames = FRAMES.to_string();
        let out = xr(&manifest, &runtime_dir)
            .arg(cornell())
            .args(CAMERA)
            .args(["--backend", backend, "--size", "64x48", "--frames", &frames])
            .arg("--record")
            .arg(&record)
            .arg("--stats")
            .arg(&stats)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{backend}: {stderr}");
        assert!(
            stderr.contains("OpenXR runtime Monado") && stderr.contains("no eye-gaze extension"),
            "{backend}: {stderr}"
        );
        let s = json(&stats);
        assert_eq!(s["frames_submitted"], FRAMES, "{backend}: {s}");
        assert_eq!(s["ending"], "the session ended as asked", "{backend}");
        assert_eq!(s["backend"], backend);
        assert_eq!(
            s["validation_messages"],
            serde_json::json!([]),
            "{backend}: validation spoke"
        );
        let eyes = s["eyes"].as_array().unwrap();
        assert_eq!(eyes.len(), 2 * FRAMES as usize);
        // Each eye's history accumulates: only each eye's first frame starts one.
        let restarts: Vec<bool> = eyes
            .iter()
            .map(|e| e["history_restarted"].as_bool().unwrap())
            .collect();
        assert_eq!(
            restarts.iter().filter(|&&r| r).count(),
            2,
            "{backend}: {restarts:?}"
        );
        // The simulated headset's eyes are symmetric: each fixates its own centre.
        assert_eq!(eyes[0]["gaze"], serde_json::json!([32.0, 24.0]));
        let radius = eyes[0]["radii_px"][0].as_f64().unwrap();
        assert!(radius > 0.5 && radius < 32.0, "{backend}: radius {radius}");

        // The same poses and gaze, rendered offline.
        let rendered = dir.join("r.exr");
        let out = fovea()
            .arg("render")
            .arg(cornell())
            .args(CAMERA)
            .args([
                "--backend",
                backend,
                "--resolution",
                "64x48",
                "--history",
                "-q",
            ])
            .arg("--stereo-views")
            .arg(record.join("views.csv"))
            .arg("--gaze-trace")
            .arg(record.join("gaze.csv"))
            .arg("-o")
            .arg(&rendered)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{backend}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let mut worst: f64 = 1.0;
        for frame in 0..FRAMES {
            for eye in ["left", "right"] {
                let a = record.join(format!("f_{eye}_{frame:05}.exr"));
                let b = dir.join(format!("r_{eye}_{frame:05}.exr"));
                worst = worst.min(agreement(&a, &b));
            }
        }
        // What was compared is an image, not two black ones.
        let first = read_exr(&record.join("f_left_00000.exr"));
        let mean = first.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / first.len() as f32;
        assert!(
            mean > 0.01,
            "{backend}: the left eye's first image is black ({mean})"
        );
        let bound = if backend == "cpu" { 1.0 } else { 0.999 };
        assert!(
            worst >= bound,
            "{backend}: the headset's eyes and render --stereo-views agree on {:.3} % of pixels",
            100.0 * worst
        );
        eprintln!(
            "{backend}: {FRAMES} frames, median {:.0} ms a frame; every eye agrees with render on \
             >= {:.3} % of pixels",
            s["median_frame_ms"].as_f64().unwrap(),
            100.0 * worst
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// Without a runtime, `fovea xr` says how to get one, and nothing panics.
#[test]
fn without_a_runtime_the_error_names_xr_runtime_json() {
    let dir = temp_dir("none");
    let out = fovea()
        .arg("xr")
        .env("XR_RUNTIME_JSON", dir.join("missing.json"))
        .env("XDG_RUNTIME_DIR", &dir)
        .args(["--frames", "1"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        stderr.contains("XR_RUNTIME_JSON") && stderr.contains("setup-monado.sh"),
        "{stderr}"
    );
    // Options are checked before a runtime is looked for.
    let out = fovea()
        .arg("xr")
        .args(["--world-scale", "0"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("--world-scale"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// An eye tracker's datagrams of both eyes (`t,lx,ly,rx,ry`) fixate each eye on its own gaze.
#[test]
fn a_udp_tracker_of_both_eyes_fixates_each_eye_on_its_own() {
    let Some(manifest) = monado_manifest() else {
        return;
    };
    let dir = temp_dir("udp");
    let runtime_dir = dir.join("xdg");
    std::fs::create_dir_all(&runtime_dir).unwrap();
    let port = {
        let probe = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        probe.local_addr().unwrap().port()
    };
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let sender = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            let socket = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                let _ = socket.send_to(b"0,0.25,0.5,0.75,0.25\n", ("127.0.0.1", port));
                std::thread::sleep(std::time::Duration::from_millis(2));
            }
        })
    };
    let stats = dir.join("xr.json");
    let out = xr(&manifest, &runtime_dir)
        .arg(cornell())
        .args(CAMERA)
        .args(["--backend", "cpu", "--size", "64x48", "--frames", "8"])
        .args(["--gaze-source", &format!("udp:{port}")])
        .arg("--stats")
        .arg(&stats)
        .output()
        .unwrap();
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    sender.join().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = json(&stats);
    let eyes = s["eyes"].as_array().unwrap();
    let last = &eyes[eyes.len() - 2..];
    assert_eq!(last[0]["gaze"], serde_json::json!([16.0, 24.0]), "{s}");
    assert_eq!(last[1]["gaze"], serde_json::json!([48.0, 12.0]), "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}
