//! `fovea view` end to end: the real binary opens a window under Xvfb (`xvfb-run`), renders on lavapipe
//! or the CPU, presents through the swapchain with the Vulkan validation layer on, and is driven by
//! `--script`; the tests read its `--stats` JSON and screenshots. Bad input must fail before a window
//! opens, with a message that names the problem.
//!
//! The window tests need `xvfb-run` (scripts/setup.sh installs it) and a Vulkan driver; without them
//! they are skipped with a note, except under CI (`CI=true`), where that is a failure.
use std::io::Write;
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use serde_json::Value;

mod support;
use support::read_exr;

/// One Xvfb at a time (and the CPU is shared anyway).
static DISPLAY_LOCK: Mutex<()> = Mutex::new(());

const CAMERA: [&str; 6] = ["--eye", "0,1,3.9", "--target", "0,1,0", "--fov", "38"];

fn fovea() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fovea"))
}

fn cornell() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/cornell_box/CornellBox-Original.obj")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fovea-view-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// `xvfb-run -a fovea view` with validation on, or `None` (skip) where there is no xvfb-run outside CI.
fn view_under_xvfb() -> Option<Command> {
    let found = Command::new("xvfb-run")
        .arg("--help")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok();
    if !found {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "xvfb-run is missing (scripts/setup.sh installs xvfb)"
        );
        eprintln!("note: skipping a window test: xvfb-run is not installed");
        return None;
    }
    let mut c = Command::new("xvfb-run");
    c.args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(env!("CARGO_BIN_EXE_fovea"))
        .arg("view")
        .env("FOVEA_VULKAN_VALIDATION", "1")
        .env_remove("WAYLAND_DISPLAY");
    Some(c)
}

/// Runs a view command to completion (bounded), asserting success; returns its stats JSON.
fn run_ok(mut c: Command, stats: &Path) -> Value {
    let out = run_bounded(&mut c, Duration::from_secs(240));
    assert!(
        out.status.success(),
        "fovea view failed ({:?}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let json: Value = serde_json::from_str(&std::fs::read_to_string(stats).unwrap()).unwrap();
    let validation = json["validation_messages"].as_array().unwrap();
    assert!(validation.is_empty(), "validation: {validation:?}");
    assert_eq!(
        json["run"]["complete"], true,
        "a run that ended writes it whole"
    );
    json
}

/// Runs `c`, killing it after `limit`.
fn run_bounded(c: &mut Command, limit: Duration) -> Output {
    let mut child = c
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!(
                "fovea view ran past {limit:?}:\n{}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn frames(json: &Value) -> &Vec<Value> {
    json["frames"].as_array().unwrap()
}

fn gaze(frame: &Value) -> [f64; 2] {
    let g = frame["gaze"].as_array().unwrap();
    [g[0].as_f64().unwrap(), g[1].as_f64().unwrap()]
}

fn mse(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    assert_eq!(a.len(), b.len());
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|c| f64::from(p[c] - q[c]).powi(2)).sum::<f64>())
        .sum();
    sum / (3 * a.len()) as f64
}

#[test]
fn the_window_presents_frames_whose_fovea_sits_at_the_scripted_gaze() {
    let _guard = DISPLAY_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut c) = view_under_xvfb() else {
        return;
    };
    let dir = temp_dir("gaze");
    let script = write(&dir, "s.txt", "0 gaze 0.25 0.5\n");
    let stats = dir.join("stats.json");
    c.arg(cornell())
        .args(CAMERA)
        .args([
            "--backend",
            "vulkan",
            "--size",
            "160x120",
            "--radii",
            "10,30",
        ])
        .args(["--budget-ms", "0", "--exit-after-frames", "5"])
        .args(["--screenshot-at-frame", "3", "--overlay", "-q"])
        .arg("--script")
        .arg(&script)
        .arg("--screenshot-dir")
        .arg(dir.join("shots"))
        .arg("--stats")
        .arg(&stats);
    let json = run_ok(c, &stats);
    assert_eq!(json["summary"]["frames"], 5);
    assert_eq!(json["summary"]["presented"], 5, "every frame is presented");
    assert_eq!(json["run"]["backend"], "vulkan");
    // The run records the traversal it was asked for and the warnings it printed (none here).
    assert_eq!(json["run"]["traversal"], "auto");
    assert_eq!(json["run"]["warnings"], serde_json::json!([]));
    for f in frames(&json) {
        assert_eq!(gaze(f), [40.0, 60.0]);
        assert_eq!(f["window"], serde_json::json!([160, 120]));
    }
    // The screenshot: the files `render` writes, centred on the gaze.
    let shot = dir.join("shots/fovea_view_00003");
    for ext in ["png", "exr", "json"] {
        assert!(shot.with_extension(ext).is_file(), "{ext}");
    }
    let meta: Value =
        serde_json::from_str(&std::fs::read_to_string(shot.with_extension("json")).unwrap())
            .unwrap();
    assert_eq!(meta["foveation"]["gaze"], serde_json::json!([40.0, 60.0]));
    let regions = image::open(dir.join("shots/fovea_view_00003_regions.png"))
        .unwrap()
        .to_rgb8();
    let at = |x: u32, y: u32| regions.get_pixel(x, y).0.map(i32::from);
    let fovea = at(40, 60);
    assert!(
        fovea[1] > fovea[0] && fovea[1] > fovea[2],
        "green at the gaze: {fovea:?}"
    );
    let far = at(150, 110);
    assert!(
        far[2] > far[0] && far[2] > far[1],
        "blue far from it: {far:?}"
    );
    // Accumulation while nothing moves.
    let counts: Vec<u64> = frames(&json)
        .iter()
        .map(|f| f["accumulated_frames"].as_u64().unwrap())
        .collect();
    assert_eq!(counts, [1, 2, 3, 4, 5]);
}

/// A gaze that moves every frame (saccades across the window, then a tracker's jitter) keeps the
/// history on both backends: every frame adds to it (`accumulated_frames` counts 1, 2, 3, ...). On
/// Vulkan the history used to restart whenever the new gaze needed more blocks or cells than the
/// buffers had (issue 50).
#[test]
fn a_moving_gaze_keeps_the_history_on_both_backends() {
    let _guard = DISPLAY_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let dir = temp_dir("moving-gaze");
    let mut lines = String::new();
    let gazes = [
        (0.5, 0.5),
        (0.2, 0.3),
        (0.8, 0.7),
        (0.1, 0.9),
        (0.9, 0.1),
        (0.5, 0.5),
        (0.51, 0.49),
        (0.49, 0.5),
        (0.52, 0.51),
        (0.5, 0.52),
    ];
    for (k, (x, y)) in gazes.iter().enumerate() {
        lines += &format!("{k} gaze {x} {y}\n");
    }
    let script = write(&dir, "s.txt", &lines);
    for backend in ["vulkan", "cpu"] {
        let Some(mut c) = view_under_xvfb() else {
            return;
        };
        let stats = dir.join(format!("{backend}.json"));
        c.arg(cornell())
            .args(CAMERA)
            .args(["--backend", backend, "--size", "96x64", "--radii", "6,18"])
            .args(["--spp", "4,2,1", "--budget-ms", "0", "-q"])
            .args(["--exit-after-frames", &gazes.len().to_string()])
            .arg("--script")
            .arg(&script)
            .arg("--stats")
            .arg(&stats);
        let json = run_ok(c, &stats);
        let f = frames(&json);
        let moved = f.windows(2).filter(|w| gaze(&w[0]) != gaze(&w[1])).count();
        assert!(moved >= gazes.len() - 2, "{backend}: the gaze must move");
        let counts: Vec<u64> = f
            .iter()
            .map(|f| f["accumulated_frames"].as_u64().unwrap())
            .collect();
        let expected: Vec<u64> = (1..=gazes.len() as u64).collect();
        assert_eq!(counts, expected, "{backend}");
    }
}

#[test]
fn the_uniform_toggle_changes_the_samples_per_frame_by_the_sample_ratio() {
    let _guard = DISPLAY_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut c) = view_under_xvfb() else {
        return;
    };
    let dir = temp_dir("uniform");
    let script = write(&dir, "s.txt", "2 press U\n3 press N\n");
    let stats = dir.join("stats.json");
    // The CPU backend: its frames are uploaded and presented through the same swapchain.
    c.arg(cornell())
        .args(CAMERA)
        .args(["--backend", "cpu", "--size", "160x120", "--radii", "10,30"])
        .args([
            "--spp",
            "8,4,2",
            "--budget-ms",
            "0",
            "--exit-after-frames",
            "5",
            "-q",
        ])
        .arg("--script")
        .arg(&script)
        .arg("--stats")
        .arg(&stats);
    let json = run_ok(c, &stats);
    assert_eq!(json["run"]["backend"], "cpu");
    let f = frames(&json);
    let samples = |i: usize| f[i]["primary_samples"].as_u64().unwrap();
    let foveation = fovea_core::foveation::regions::FoveationParams {
        gaze: [80.0, 60.0],
        radius_fovea: 10.0,
        radius_intermediate: 30.0,
        spp: [8, 4, 2, 0],
        block_size: [1, 2, 4, 0],
    };
    let expected: u64 = fovea_core::foveation::count_samples(160, 120, &foveation)
        .iter()
        .sum();
    assert_eq!(samples(0), expected);
    assert_eq!(samples(1), expected);
    assert_eq!(samples(2), 160 * 120 * 8, "uniform: 8 spp everywhere");
    assert_eq!(f[2]["uniform"], true);
    assert_eq!(
        f[2]["accumulated_frames"], 3,
        "the toggle changes the next samples, not the history"
    );
    let ratio = samples(2) as f64 / samples(0) as f64;
    assert!(ratio > 5.0, "uniform / foveated = {ratio}");
    // N turns the denoiser on: its passes run after the history's, which it does not reset.
    let ran = |i: usize, pass: &str| f[i]["pass_ms"][pass].as_f64().is_some();
    assert!(!ran(2, "denoise_atrous"), "{}", f[2]["pass_ms"]);
    assert!(
        ran(3, "denoise_atrous") && ran(3, "denoise_output"),
        "{}",
        f[3]["pass_ms"]
    );
    assert_eq!(f[3]["accumulated_frames"], 4);
}

#[test]
fn accumulation_error_falls_like_one_over_n_and_a_camera_move_keeps_the_history() {
    let _guard = DISPLAY_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut c) = view_under_xvfb() else {
        return;
    };
    let dir = temp_dir("accumulate");
    // The long render: 2048 spp, the same camera.
    let reference = dir.join("ref.exr");
    let out = fovea()
        .arg("render")
        .arg(cornell())
        .args(CAMERA)
        .args(["--backend", "cpu", "--resolution", "64x48", "--uniform"])
        .args(["--spp", "2048,2048,2048", "--seed", "7", "-q", "-o"])
        .arg(&reference)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let script = write(&dir, "s.txt", "16 press W\n");
    let stats = dir.join("stats.json");
    c.arg(cornell())
        .args(CAMERA)
        .args(["--backend", "vulkan", "--size", "64x48", "--uniform"])
        .args([
            "--spp",
            "2,2,2",
            "--budget-ms",
            "0",
            "--exit-after-frames",
            "18",
            "-q",
        ])
        .args(["--screenshot-at-frame", "0", "--screenshot-at-frame", "3"])
        .args(["--screenshot-at-frame", "15"])
        .arg("--script")
        .arg(&script)
        .arg("--screenshot-dir")
        .arg(dir.join("shots"))
        .arg("--stats")
        .arg(&stats);
    let json = run_ok(c, &stats);
    let f = frames(&json);
    assert_eq!(f[15]["accumulated_frames"], 16);
    assert_eq!(
        f[16]["accumulated_frames"], 17,
        "moving the camera reprojects the history instead of restarting it"
    );
    let reference = read_exr(&reference);
    let err = |frame: u32| {
        mse(
            &read_exr(&dir.join(format!("shots/fovea_view_{frame:05}.exr"))),
            &reference,
        )
    };
    let (e1, e4, e16) = (err(0), err(3), err(15));
    eprintln!("accumulated error against 2048 spp: N=1 {e1:.3e}, N=4 {e4:.3e}, N=16 {e16:.3e}");
    // Independent frames: the variance of their mean falls as 1/N (4x per step; 2.5x allows for noise).
    assert!(e1 / e4 > 2.5, "N=1 {e1}, N=4 {e4}");
    assert!(e4 / e16 > 2.5, "N=4 {e4}, N=16 {e16}");
}

#[test]
fn an_eye_tracker_on_udp_moves_the_fovea_and_bad_datagrams_are_dropped() {
    let _guard = DISPLAY_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut c) = view_under_xvfb() else {
        return;
    };
    let dir = temp_dir("udp");
    let port = {
        let probe = UdpSocket::bind("127.0.0.1:0").unwrap();
        probe.local_addr().unwrap().port()
    };
    let stats = dir.join("stats.json");
    c.arg(cornell())
        .args(CAMERA)
        .args([
            "--backend",
            "vulkan",
            "--size",
            "160x120",
            "--radii",
            "10,30",
        ])
        .args(["--budget-ms", "0", "--exit-after-frames", "30", "-q"])
        .arg("--gaze-source")
        .arg(format!("udp:{port}"))
        .arg("--stats")
        .arg(&stats);
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let sender = {
        let done = done.clone();
        std::thread::spawn(move || {
            let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
            let target = ("127.0.0.1", port);
            let start = Instant::now();
            let mut sent = 0u32;
            // Bounded: until the viewer exits, at most 60 s, 100 datagrams a second.
            while !done.load(std::sync::atomic::Ordering::Relaxed)
                && start.elapsed() < Duration::from_secs(60)
            {
                let t = start.elapsed().as_secs_f64();
                if sent.is_multiple_of(20) {
                    let _ = socket.send_to(b"not a gaze sample", target);
                }
                let _ = socket.send_to(format!("{t:.3},0.75,0.25\n").as_bytes(), target);
                sent += 1;
                std::thread::sleep(Duration::from_millis(10));
            }
        })
    };
    let json = run_ok(c, &stats);
    done.store(true, std::sync::atomic::Ordering::Relaxed);
    sender.join().unwrap();
    let f = frames(&json);
    assert_eq!(gaze(f.last().unwrap()), [120.0, 30.0], "the tracker's gaze");
    assert!(json["run"]["malformed_gaze_datagrams"].as_u64().unwrap() >= 1);
    assert!(
        f.iter().any(|r| r["latency_ms"].is_number()),
        "latency is measured for new samples"
    );
}

#[test]
fn resize_minimise_restore_and_close_do_not_crash() {
    let _guard = DISPLAY_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut c) = view_under_xvfb() else {
        return;
    };
    let dir = temp_dir("resize");
    let script = write(
        &dir,
        "s.txt",
        "1 mouse 30 20\n2 resize 200 150\n4 minimize\n6 restore\n7 down D\n8 up D\n9 close\n",
    );
    let stats = dir.join("stats.json");
    c.arg(cornell())
        .args(CAMERA)
        .args(["--backend", "vulkan", "--size", "160x120", "-q"])
        .arg("--script")
        .arg(&script)
        .arg("--stats")
        .arg(&stats);
    let json = run_ok(c, &stats);
    let f = frames(&json);
    let numbers: Vec<u64> = f.iter().map(|r| r["frame"].as_u64().unwrap()).collect();
    assert!(
        !numbers.contains(&4) && !numbers.contains(&5),
        "minimised: {numbers:?}"
    );
    assert!(
        numbers.contains(&6) && !numbers.contains(&9),
        "restored, then closed: {numbers:?}"
    );
    let last = f.last().unwrap();
    assert_eq!(last["window"], serde_json::json!([200, 150]));
    assert_eq!(gaze(last), [30.0, 20.0], "the mouse is the default gaze");
    assert_eq!(json["summary"]["presented"], json["summary"]["frames"]);
}

/// A `fovea view` that must fail before opening a window; returns its stderr.
fn fails(args: &[&str], extra: impl FnOnce(&mut Command)) -> String {
    let mut c = fovea();
    c.arg("view").args(args);
    extra(&mut c);
    let out = run_bounded(&mut c, Duration::from_secs(60));
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    // 1: fovea's own errors; 2: clap's (a value that does not parse).
    assert!(matches!(out.status.code(), Some(1 | 2)), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

#[test]
fn bad_input_fails_with_a_clear_message() {
    let dir = temp_dir("bad");
    // No display.
    let e = fails(&["--exit-after-frames", "1"], |c| {
        c.env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY");
    });
    assert!(e.contains("DISPLAY") && e.contains("xvfb-run"), "{e}");
    // A script naming an unknown key.
    let script = write(&dir, "bad.txt", "# keys\n0 press F9\n");
    let e = fails(&["--script", script.to_str().unwrap()], |_| {});
    assert!(
        e.contains("line 2") && e.contains("unknown key 'F9'"),
        "{e}"
    );
    // A malformed gaze trace line.
    let trace = write(&dir, "trace.csv", "t,x,y\n0.0,0.5,0.5\n0.1,zero,0.5\n");
    let e = fails(&["--gaze-trace", trace.to_str().unwrap()], |_| {});
    assert!(e.contains("line 3") && e.contains("--gaze-trace"), "{e}");
    // A port in use.
    let taken = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port();
    let e = fails(&["--gaze-source", &format!("udp:{port}")], |_| {});
    assert!(e.contains("in use"), "{e}");
    // An unknown gaze source and a trace without a file.
    let e = fails(&["--gaze-source", "tobii"], |_| {});
    assert!(e.contains("mouse, udp:PORT or trace"), "{e}");
    let e = fails(&["--gaze-source", "trace"], |_| {});
    assert!(e.contains("--gaze-trace"), "{e}");
    // A screenshot folder through a file, and a screenshot after the last frame, refused at start.
    let shots = dir.join("trace.csv/shots");
    let e = fails(&["--screenshot-dir", shots.to_str().unwrap()], |_| {});
    assert!(
        e.contains("--screenshot-dir") && e.contains("is a file"),
        "{e}"
    );
    // A folder that takes no files (a probe tells, not the permission bits).
    let e = fails(&["--screenshot-dir", "/proc/fovea-shots"], |_| {});
    assert!(
        e.contains("--screenshot-dir") && e.contains("cannot write into the folder '/proc'"),
        "{e}"
    );
    let e = fails(
        &["--exit-after-frames", "5", "--screenshot-at-frame", "9"],
        |_| {},
    );
    assert!(e.contains("9 comes after --exit-after-frames 5"), "{e}");
    // Nothing half-written.
    let mut leftovers = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect::<Vec<_>>();
    leftovers.sort();
    assert_eq!(leftovers, ["bad.txt", "trace.csv"]);
    let _ = std::io::stderr().flush();
}

/// A machine whose Vulkan loader finds no driver: the view says so and exits 1 (no panic).
#[test]
fn no_vulkan_driver_is_a_clear_error() {
    let _guard = DISPLAY_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut c) = view_under_xvfb() else {
        return;
    };
    c.arg(cornell())
        .args([
            "--backend",
            "cpu",
            "--size",
            "64x48",
            "--exit-after-frames",
            "1",
        ])
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json");
    let out = run_bounded(&mut c, Duration::from_secs(120));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("needs a Vulkan driver"), "{stderr}");
}

/// `--stats` is written every few seconds while the view runs (`"complete": false`), so that a run
/// ended by SIGTERM, which the view cannot catch, keeps its figures up to the last snapshot.
#[test]
fn a_terminated_view_keeps_its_last_stats_snapshot() {
    let _guard = DISPLAY_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut c) = view_under_xvfb() else {
        return;
    };
    let dir = temp_dir("snapshot");
    let stats = dir.join("stats.json");
    c.arg(cornell())
        .args(CAMERA)
        .args(["--backend", "cpu", "--size", "160x120", "-q"])
        .args(["--budget-ms", "0", "--exit-after-frames", "1000000"])
        .arg("--stats")
        .arg(&stats)
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    let mut child = c.spawn().unwrap();
    let read =
        || -> Option<Value> { serde_json::from_str(&std::fs::read_to_string(&stats).ok()?).ok() };
    // The first frame's snapshot, then one at least 5 s later with more frames.
    let start = Instant::now();
    let mut first: Option<usize> = None;
    let mut second: Option<Value> = None;
    while start.elapsed() < Duration::from_secs(120) && second.is_none() {
        if let Some(v) = read() {
            let n = frames(&v).len();
            match first {
                None => first = Some(n),
                Some(f) if n > f => second = Some(v),
                _ => {}
            }
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    // SIGTERM to the fovea process itself (xvfb-run is its parent).
    let pid = std::fs::read_dir("/proc")
        .unwrap()
        .filter_map(|e| e.ok())
        .find(|e| {
            std::fs::read(e.path().join("cmdline")).is_ok_and(|cmd| {
                let args: Vec<&[u8]> = cmd.split(|&b| b == 0).collect();
                args.first().is_some_and(|a| a.ends_with(b"fovea"))
                    && args
                        .iter()
                        .any(|a| *a == stats.to_str().unwrap().as_bytes())
            })
        })
        .map(|e| e.file_name().to_string_lossy().into_owned());
    if let Some(pid) = &pid {
        let _ = Command::new("kill").args(["-TERM", pid]).status();
    }
    let _ = child.kill();
    let _ = child.wait();
    let second = second.expect("a second --stats snapshot within 2 minutes");
    assert!(pid.is_some(), "the fovea process was found");
    assert_eq!(second["run"]["complete"], false, "a snapshot is marked so");
    let last = read().expect("the last snapshot is a whole JSON file");
    assert_eq!(
        last["run"]["complete"], false,
        "the run never ended normally"
    );
    assert!(frames(&last).len() >= frames(&second).len());
    let _ = std::fs::remove_dir_all(&dir);
}
