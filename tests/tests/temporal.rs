//! Temporal reuse end to end (`fovea_core::temporal`, the CPU's `TemporalHistory`, the kernel's
//! `gbuffer`/`temporal`/`resolve_history`): history that an eye tracker's gaze does not erase, that
//! follows the camera, that bad samples never enter, and that is the same on the CPU and lavapipe.
//!
//! The Cornell box at 96 × 72 with the paper's 32/16/8 samples; errors are relMSE against a uniform
//! 1024-spp render of the same camera (`-- --nocapture` prints them).
use fovea_core::camera::Camera;
use fovea_core::foveation::fill::FILL_BILINEAR;
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::integrator::FrameParams;
use fovea_core::math::color::luminance;
use fovea_core::temporal::{HistoryTexel, TemporalParams};
use fovea_cpu::{render_frame, render_frame_with_history, FrameImage, TemporalHistory};
use fovea_scene::environment::Environment;
use fovea_scene::pack::PackedScene;
use fovea_tests::*;
use glam::Vec3;

const W: u32 = 96;
const H: u32 = 72;
const RADII: [f32; 2] = [16.0, 30.0];
const CENTRE: [f32; 2] = [48.0, 36.0];

fn scene() -> PackedScene {
    load_packed(&cornell_box_path(), &Environment::None)
}

fn frame(camera: Camera, gaze: [f32; 2], spp: [u32; 3], index: u32) -> FrameParams {
    let mut foveation = FoveationParams::paper(gaze, RADII[0], RADII[1]);
    foveation.spp = [spp[0], spp[1], spp[2], 0];
    let mut f = frame_params(camera, foveation, W, H, 7);
    f.frame_index = index;
    f
}

/// A converged render of `camera` (uniform, 1024 spp).
fn reference(scene: &PackedScene, camera: Camera) -> FrameImage {
    let mut f = frame_params(camera, FoveationParams::uniform(1024), W, H, 99);
    f.frame_index = 1 << 20;
    render(scene, &f).0
}

/// A deterministic eye-tracker gaze: the fixation plus noise of about 2.5 px RMS per axis, a slow drift
/// and a 5 px microsaccade every 8 frames (0.15 degrees RMS and 0.5 degrees at 28 px per degree,
/// scaled to this small image).
fn tracker_gaze(frame: u32) -> [f32; 2] {
    Tracker {
        centre: CENTRE,
        rms_px: 2.5,
        drift_px: 0.2,
        saccade_px: 5.0,
        saccade_every: 8,
    }
    .gaze(frame)
}

/// An eye tracker's gaze on a fixation: uniform noise of `rms_px` RMS per axis, a drift of `drift_px`
/// per frame that a microsaccade of `saccade_px` undoes and redoes every `saccade_every` frames.
struct Tracker {
    centre: [f32; 2],
    rms_px: f32,
    drift_px: f32,
    saccade_px: f32,
    saccade_every: u32,
}

impl Tracker {
    fn gaze(&self, frame: u32) -> [f32; 2] {
        let hash = |k: u32| {
            let mut x = k.wrapping_mul(0x9E37_79B9) ^ 0x85EB_CA6B;
            x ^= x >> 15;
            x = x.wrapping_mul(0x2C1B_3C6D);
            x ^= x >> 12;
            (x as f32 / u32::MAX as f32) * 2.0 - 1.0
        };
        // Uniform noise in [-1, 1] has RMS 1/sqrt(3).
        let amplitude = self.rms_px * 3f32.sqrt();
        let noise = [hash(2 * frame) * amplitude, hash(2 * frame + 1) * amplitude];
        let drift = self.drift_px * (frame % self.saccade_every) as f32;
        let saccade = if (frame / self.saccade_every) % 2 == 1 {
            self.saccade_px
        } else {
            0.0
        };
        [
            self.centre[0] + noise[0] + drift + saccade,
            self.centre[1] + noise[1] - 0.5 * drift,
        ]
    }
}

fn distance_to_centre(x: u32, y: u32) -> f32 {
    ((x as f32 + 0.5 - CENTRE[0]).powi(2) + (y as f32 + 0.5 - CENTRE[1]).powi(2)).sqrt()
}

fn fovea(x: u32, y: u32) -> bool {
    distance_to_centre(x, y) < RADII[0] - 8.0
}

fn periphery(x: u32, y: u32) -> bool {
    distance_to_centre(x, y) > RADII[1] + 10.0
}

/// `frames` frames of the still camera with `gaze(frame)`, through the history: the displayed images.
fn run_with_history(
    scene: &PackedScene,
    frames: u32,
    gaze: impl Fn(u32) -> [f32; 2],
) -> Vec<FrameImage> {
    run_with_history_seeded(scene, frames, gaze, 7)
}

/// [`run_with_history`] with the random numbers of `seed`.
fn run_with_history_seeded(
    scene: &PackedScene,
    frames: u32,
    gaze: impl Fn(u32) -> [f32; 2],
    seed: u32,
) -> Vec<FrameImage> {
    let camera = cornell_camera(W, H);
    let mut history = TemporalHistory::new();
    (0..frames)
        .map(|i| {
            let mut f = frame(camera, gaze(i), [32, 16, 8], i);
            f.seed = seed;
            render_frame_with_history(&scene.view(), &f, FILL_BILINEAR, &mut history, &|_| {}).0
        })
        .collect()
}

/// Mean over the selected pixels of each pixel's luminance variance across `images`.
fn flicker(images: &[FrameImage], keep: impl Fn(u32, u32) -> bool) -> f64 {
    let mut total = 0.0f64;
    let mut n = 0u64;
    let (w, h) = (images[0].width, images[0].height);
    for y in 0..h {
        for x in 0..w {
            if !keep(x, y) {
                continue;
            }
            let i = (y * w + x) as usize;
            let l: Vec<f64> = images
                .iter()
                .map(|im| luminance(Vec3::from_slice(&im.pixels[i][..3])) as f64)
                .collect();
            let mean = l.iter().sum::<f64>() / l.len() as f64;
            total += l.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / l.len() as f64;
            n += 1;
        }
    }
    total / n as f64
}

#[test]
fn a_jittering_gaze_converges_like_a_still_one() {
    let scene = scene();
    let reference = reference(&scene, cornell_camera(W, H));
    const FRAMES: u32 = 24;
    // Different random numbers on each side: with the same ones, the pixels that stay in one region
    // would draw the same samples whatever the gaze did, and the comparison would hold by construction.
    let still = run_with_history_seeded(&scene, FRAMES, |_| CENTRE, 7);
    let tracked = run_with_history_seeded(&scene, FRAMES, tracker_gaze, 8);
    // Without history (what the view did before: every gaze move restarted the mean) each frame is one
    // frame of noise.
    let camera = cornell_camera(W, H);
    let single: Vec<FrameImage> = (FRAMES - 8..FRAMES)
        .map(|i| render(&scene, &frame(camera, tracker_gaze(i), [32, 16, 8], i)).0)
        .collect();
    let last = (FRAMES - 1) as usize;
    let (still_f, tracked_f, single_f) = (
        rel_mse_where(&still[last], &reference, fovea),
        rel_mse_where(&tracked[last], &reference, fovea),
        rel_mse_where(&single[7], &reference, fovea),
    );
    let (still_p, tracked_p, single_p) = (
        rel_mse_where(&still[last], &reference, periphery),
        rel_mse_where(&tracked[last], &reference, periphery),
        rel_mse_where(&single[7], &reference, periphery),
    );
    // The region borders, which the tracker's gaze moves over: the pixels whose region (and so
    // history) changes while it jitters. Away from the ceiling light, whose blur in the coarse
    // blocks around it (radiance 17 against the walls' 0.5) would outweigh everything else.
    let borders = |x: u32, y: u32| {
        let d = distance_to_centre(x, y);
        y >= 16 && ((d - RADII[0]).abs() < 8.0 || (d - RADII[1]).abs() < 8.0)
    };
    let (still_a, tracked_a) = (
        rel_mse_where(&still[last], &reference, borders),
        rel_mse_where(&tracked[last], &reference, borders),
    );
    let flicker_history = flicker(&tracked[last - 7..], periphery);
    let flicker_single = flicker(&single, periphery);
    eprintln!(
        "fovea relMSE after {FRAMES} frames: still {still_f:.3e}, tracker {tracked_f:.3e}, no history \
         {single_f:.3e}; periphery: still {still_p:.3e}, tracker {tracked_p:.3e}, no history \
         {single_p:.3e}; region borders: still {still_a:.3e}, tracker {tracked_a:.3e}; periphery \
         flicker (luminance variance over 8 frames): history {flicker_history:.3e}, no history \
         {flicker_single:.3e}"
    );
    assert!(
        tracked_f < 1.5 * still_f,
        "fovea {tracked_f} vs still {still_f}"
    );
    assert!(
        tracked_p < 2.0 * still_p,
        "periphery {tracked_p} vs still {still_p}"
    );
    assert!(
        tracked_a < 1.5 * still_a,
        "region borders {tracked_a} vs still {still_a}"
    );
    assert!(
        single_f > 8.0 * tracked_f,
        "no history {single_f} vs {tracked_f}"
    );
    assert!(
        flicker_single > 10.0 * flicker_history,
        "flicker {flicker_single} vs {flicker_history}"
    );
}

#[test]
fn the_fovea_leaves_no_blur_trail_and_keeps_its_detail_when_it_moves_on() {
    // 12 frames gazing at the left, then 12 at the right: the left keeps its fovea-quality history,
    // the right, coarse until the gaze arrives, loses its coarse history at once.
    let scene = scene();
    let reference = reference(&scene, cornell_camera(W, H));
    let left = [24.0f32, 36.0];
    let right = [72.0f32, 36.0];
    let images = run_with_history(&scene, 24, |i| if i < 12 { left } else { right });
    let near = |g: [f32; 2]| {
        move |x: u32, y: u32| {
            ((x as f32 + 0.5 - g[0]).powi(2) + (y as f32 + 0.5 - g[1]).powi(2)).sqrt() < 6.0
        }
    };
    let left_before = rel_mse_where(&images[11], &reference, near(left));
    let left_after = rel_mse_where(&images[23], &reference, near(left));
    let right_first = rel_mse_where(&images[12], &reference, near(right));
    // One fovea frame alone, for comparison.
    let camera = cornell_camera(W, H);
    let one = render(&scene, &frame(camera, right, [32, 16, 8], 12)).0;
    let right_one = rel_mse_where(&one, &reference, near(right));
    eprintln!(
        "left fovea: {left_before:.3e} when left, {left_after:.3e} after 12 periphery frames; right: \
         first fovea frame {right_first:.3e}, the same frame without history {right_one:.3e}"
    );
    assert!(
        left_after < 1.3 * left_before,
        "{left_after} vs {left_before}"
    );
    // The fovea arriving keeps what the periphery left and refines it: better than its first frame
    // alone.
    assert!(
        right_first < 0.95 * right_one,
        "{right_first} vs {right_one}"
    );
}

#[test]
fn history_follows_a_panning_camera() {
    let scene = scene();
    let camera_at = |i: u32| {
        let eye = Vec3::new(0.02 * i as f32, 1.0, 3.9);
        Camera::look_at(
            eye,
            eye - Vec3::new(0.0, 0.0, 3.9),
            Vec3::Y,
            38f32.to_radians(),
            W as f32 / H as f32,
        )
    };
    const FRAMES: u32 = 12;
    let last = FRAMES - 1;
    let reference = reference(&scene, camera_at(last));
    let mut history = TemporalHistory::new();
    let mut with_reuse = None;
    for i in 0..FRAMES {
        let f = frame(camera_at(i), CENTRE, [32, 16, 8], i);
        with_reuse = Some(
            render_frame_with_history(&scene.view(), &f, FILL_BILINEAR, &mut history, &|_| {}).0,
        );
    }
    let with_reuse = with_reuse.unwrap();
    let without = render(&scene, &frame(camera_at(last), CENTRE, [32, 16, 8], last)).0;
    // The periphery's blocks blur the box's edges against the black outside, an error both share;
    // the fovea (full resolution) shows the noise that reuse removes.
    let (e_reuse, e_without) = (
        rel_mse_where(&with_reuse, &reference, fovea),
        rel_mse_where(&without, &reference, fovea),
    );
    let all = |_: u32, _: u32| true;
    let (a_reuse, a_without) = (
        rel_mse_where(&with_reuse, &reference, all),
        rel_mse_where(&without, &reference, all),
    );
    // Frames the pixel's history was carried through (its fill average counts every frame; its own
    // samples' count only those that brought one, every other frame in the periphery).
    let frames: Vec<f32> = history
        .texels()
        .iter()
        .map(HistoryTexel::fill_frames)
        .collect();
    let followed = frames.iter().filter(|&&n| n >= 8.0).count() as f64 / frames.len() as f64;
    eprintln!(
        "panning camera, frame {last}: fovea relMSE with reuse {e_reuse:.3e}, without {e_without:.3e} \
         ({:.1}x); whole image {a_reuse:.3e} vs {a_without:.3e}; {:.1} % of pixels kept 8 or more \
         frames of history",
        e_without / e_reuse,
        followed * 100.0
    );
    assert!(e_without > 3.0 * e_reuse, "{e_without} vs {e_reuse}");
    assert!(followed > 0.8, "{followed}");
}

/// The ring's and the periphery's history follows the camera too, where a pixel's own samples come
/// one block's share at a time and the clamp box is built from coarse fills (issue 50): Lost Empire at
/// 160 × 90 in daylight, the camera panning 0.15 units a frame (about a pixel), 8/4/16 samples with
/// the fovea a corner of the image's middle, scored outside the fovea against 128 spp references.
#[test]
fn the_coarse_regions_history_follows_a_panning_camera() {
    let (w, h) = (160u32, 90u32);
    let scene = load_packed(
        &bundled_scenes().join("lost_empire/lost_empire.obj"),
        &Environment::Constant([1.0, 1.0, 1.0]),
    );
    let centre = [80.0f32, 45.0];
    let camera_at = |i: u32| {
        let mut c = lost_empire_camera(60f32.to_radians(), w as f32 / h as f32);
        c.position[0] += 0.15 * i as f32;
        c
    };
    let frame_at = |i: u32| {
        let mut foveation = FoveationParams::paper(centre, 18.0, 60.0);
        foveation.spp = [8, 4, 16, 0];
        let mut f = frame_params(camera_at(i), foveation, w, h, 7);
        f.frame_index = i;
        f
    };
    let outside_fovea = |x: u32, y: u32| {
        ((x as f32 + 0.5 - centre[0]).powi(2) + (y as f32 + 0.5 - centre[1]).powi(2)).sqrt() > 20.0
    };
    const FRAMES: u32 = 16;
    const SCORED: u32 = 4;
    let mut history = TemporalHistory::new();
    let (mut with, mut without) = (0.0, 0.0);
    for i in 0..FRAMES {
        let f = frame_at(i);
        let shown =
            render_frame_with_history(&scene.view(), &f, FILL_BILINEAR, &mut history, &|_| {}).0;
        if i >= FRAMES - SCORED {
            let mut r = frame_params(camera_at(i), FoveationParams::uniform(128), w, h, 99);
            r.frame_index = 1 << 20;
            let reference = render(&scene, &r).0;
            with += rel_mse_where(&shown, &reference, outside_fovea);
            without += rel_mse_where(&render(&scene, &f).0, &reference, outside_fovea);
        }
    }
    eprintln!(
        "panning camera, frames {}-{}: relMSE outside the fovea with history {:.4}, without {:.4} \
         ({:.2}x)",
        FRAMES - SCORED,
        FRAMES - 1,
        with / SCORED as f64,
        without / SCORED as f64,
        without / with
    );
    // Measured 4.16x (release, 2026-12-04); a history that restarted each frame would be 1x.
    assert!(without > 3.0 * with, "{without} vs {with}");
}

#[test]
fn bad_samples_never_enter_the_history_on_the_cpu() {
    let scene = scene();
    let camera = cornell_camera(W, H);
    let mut history = TemporalHistory::new();
    let f0 = frame(camera, CENTRE, [4, 2, 1], 0);
    let (filled, _) = render_frame(&scene.view(), &f0, FILL_BILINEAR, &|_| {});
    history.accumulate(
        &scene.view(),
        &f0,
        &history.params_for(&f0, FILL_BILINEAR),
        &filled,
    );
    let before: Vec<HistoryTexel> = history.texels().to_vec();
    let f1 = frame(camera, CENTRE, [4, 2, 1], 1);
    let (mut bad, _) = render_frame(&scene.view(), &f1, FILL_BILINEAR, &|_| {});
    let poisoned = [
        (10usize, f32::NAN),
        (500, f32::INFINITY),
        (2000, f32::NEG_INFINITY),
        (3000, 1.0e30),
    ];
    for (i, v) in poisoned {
        bad.pixels[i] = [v, v, v, 1.0];
    }
    let params: TemporalParams = history.params_for(&f1, FILL_BILINEAR);
    history.accumulate(&scene.view(), &f1, &params, &bad);
    for (i, t) in history.texels().iter().enumerate() {
        assert!(
            t.mean.iter().chain(&t.moments).all(|v| v.is_finite()),
            "pixel {i}: {t:?}"
        );
    }
    // The non-finite ones kept their history; the huge one was clamped.
    for i in [10usize, 500, 2000] {
        assert_eq!(history.texels()[i], before[i], "pixel {i}");
    }
    assert!(history.texels()[3000].mean[0] <= 1.0e6);
}

#[test]
fn cpu_and_lavapipe_histories_agree_after_16_frames() {
    let Some(mut ctx) = vulkan_context_or_skip("the temporal cross-backend test") else {
        return;
    };
    let scene = scene();
    let gpu_scene = ctx.upload_scene(&scene).expect("upload");
    let camera_at = |i: u32| {
        let eye = Vec3::new(0.015 * i as f32, 1.0 + 0.005 * i as f32, 3.9);
        Camera::look_at(
            eye,
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::Y,
            38f32.to_radians(),
            W as f32 / H as f32,
        )
    };
    let mut history = TemporalHistory::new();
    let (mut cpu, mut gpu) = (None, None);
    for i in 0..16 {
        // A jittered gaze and, from frame 6 on, a moving camera; still again for the last three.
        let camera = camera_at(i.clamp(6, 12));
        let f = frame(camera, tracker_gaze(i), [4, 2, 1], i);
        cpu = Some(
            render_frame_with_history(&scene.view(), &f, FILL_BILINEAR, &mut history, &|_| {}).0,
        );
        let (image, _) = ctx
            .render_frame_and_history(&gpu_scene, &f, FILL_BILINEAR, 0.0, true, true, &|_| {})
            .expect("the device renders");
        gpu = Some(image);
    }
    let (cpu, gpu) = (cpu.unwrap(), gpu.unwrap());
    let hdr = gpu.hdr.as_ref().expect("HDR was asked for");
    let (fraction, max_abs) = agreement(&cpu, hdr);
    let messages = ctx.validation_messages();
    eprintln!(
        "CPU against lavapipe after 16 frames with history: {:.3} % of pixels within 1e-3, max abs {max_abs:.2e}; {} validation messages",
        fraction * 100.0,
        messages.len()
    );
    assert!(messages.is_empty(), "{messages:?}");
    assert!(fraction >= 0.995, "{fraction}");
}

/// The measurement on Lost Empire (a benchmark, not a test: it asserts nothing and is run by
/// hand): `cargo test --release -p fovea-tests --test temporal lost_empire -- --ignored --nocapture`.
/// 640 × 360, the paper's 32/16/8 on the default display (9.5 px per degree): 50 frames with the gaze on
/// the centre plus 0.15 degrees RMS of tracker noise, a drift of 0.3 degrees per second at 30 fps and a
/// 0.5 degree microsaccade every 20 frames; then a slow pan and a rest. Errors are relMSE against a
/// uniform 512-spp render.
#[test]
#[ignore = "a benchmark (minutes); run by hand"]
fn lost_empire_eye_tracker_benchmark() {
    let path = bundled_scenes().join("lost_empire/lost_empire.obj");
    let (w, h) = (640u32, 360u32);
    let scene = load_packed(&path, &Environment::Constant([1.0, 1.0, 1.0]));
    let base = paper_foveation(w, h);
    let centre = base.gaze;
    let (rf, ri) = (base.radius_fovea, base.radius_intermediate);
    let ppd = 60.0 * (w as f32 / 70.848) * std::f32::consts::PI / 180.0;
    let tracker = Tracker {
        centre,
        rms_px: 0.15 * ppd,
        drift_px: 0.3 / 30.0 * ppd,
        saccade_px: 0.5 * ppd,
        saccade_every: 20,
    };
    let camera_at = |i: u32| {
        // A slow pan: 0.05 units per frame sideways, from frame 0 to 29.
        let mut c = lost_empire_camera(60f32.to_radians(), w as f32 / h as f32);
        let shift = 0.05 * i.min(29) as f32;
        c.position[0] += shift;
        c
    };
    let frame_at = |camera: Camera, gaze: [f32; 2], i: u32| {
        let mut f = frame_params(camera, FoveationParams { gaze, ..base }, w, h, 7);
        f.frame_index = i;
        f
    };
    // FOVEA_BENCH_REFERENCE_DIR keeps the references between runs (they take minutes; delete the
    // folder when the renderer changes).
    let cache_dir = std::env::var_os("FOVEA_BENCH_REFERENCE_DIR").map(std::path::PathBuf::from);
    let reference_of = |camera: Camera| {
        let cached = cache_dir.as_ref().map(|d| {
            d.join(format!(
                "lost_empire_{w}x{h}_{}.f32",
                bytemuck::cast_slice::<f32, u32>(&camera.position)
                    .iter()
                    .map(|b| format!("{b:08x}"))
                    .collect::<String>()
            ))
        });
        if let Some(bytes) = cached.as_ref().and_then(|p| std::fs::read(p).ok()) {
            if bytes.len() == (w * h) as usize * 16 {
                return FrameImage {
                    width: w,
                    height: h,
                    pixels: bytemuck::pod_collect_to_vec(&bytes),
                };
            }
        }
        let mut f = frame_params(camera, FoveationParams::uniform(512), w, h, 99);
        f.frame_index = 1 << 20;
        let start = std::time::Instant::now();
        let r = render(&scene, &f).0;
        eprintln!("reference: {:.1} s", start.elapsed().as_secs_f64());
        if let Some(p) = &cached {
            let _ = std::fs::create_dir_all(p.parent().unwrap());
            let _ = std::fs::write(p, bytemuck::cast_slice(&r.pixels));
        }
        r
    };
    let d = |x: u32, y: u32| {
        ((x as f32 + 0.5 - centre[0]).powi(2) + (y as f32 + 0.5 - centre[1]).powi(2)).sqrt()
    };
    let margin = tracker.saccade_px + 3.0 * tracker.rms_px;
    let fovea = |x: u32, y: u32| d(x, y) < rf - margin;
    let periphery = |x: u32, y: u32| d(x, y) > ri + margin;

    let still_camera = camera_at(0);
    let reference = reference_of(still_camera);
    // Each run has its own random numbers: with one key, the pixels that stay in one region would
    // draw the same samples whatever the gaze did.
    let run = |gaze: &dyn Fn(u32) -> [f32; 2], frames: u32, history: bool, seed: u32| {
        let mut state = TemporalHistory::new();
        let mut passes: Vec<(&'static str, f64)> = Vec::new();
        let images: Vec<FrameImage> = (0..frames)
            .map(|i| {
                let mut f = frame_at(still_camera, gaze(i), i);
                f.seed = seed;
                let (image, stats) = if history {
                    render_frame_with_history(&scene.view(), &f, FILL_BILINEAR, &mut state, &|_| {})
                } else {
                    render(&scene, &f)
                };
                for (k, (name, ms)) in stats.passes.iter().enumerate() {
                    if passes.len() <= k {
                        passes.push((name, 0.0));
                    }
                    passes[k].1 += ms / frames as f64;
                }
                image
            })
            .collect();
        (images, passes)
    };
    const FRAMES: u32 = 50;
    // FOVEA_BENCH_PAN_ONLY=1 skips the still-camera runs.
    let pan_only = std::env::var_os("FOVEA_BENCH_PAN_ONLY").is_some();
    if !pan_only {
        let (still, _) = run(&|_| centre, FRAMES, true, 7);
        let (tracked, passes) = run(&|i| tracker.gaze(i), FRAMES, true, 8);
        let (single, single_passes) = run(&|i| tracker.gaze(i + FRAMES - 16), 16, false, 9);
        let last = FRAMES as usize - 1;
        eprintln!("| run | fovea relMSE | periphery relMSE |");
        eprintln!("|---|---|---|");
        for (name, image) in [
            ("history, still gaze, frame 50", &still[last]),
            ("history, tracker gaze, frame 50", &tracked[last]),
            ("no history (one frame), tracker gaze", &single[15]),
        ] {
            eprintln!(
                "| {name} | {:.4e} | {:.4e} |",
                rel_mse_where(image, &reference, fovea),
                rel_mse_where(image, &reference, periphery)
            );
        }
        eprintln!(
            "periphery flicker (luminance variance over the last 16 frames): history {:.4e}, no history {:.4e}",
            flicker(&tracked[last - 15..], periphery),
            flicker(&single, periphery)
        );
        let mp = (w * h) as f64 * 1e-6;
        let per_mp: Vec<String> = passes
            .iter()
            .map(|(n, ms)| format!("{n} {:.2}", ms / mp))
            .collect();
        eprintln!(
            "CPU ms per megapixel per pass (mean of {FRAMES} frames): {}",
            per_mp.join(", ")
        );
        let per_mp: Vec<String> = single_passes
            .iter()
            .map(|(n, ms)| format!("{n} {:.2}", ms / mp))
            .collect();
        eprintln!("without history: {}", per_mp.join(", "));
    }

    // The pan: 30 moving frames then 20 at rest, with and without reuse, against the last camera's
    // reference.
    let end_camera = camera_at(29);
    let end_reference = reference_of(end_camera);
    let mut state = TemporalHistory::new();
    let all = |_: u32, _: u32| true;
    // The fovea's error over four moving frames (the references take minutes each), each against its
    // own camera's reference (with reuse, without), outside disocclusions.
    const FOVEA_MEAN_FRAMES: [u32; 4] = [20, 21, 22, 29];
    let mut fovea_moving = (0.0, 0.0);
    for i in 0..50u32 {
        let f = frame_at(camera_at(i), tracker.gaze(i), i);
        let (image, _) =
            render_frame_with_history(&scene.view(), &f, FILL_BILINEAR, &mut state, &|_| {});
        let in_mean = FOVEA_MEAN_FRAMES.contains(&i);
        if !in_mean && i != 49 {
            continue;
        }
        let valid: Vec<bool> = state.texels().iter().map(|t| t.frames() >= 4.0).collect();
        let without = render(&scene, &f).0;
        // Outside disocclusions (4+ frames of history), by region.
        let kept = |x: u32, y: u32| valid[(y * w + x) as usize];
        let (in_fovea, in_periphery) = (
            |x: u32, y: u32| kept(x, y) && fovea(x, y),
            |x: u32, y: u32| kept(x, y) && periphery(x, y),
        );
        if in_mean {
            let own_reference = (i != 29).then(|| reference_of(camera_at(i)));
            let reference = own_reference.as_ref().unwrap_or(&end_reference);
            fovea_moving.0 += rel_mse_where(&image, reference, in_fovea) / 4.0;
            fovea_moving.1 += rel_mse_where(&without, reference, in_fovea) / 4.0;
        }
        if i == 29 {
            eprintln!(
                "pan, frames 20, 21, 22, 29: mean fovea relMSE with reuse {:.4e}, without {:.4e} ({:.2}x)",
                fovea_moving.0,
                fovea_moving.1,
                fovea_moving.1 / fovea_moving.0
            );
        }
        if i == 29 || i == 49 {
            let when = if i == 29 {
                "last moving frame"
            } else {
                "after 20 frames at rest"
            };
            eprintln!(
                "pan, frame {i} ({when}): fovea relMSE with reuse {:.4e}, without {:.4e}; periphery \
                 {:.4e} vs {:.4e}; whole image {:.4e} vs {:.4e}; {:.1} % of pixels with 4+ frames",
                rel_mse_where(&image, &end_reference, in_fovea),
                rel_mse_where(&without, &end_reference, in_fovea),
                rel_mse_where(&image, &end_reference, in_periphery),
                rel_mse_where(&without, &end_reference, in_periphery),
                rel_mse_where(&image, &end_reference, all),
                rel_mse_where(&without, &end_reference, all),
                valid.iter().filter(|&&v| v).count() as f64 * 100.0 / valid.len() as f64
            );
        }
    }
}

/// A thin bright bar in front of a dark wall, the camera strafing past it: where the bar was three or
/// more frames ago the wall shows no trace of it (disocclusion and the clamp drop its history).
#[test]
fn a_thin_bright_bar_leaves_no_ghost() {
    use fovea_core::scene::Material;
    use fovea_tests::stability::{loaded_scene, pack};
    let quad = |x: [f32; 2], y: [f32; 2], z: f32, first: u32| {
        (
            vec![
                [x[0], y[0], z],
                [x[1], y[0], z],
                [x[1], y[1], z],
                [x[0], y[1], z],
            ],
            vec![[first, first + 1, first + 2], [first, first + 2, first + 3]],
        )
    };
    let (mut positions, mut triangles) = quad([-30.0, 30.0], [-30.0, 30.0], -5.0, 0);
    let (bar_positions, bar_triangles) = quad([-0.05, 0.05], [-3.0, 3.0], -2.0, 4);
    positions.extend(bar_positions);
    triangles.extend(bar_triangles);
    let wall = Material {
        base_color: [0.1, 0.1, 0.1, 1.0],
        ..Material::default()
    };
    let bar = Material {
        base_color: [0.0, 0.0, 0.0, 1.0],
        emission: [20.0, 20.0, 20.0, 0.0],
        ..Material::default()
    };
    let scene = pack(
        loaded_scene(positions, triangles, vec![0, 0, 1, 1], vec![wall, bar]),
        &Environment::Constant([0.5, 0.5, 0.5]),
    );
    let camera_at = |i: u32| {
        let eye = Vec3::new(-0.6 + 0.04 * i as f32, 0.0, 0.0);
        Camera::look_at(
            eye,
            eye + Vec3::NEG_Z,
            Vec3::Y,
            40f32.to_radians(),
            W as f32 / H as f32,
        )
    };
    const FRAMES: u32 = 24;
    let now = FRAMES as usize - 1;
    let reference = reference(&scene, camera_at(FRAMES - 1));
    let lum = |c: &[f32; 4]| luminance(Vec3::new(c[0], c[1], c[2])) as f64;
    // Mean and worst excess luminance (relative to the reference) of the history's image over
    // `against` on the pixels that saw the bar 3-8 frames ago and not since.
    let trail_excess = |foveation: FoveationParams,
                        against: &dyn Fn(&FrameParams) -> FrameImage| {
        let mut history = TemporalHistory::new();
        // Which pixels saw the bar (distance about 2) in each frame.
        let mut saw_bar: Vec<Vec<bool>> = Vec::new();
        let mut shown = None;
        let mut last = None;
        for i in 0..FRAMES {
            let mut f = frame(camera_at(i), CENTRE, [1, 1, 1], i);
            f.foveation = FoveationParams {
                gaze: CENTRE,
                ..foveation
            };
            shown = Some(
                render_frame_with_history(&scene.view(), &f, FILL_BILINEAR, &mut history, &|_| {})
                    .0,
            );
            saw_bar.push(
                history
                    .gbuffer()
                    .iter()
                    .map(|g| !g.is_sky() && g.distance() < 3.5)
                    .collect(),
            );
            last = Some(f);
        }
        let (shown, baseline) = (shown.unwrap(), against(&last.unwrap()));
        let (mut excess, mut worst, mut n) = (0.0f64, 0.0f64, 0);
        for (p, pixel) in shown.pixels.iter().enumerate() {
            let recent = saw_bar[now - 2..=now].iter().any(|seen| seen[p]);
            let before = saw_bar[now - 8..now - 2].iter().any(|seen| seen[p]);
            if before && !recent {
                let e = (lum(pixel) - lum(&baseline.pixels[p])) / lum(&reference.pixels[p]);
                excess += e;
                worst = worst.max(e);
                n += 1;
            }
        }
        (excess / n.max(1) as f64, worst, n)
    };
    // Uniform 4 spp against the converged image: what the history keeps of the bar.
    let (mean, worst, n) = trail_excess(FoveationParams::uniform(4), &|_| reference.clone());
    // Foveated 8/4/2 (the periphery's blocks blur the bar over its neighbours in every frame) against
    // the same frame rendered alone: what the history adds to that blur.
    let mut foveated = FoveationParams::paper(CENTRE, RADII[0], RADII[1]);
    foveated.spp = [8, 4, 2, 0];
    let (f_mean, f_worst, _) = trail_excess(foveated, &|f| {
        let mut alone = *f;
        alone.frame_index += 1000;
        render(&scene, &alone).0
    });
    eprintln!(
        "bar trail ({n} pixels that saw the bar 3-8 frames ago; the bar is ~400x the wall): uniform, \
         mean excess luminance {:.1} %, worst {:.1} % over the converged image; foveated, mean {:.1} %, \
         worst {:.1} % over the same frame without history",
        mean * 100.0,
        worst * 100.0,
        f_mean * 100.0,
        f_worst * 100.0
    );
    assert!(n > 20, "{n}");
    assert!(mean < 0.1 && worst < 1.0, "mean {mean}, worst {worst}");
    assert!(f_mean < 0.1, "foveated: mean {f_mean}, worst {f_worst}");
}

/// The G-buffer's albedo is what a pixel's jittered samples see on average, the texture box-filtered
/// over the pixel (`fovea_core::temporal::gbuffer::footprint_albedo`): a quad under a fine random
/// texture (about three texels per pixel), seen at an angle. Against the mean of 16 × 16 points per
/// pixel read at mip level 0 (as the samples read it), its error is well below that of one read at the
/// centre at the footprint's mip level, which the history and the denoiser used before.
#[test]
fn the_gbuffer_albedo_is_the_mean_over_the_pixel() {
    use fovea_core::bvh::closest_hit;
    use fovea_core::integrator::pixel_cone_spread;
    use fovea_core::material::shading::surface_point_lod;
    use fovea_core::material::surface_point;
    use fovea_core::scene::{Material, SceneSlices, MATERIAL_LAMBERTIAN};
    use fovea_core::temporal::first_hit_gbuffer;
    use fovea_scene::texture::{pack_rgba8, Texture};
    use glam::Vec2;

    let material = Material {
        base_color: [1.0, 1.0, 1.0, 1.0],
        flags: MATERIAL_LAMBERTIAN,
        base_color_texture: 0,
        ..Material::default()
    };
    let mut s = fovea_tests::stability::textured_quad(material);
    let side = 64u32;
    let texels = (0..side * side)
        .map(|i| {
            let v = (i.wrapping_mul(2_654_435_761) >> 24) as u8;
            pack_rgba8([v, v / 2 + 64, 255 - v, 255])
        })
        .collect();
    s.textures = vec![Texture::new("noise", side, side, false, texels)];
    let packed = fovea_tests::stability::pack(s, &Environment::Constant([1.0, 1.0, 1.0]));
    let view = packed.view();
    let (w, h) = (24u32, 24u32);
    let camera = Camera::look_at(Vec3::new(1.2, 0.7, 3.0), Vec3::ZERO, Vec3::Y, 0.5, 1.0);
    let frame = frame_params(camera, FoveationParams::uniform(1), w, h, 1);

    let (mut new_error, mut centre_error, mut pixels) = (0.0f32, 0.0f32, 0u32);
    for y in 0..h {
        for x in 0..w {
            // The pixel's mean albedo: 16 × 16 points, each read at mip level 0.
            let (mut sum, mut count) = (Vec3::ZERO, 0u32);
            for j in 0..256u32 {
                let point = Vec2::new(
                    x as f32 + ((j % 16) as f32 + 0.5) / 16.0,
                    y as f32 + ((j / 16) as f32 + 0.5) / 16.0,
                );
                let hit = closest_hit(&view, &camera.generate_ray(point, w, h), f32::INFINITY);
                if hit.is_hit() {
                    sum += surface_point(&view, &SceneSlices, &hit).params.base_color;
                    count += 1;
                }
            }
            // Only pixels wholly on the quad: at its silhouette the mean mixes in the sky.
            if count < 256 {
                continue;
            }
            let mean = sum / 256.0;
            let g = first_hit_gbuffer(&view, &SceneSlices, &frame, x, y);
            new_error += (Vec3::from_slice(&g.albedo[..3]) - mean)
                .abs()
                .element_sum();
            // One read at the centre over the whole footprint.
            let ray = camera.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), w, h);
            let hit = closest_hit(&view, &ray, f32::INFINITY);
            let cone = pixel_cone_spread(&frame) * hit.t;
            let centre = surface_point_lod(&view, &SceneSlices, &hit, ray.direction, cone);
            centre_error += (centre.params.base_color - mean).abs().element_sum();
            pixels += 1;
        }
    }
    assert!(pixels > 200, "{pixels} pixels on the quad");
    let (new_error, centre_error) = (new_error / pixels as f32, centre_error / pixels as f32);
    println!(
        "mean abs error per pixel: over the pixel {new_error:.4}, at the centre {centre_error:.4}"
    );
    assert!(
        new_error < 0.6 * centre_error,
        "the pixel's mean albedo is off by {new_error:.4}, one read at the centre by {centre_error:.4}"
    );
}
