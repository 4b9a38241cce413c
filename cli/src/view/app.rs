//! The live view's window and event loop (winit): input and scripted events change the viewer's
//! state; each redraw reads the newest gaze, moves the camera, renders one frame (or a budgeted
//! fraction of one), adds it to each pixel's history, presents it with the on-screen figures, and
//! records it.
//!
//! **History** (`fovea_core::temporal`) survives what a frame does not invalidate: a gaze move changes
//! where the next samples go and how much they weigh, a camera move reprojects the history (and a
//! disocclusion restarts it there), a new configuration or the uniform toggle only changes the next
//! samples. It restarts only when the rendered size changes or on `R`. After
//! [`MAX_ACCUMULATED_FRAMES`] frames with nothing changing, the view stops rendering and waits.
use clap::ValueEnum;
use std::collections::HashSet;
use std::time::{Duration, Instant};

use fovea_core::camera::Camera;
use fovea_core::foveation::regions::FOVEATION_OK;
use glam::Vec3;
use serde_json::json;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, StartCause, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

use crate::args::Backend;
use crate::backend::FrameOutput;
use crate::error::{FoveaError, Result};
use crate::fixation::FixationFilter;
use crate::gaze::GazeConvention;
use crate::scene_setup::{choose_camera, prepare_scene, PreparedScene};
use crate::schedule::{FoveationRule, ScheduledFrame};
use crate::view::fly::{FlyCamera, Movement};
use crate::view::hud::render_hud;
use crate::view::live::LiveRenderer;
use crate::view::options::{GazeInput, ViewOptions};
use crate::view::record::{median, stats_document, write_screenshot, FrameRecord};
use crate::view::sampling::{frame_foveation, BudgetController};
use crate::view::script::{ScriptEvent, ViewKey};

/// Frames in one mean before the view stops rendering and waits (the image has converged far past
/// what a viewer can tell apart).
const MAX_ACCUMULATED_FRAMES: u32 = 4096;
/// Time step of the fly controls in scripted runs (real time otherwise), so a script moves the camera
/// the same way on every machine.
const SCRIPT_DT: f32 = 1.0 / 30.0;
/// How often a minimised or paused scripted run advances its frame clock.
const IDLE_TICK: Duration = Duration::from_millis(15);
/// The shortest time between two snapshots of `--stats` while the view runs.
const STATS_SNAPSHOT_MIN_INTERVAL: Duration = Duration::from_secs(5);
/// Where the on-screen figures go.
const HUD_CORNER: [u32; 2] = [8, 8];

/// Opens the window and runs the view until it is closed.
pub fn run(options: ViewOptions) -> Result<()> {
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        return Err(FoveaError::View(
            "no display to open a window on (neither DISPLAY nor WAYLAND_DISPLAY is set); run it in a \
             desktop session, or headless under Xvfb: xvfb-run -a fovea view ..."
                .into(),
        ));
    }
    let use_gpu = match options.backend {
        Backend::Cpu => false,
        Backend::Vulkan => true,
        Backend::Auto => match crate::backend::auto_vulkan_refusal() {
            None => true,
            Some(why) => {
                if !options.quiet {
                    eprintln!("note: rendering on the CPU (presenting through Vulkan): {why}");
                }
                false
            }
        },
    };
    let mut scene = prepare_scene(
        options.scene.as_deref(),
        options.mtl.as_deref(),
        options.mtl_diffuse,
        &options.lighting.environment(options.scene.is_none()),
        &options.lighting.point_lights,
        !use_gpu,
    )?;
    if scene.packed.lights.list.is_empty() {
        eprintln!("warning: {}", crate::scene_setup::NO_LIGHT_WARNING);
        // `--stats` lists it with the scene's own warnings.
        scene
            .warnings
            .insert(0, crate::scene_setup::NO_LIGHT_WARNING.to_string());
    }
    let event_loop = EventLoop::new().map_err(|e| {
        FoveaError::View(format!(
            "cannot connect to the display: {e} (is the X server or Wayland compositor running?)"
        ))
    })?;
    let mut viewer = Viewer::new(options, scene, use_gpu)?;
    event_loop
        .run_app(&mut viewer)
        .map_err(|e| FoveaError::View(format!("the window's event loop failed: {e}")))?;
    viewer.finish()
}

/// The state of the view.
struct Viewer {
    options: ViewOptions,
    scene: PreparedScene,
    use_gpu: bool,
    // Field order: the renderer (which owns the window's surface) is dropped before the window.
    renderer: Option<LiveRenderer>,
    window: Option<Window>,
    error: Option<FoveaError>,

    // Input.
    held: HashSet<ViewKey>,
    /// Movement keys pressed (not held) this frame: they move the camera for one frame.
    tapped: HashSet<ViewKey>,
    cursor: Option<[f64; 2]>,
    looking: bool,
    window_size: [u32; 2],
    minimized: bool,

    // Gaze: where the regions go (the fixation filter's output) in window pixels, the newest raw
    // sample, and when it arrived.
    gaze: [f32; 2],
    raw_gaze: [f32; 2],
    fixation: FixationFilter,
    gaze_arrived: Option<Instant>,
    gaze_used: Option<Instant>,
    started: Instant,

    // Camera.
    fly: FlyCamera,
    fly_start: FlyCamera,
    camera_moved: bool,
    last_tick: Option<Instant>,

    // Sampling.
    config_index: usize,
    uniform: bool,
    overlay: bool,
    /// The denoiser's passes on (toggle with N).
    denoise: bool,
    hud_on: bool,
    paused: bool,
    budget: BudgetController,

    // Accumulation: frames in the mean, and what the mean was rendered with.
    accumulated: u32,
    /// Samples per pixel / block summed over the frames of the mean (the effective spp).
    effective_spp: [u64; 3],
    mean_key: Option<MeanKey>,
    reset_requested: bool,

    // Clock and records.
    frame: u64,
    frame_index_key: u32,
    next_idle_tick: Instant,
    records: Vec<FrameRecord>,
    /// When `--stats` is next written while the run goes on ([`Self::snapshot_stats`]).
    next_stats_snapshot: Instant,
    last_foveation: Option<fovea_core::foveation::regions::FoveationParams>,
    screenshot_requested: bool,
    screenshots: Vec<String>,
    malformed_gaze: Vec<String>,
    exit: bool,
    present_mode: &'static str,
}

/// What the view was rendered with: a change renders a new frame even after convergence.
#[derive(Clone, Copy, Debug, PartialEq)]
struct MeanKey {
    size: [u32; 2],
    config_index: usize,
    uniform: bool,
    gaze: [f32; 2],
    /// Not part of the history: toggling it redraws without restarting anything.
    denoise: bool,
}

impl Viewer {
    fn new(options: ViewOptions, scene: PreparedScene, use_gpu: bool) -> Result<Self> {
        let [w, h] = options.window_size;
        let (eye_option, target_option, world_up) = options.camera;
        let camera = choose_camera(
            &scene,
            eye_option,
            target_option,
            world_up,
            options.fov,
            w as f32 / h as f32,
        )?;
        let eye = Vec3::from_slice(&camera.position[..3]);
        let forward = Vec3::from_slice(&camera.forward[..3]);
        let up = Vec3::from_slice(&camera.up[..3]);
        let fov_deg = (2.0 * up.length().atan()).to_degrees();
        let diagonal = (scene.packed.bounds_max - scene.packed.bounds_min).length();
        let fly = FlyCamera::new(eye, eye + forward, Vec3::from(world_up), fov_deg, diagonal);
        let now = Instant::now();
        Ok(Self {
            uniform: options.uniform,
            overlay: options.overlay,
            denoise: options.denoise,
            budget: BudgetController::new(options.budget_ms),
            window_size: options.window_size,
            gaze: [0.5 * w as f32, 0.5 * h as f32],
            raw_gaze: [0.5 * w as f32, 0.5 * h as f32],
            fixation: FixationFilter::new(0.0),
            options,
            scene,
            use_gpu,
            renderer: None,
            window: None,
            error: None,
            held: HashSet::new(),
            tapped: HashSet::new(),
            cursor: None,
            looking: false,
            minimized: false,
            gaze_arrived: None,
            gaze_used: None,
            started: now,
            fly_start: fly.clone(),
            fly,
            camera_moved: false,
            last_tick: None,
            config_index: 0,
            hud_on: true,
            paused: false,
            accumulated: 0,
            effective_spp: [0; 3],
            mean_key: None,
            reset_requested: false,
            frame: 0,
            frame_index_key: 0,
            next_idle_tick: now,
            records: Vec::new(),
            next_stats_snapshot: now,
            last_foveation: None,
            screenshot_requested: false,
            screenshots: Vec::new(),
            malformed_gaze: Vec::new(),
            exit: false,
            present_mode: "",
        })
    }

    /// Stops the event loop with `e` as the run's result.
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: FoveaError) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        self.exit = true;
        event_loop.exit();
    }

    fn scripted(&self) -> bool {
        self.options.script.is_some()
    }

    /// Whether frames are counted while none renders (converged, paused, minimised): a script's
    /// clock must reach its next event, and `--exit-after-frames` must end the run even when the
    /// image has converged and nothing moves.
    fn counts_idle_frames(&self) -> bool {
        self.scripted() || self.options.exit_after_frames.is_some()
    }

    /// Whether the next tick renders (else the view waits for input).
    fn wants_frame(&self) -> bool {
        !self.exit
            && !self.minimized
            && !self.paused
            && self.window_size[0] > 0
            && self.window_size[1] > 0
            && (self.accumulated < MAX_ACCUMULATED_FRAMES
                || self.view_changed_since_last_frame()
                || !self.held.is_empty()
                || !self.tapped.is_empty())
    }

    fn view_changed_since_last_frame(&self) -> bool {
        self.reset_requested || self.camera_moved || self.mean_key != Some(self.mean_key_now())
    }

    /// The rendered size: the window's times `--render-scale`.
    fn render_size(&self) -> [u32; 2] {
        let scale = self.options.render_scale;
        self.window_size
            .map(|w| ((w as f32 * scale).round() as u32).max(1))
    }

    /// What a mean started now would depend on.
    fn mean_key_now(&self) -> MeanKey {
        MeanKey {
            size: self.render_size(),
            config_index: self.config_index,
            uniform: self.uniform,
            gaze: self.gaze,
            denoise: self.denoise,
        }
    }

    /// Whether the history must restart before a frame with `key` joins it: on `R` and when the
    /// rendered size changes (its pixels are not the history's). Gaze, camera, configuration and the
    /// uniform toggle keep it.
    fn history_is_stale(&self, key: &MeanKey) -> bool {
        match self.mean_key {
            None => true,
            Some(old) => self.reset_requested || old.size != key.size,
        }
    }

    // ----- input --------------------------------------------------------------------------------------

    fn key(&mut self, key: ViewKey, pressed: bool, repeat: bool, event_loop: &ActiveEventLoop) {
        if key.is_movement() {
            if pressed {
                self.held.insert(key);
            } else {
                self.held.remove(&key);
            }
            return;
        }
        if !pressed || repeat {
            return;
        }
        self.press(key, event_loop);
    }

    /// A key's action (keys other than the movement keys act on press).
    fn press(&mut self, key: ViewKey, event_loop: &ActiveEventLoop) {
        match key {
            ViewKey::U => {
                self.uniform = !self.uniform;
                self.budget.reset();
            }
            ViewKey::O => self.overlay = !self.overlay,
            ViewKey::N => self.denoise = !self.denoise,
            ViewKey::C => {
                self.config_index = (self.config_index + 1) % self.options.configs.len();
                self.budget.reset();
            }
            ViewKey::Space => self.paused = !self.paused,
            ViewKey::P => self.screenshot_requested = true,
            ViewKey::R => {
                self.fly.reset_to(&self.fly_start);
                self.reset_requested = true;
                self.budget.reset();
            }
            ViewKey::H => self.hud_on = !self.hud_on,
            ViewKey::Escape => {
                self.exit = true;
                event_loop.exit();
            }
            ViewKey::W
            | ViewKey::A
            | ViewKey::S
            | ViewKey::D
            | ViewKey::Q
            | ViewKey::E
            | ViewKey::Shift => {
                self.tapped.insert(key);
            }
        }
        self.request_redraw();
    }

    fn cursor_moved(&mut self, x: f64, y: f64, at: Instant) {
        if let Some([px, py]) = self.cursor {
            if self.looking {
                let rad_per_px =
                    self.fly.fov_y_degrees().to_radians() / self.window_size[1].max(1) as f32;
                if self.fly.look(x - px, y - py, rad_per_px) {
                    self.camera_moved = true;
                }
            }
        }
        self.cursor = Some([x, y]);
        if matches!(self.options.gaze, GazeInput::Mouse) {
            self.gaze = [x as f32, y as f32];
            self.gaze_arrived = Some(at);
        }
        self.request_redraw();
    }

    fn request_redraw(&self) {
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }

    fn apply_script_event(&mut self, event: ScriptEvent, event_loop: &ActiveEventLoop) {
        let now = Instant::now();
        match event {
            ScriptEvent::Gaze { x, y } => {
                let [w, h] = self.window_size;
                self.gaze = crate::gaze::to_window_pixels(GazeConvention::Normalized, x, y, [w, h]);
                self.gaze_arrived = Some(now);
            }
            ScriptEvent::Mouse { x, y } => self.cursor_moved(x, y, now),
            ScriptEvent::Press(k) => self.press(k, event_loop),
            ScriptEvent::Down(k) => self.key(k, true, false, event_loop),
            ScriptEvent::Up(k) => self.key(k, false, false, event_loop),
            ScriptEvent::Button { down } => self.looking = down,
            ScriptEvent::Wheel(steps) => self.fly.scroll(steps),
            ScriptEvent::Resize { width, height } => {
                if let Some(w) = &self.window {
                    if let Some(size) = w.request_inner_size(PhysicalSize::new(width, height)) {
                        self.window_size = [size.width, size.height];
                    }
                }
            }
            ScriptEvent::Minimize => {
                if let Some(w) = &self.window {
                    w.set_minimized(true);
                }
                self.minimized = true;
            }
            ScriptEvent::Restore => {
                if let Some(w) = &self.window {
                    w.set_minimized(false);
                }
                self.minimized = false;
            }
            ScriptEvent::Close => {
                self.exit = true;
                event_loop.exit();
            }
        }
    }

    /// Reads the live gaze sources (UDP, trace) just before a frame.
    fn poll_gaze(&mut self) {
        let size = self.window_size;
        // The filter's radius in window pixels, on the display model that the window's width fills.
        let (display_cm, distance_cm) = self.options.display;
        let ppd = fovea_core::foveation::pixels_per_degree(&crate::values::display_at(
            display_cm,
            distance_cm,
            size,
        ));
        let radius = self.options.fixation_filter_deg * ppd;
        if self.fixation.radius() != radius {
            self.fixation = FixationFilter::new(radius);
        }
        match &mut self.options.gaze {
            GazeInput::Mouse => {}
            GazeInput::Udp(source) => {
                let poll = source.poll(size);
                if let Some((sample, at)) = poll.newest {
                    self.raw_gaze = [sample.x, sample.y];
                    self.gaze = self.fixation.push(self.raw_gaze);
                    self.gaze_arrived = Some(at);
                }
                for m in poll.malformed {
                    if self.malformed_gaze.is_empty() && !self.options.quiet {
                        eprintln!("warning: {m} (dropped; later ones are counted in --stats)");
                    }
                    if self.malformed_gaze.len() < 100 {
                        self.malformed_gaze.push(m);
                    }
                }
            }
            GazeInput::Trace(trace) => {
                let t = self.started.elapsed().as_secs_f64();
                if let Some(sample) = trace.sample_for(t, self.frame, size) {
                    if [sample.x, sample.y] != self.raw_gaze {
                        self.raw_gaze = [sample.x, sample.y];
                        self.gaze = self.fixation.push(self.raw_gaze);
                        self.gaze_arrived = Some(Instant::now());
                    }
                }
            }
        }
    }

    fn movement(&self) -> Movement {
        let on = |k: ViewKey| self.held.contains(&k) || self.tapped.contains(&k);
        Movement {
            forward: on(ViewKey::W),
            back: on(ViewKey::S),
            left: on(ViewKey::A),
            right: on(ViewKey::D),
            up: on(ViewKey::E),
            down: on(ViewKey::Q),
            fast: on(ViewKey::Shift),
        }
    }

    // ----- frames -------------------------------------------------------------------------------------

    /// One tick of the frame clock: scripted events, then a frame if the view renders, then the exit
    /// checks.
    fn tick(&mut self, event_loop: &ActiveEventLoop) {
        let due = match self.options.script.as_mut() {
            Some(s) => s.due(self.frame),
            None => Vec::new(),
        };
        for e in due {
            self.apply_script_event(e, event_loop);
        }
        if self.exit {
            return;
        }
        if let Some(w) = &self.window {
            let s = w.inner_size();
            if !self.minimized {
                self.window_size = [s.width, s.height];
            }
        }
        if self.wants_frame() {
            if let Err(e) = self.render_frame() {
                self.fail(event_loop, e);
                return;
            }
        }
        self.frame += 1;
        let script_done = self
            .options
            .script
            .as_ref()
            .is_some_and(|s| s.is_finished() && self.options.exit_after_frames.is_none());
        if self
            .options
            .exit_after_frames
            .is_some_and(|n| self.frame >= n)
            || script_done
        {
            self.exit = true;
            event_loop.exit();
        }
    }

    /// Long because it is one live frame in order (input, the frame's foveation and camera, render,
    /// HUD, present, its record), all on the viewer's state.
    fn render_frame(&mut self) -> Result<()> {
        let tick_start = Instant::now();
        if self.records.is_empty() {
            // A gaze trace replays from the first frame, not from before the window opened.
            self.started = tick_start;
        }
        self.poll_gaze();
        let dt = if self.scripted() {
            SCRIPT_DT
        } else {
            self.last_tick
                .map_or(0.0, |t| t.elapsed().as_secs_f32())
                .min(0.25)
        };
        self.last_tick = Some(tick_start);
        if self.fly.update(dt, &self.movement()) {
            self.camera_moved = true;
        }
        self.tapped.clear();

        let window = self.window_size;
        let key = self.mean_key_now();
        let size = key.size;
        // The gaze in rendered pixels.
        let gaze = [
            self.gaze[0] * size[0] as f32 / window[0] as f32,
            self.gaze[1] * size[1] as f32 / window[1] as f32,
        ];
        let config = self.options.configs[self.config_index].clone();
        let radii = self.options.radii.radii_px(size);
        let accumulated_before = if self.history_is_stale(&key) {
            0
        } else {
            self.accumulated
        };
        self.reset_requested = false;
        self.camera_moved = false;

        let shift = self.budget.shift();
        let foveation = frame_foveation(&config, self.uniform, shift, gaze, radii);
        if foveation.validate() != FOVEATION_OK {
            return Err(FoveaError::option(
                "--spp/--blocks/--radii",
                "the foveation settings are inconsistent",
            ));
        }
        let settings = self.options.settings.with_size(size);
        let pose = self.fly.pose();
        let camera = Camera::from_forward(
            pose.eye,
            pose.forward,
            pose.up_hint,
            pose.fov_y_degrees.to_radians(),
            settings.aspect(),
        );
        // Live input makes the frame: its number, the gaze and the fly camera's pose.
        let scheduled = ScheduledFrame {
            number: self.frame_index_key,
            gaze,
            eyes: None,
            camera: None,
        };
        let rule = FoveationRule {
            template: foveation,
            uniform: false,
            eye_eccentricity: None,
        };
        let frame = settings.views(&scheduled, camera, None, &rule)[0].frame;
        self.frame_index_key = self.frame_index_key.wrapping_add(1);
        let gaze_is_new = self.gaze_arrived.is_some() && self.gaze_arrived != self.gaze_used;
        self.gaze_used = self.gaze_arrived;

        let renderer = self.renderer.as_mut().expect("the window is open");
        let render_start = Instant::now();
        let request = settings.request(
            true,
            self.denoise,
            FrameOutput::Present {
                overlay: self.overlay,
            },
        );
        let (stats, before) =
            renderer.render(&self.scene.packed, &frame, &request, accumulated_before)?;
        let render_ms = render_start.elapsed().as_secs_f64() * 1e3;
        self.accumulated = before + 1;
        self.mean_key = Some(key);

        let frame_spp = [
            frame.foveation.spp[0],
            frame.foveation.spp[1],
            frame.foveation.spp[2],
        ];
        if before == 0 {
            self.effective_spp = [0; 3];
        }
        for (e, s) in self.effective_spp.iter_mut().zip(frame_spp) {
            *e += u64::from(s);
        }
        let lines = self.hud_lines(&config.name, frame_spp, shift, &stats, render_ms);
        let hud = self.hud_on.then(|| render_hud(&lines, 1));
        let present_start = Instant::now();
        let renderer = self.renderer.as_mut().expect("the window is open");
        let outcome = renderer.present(
            hud.as_ref().map(|h| fovea_vulkan::HudOverlay {
                pixels: &h.pixels,
                width: h.width,
                height: h.height,
                x: HUD_CORNER[0],
                y: HUD_CORNER[1],
            }),
            window,
        )?;
        let presented_at = Instant::now();
        self.present_mode = outcome.present_mode;
        let latency_ms = if gaze_is_new && outcome.presented {
            self.gaze_used
                .map(|t| presented_at.duration_since(t).as_secs_f64() * 1e3)
        } else {
            None
        };
        let frame_ms = tick_start.elapsed().as_secs_f64() * 1e3;
        // The first frame compiles the driver's pipelines (lavapipe: LLVM): not a measure of the budget.
        if !self.records.is_empty() {
            self.budget.observe(frame_ms, config.spp_for(self.uniform));
        }
        let record = FrameRecord {
            frame: self.frame,
            gaze: self.gaze,
            raw_gaze: self.raw_gaze,
            uniform: self.uniform,
            config: config.name.clone(),
            frame_spp,
            budget_shift: shift,
            render: stats,
            accumulated_frames: self.accumulated,
            effective_spp: self.effective_spp,
            render_ms,
            present_ms: presented_at.duration_since(present_start).as_secs_f64() * 1e3,
            frame_ms,
            latency_ms,
            window,
            rendered: size,
            presented: outcome.presented,
            eye: fovea_scene::rebase::to_world(pose.eye.to_array(), self.scene.origin),
            radii_px: [
                frame.foveation.radius_fovea,
                frame.foveation.radius_intermediate,
            ],
        };
        self.last_foveation = Some(frame.foveation);
        if self.screenshot_requested || self.options.screenshot_frames.contains(&self.frame) {
            self.screenshot_requested = false;
            self.screenshot(&record)?;
        }
        if let (Some(w), false, true) = (
            &self.window,
            self.options.quiet,
            self.frame.is_multiple_of(30),
        ) {
            w.set_title(&format!(
                "fovea view - {:.1} ms, {} - {} frames accumulated",
                frame_ms, config.name, self.accumulated
            ));
        }
        if self.records.len() < 1_000_000 {
            self.records.push(record);
        }
        self.snapshot_stats();
        Ok(())
    }

    /// Writes `--stats` while the run goes on, marked `"complete": false`: after the first frame, then at
    /// most every [`STATS_SNAPSHOT_MIN_INTERVAL`] and no more than 5 % of the time (the file grows with
    /// the frames). A run ended by Ctrl-C or SIGTERM, which Rust's standard library cannot catch, keeps
    /// the stats up to its last snapshot; one that ends normally overwrites it with the complete file.
    fn snapshot_stats(&mut self) {
        let now = Instant::now();
        if self.options.stats.is_none() || now < self.next_stats_snapshot {
            return;
        }
        match self.write_stats(false) {
            Ok(()) => {
                let took = now.elapsed();
                self.next_stats_snapshot =
                    Instant::now() + STATS_SNAPSHOT_MIN_INTERVAL.max(took * 20);
            }
            Err(e) => {
                eprintln!("warning: --stats snapshot: {e}; the file is written at the end only");
                self.next_stats_snapshot = now + Duration::from_secs(u64::from(u32::MAX));
            }
        }
    }

    /// Writes the `--stats` file: the run's settings, every frame and a summary; `complete` says
    /// whether the run has ended.
    fn write_stats(&self, complete: bool) -> Result<()> {
        let Some(path) = &self.options.stats else {
            return Ok(());
        };
        let validation = self
            .renderer
            .as_ref()
            .map(|r| r.validation_messages())
            .unwrap_or_default();
        let renderer = self.renderer.as_ref();
        let malformed = match &self.options.gaze {
            GazeInput::Udp(u) => u.malformed_count(),
            _ => 0,
        };
        let header = json!({
            "complete": complete,
            "backend": renderer.map(|r| r.backend_name),
            "device": renderer.map(|r| r.device.clone()),
            "present_device": renderer.map(|r| r.present_device.clone()),
            "present_mode": self.present_mode,
            "upload_ms": renderer.map(|r| r.upload_ms),
            "scene": self.options.scene,
            "traversal": self.options.traversal.to_possible_value().map(|v| v.get_name().to_string()),
            "warnings": self.scene.warnings,
            "triangles": self.scene.triangle_count,
            "gaze_source": self.options.gaze.describe(),
            "malformed_gaze_datagrams": malformed,
            "malformed_gaze_messages": self.malformed_gaze,
            "budget_ms": self.options.budget_ms,
            "configurations": self.options.configs.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
            "screenshots": self.screenshots,
            "ticks": self.frame,
        });
        crate::stats::write_json(path, &stats_document(header, &self.records, &validation))
    }

    fn hud_lines(
        &self,
        config: &str,
        frame_spp: [u32; 3],
        shift: u32,
        stats: &fovea_cpu::RenderStats,
        render_ms: f64,
    ) -> Vec<String> {
        let renderer = self.renderer.as_ref().expect("the window is open");
        let recent: Vec<f64> = self
            .records
            .iter()
            .rev()
            .take(30)
            .map(|r| r.frame_ms)
            .collect();
        let frame_ms = median(&recent).unwrap_or(render_ms);
        let latency = self
            .records
            .iter()
            .rev()
            .find_map(|r| r.latency_ms)
            .map_or("-".to_string(), |l| format!("{l:.1} ms"));
        let eff = self.effective_spp;
        let [cw, ch] = self.window_size;
        let scale = self.options.render_scale;
        let mut lines = vec![
            format!(
                "fovea view  {}: {}  {}x{}{}",
                renderer.backend_name,
                renderer.device,
                cw,
                ch,
                if scale < 1.0 {
                    format!(" (rendered at x{scale})")
                } else {
                    String::new()
                }
            ),
            format!(
                "frame {:>6}  {:6.1} ms  {:5.1} fps  gaze-to-present {}",
                self.frame,
                frame_ms,
                if frame_ms > 0.0 { 1e3 / frame_ms } else { 0.0 },
                latency
            ),
            format!(
                "{} {}  per frame {}/{}/{} (1/{})  {:.2} M samples",
                config,
                if self.uniform { "uniform" } else { "foveated" },
                frame_spp[0],
                frame_spp[1],
                frame_spp[2],
                1u64 << shift.min(63),
                stats.primary_samples as f64 * 1e-6
            ),
            format!(
                "history {} frames since reset  effective spp {}/{}/{}  denoiser {}",
                self.accumulated,
                eff[0],
                eff[1],
                eff[2],
                if self.denoise { "on" } else { "off" }
            ),
            pass_line(stats),
            format!(
                "gaze {:.0},{:.0} ({})  speed {:.3}/s",
                self.gaze[0],
                self.gaze[1],
                self.options.gaze.describe(),
                self.fly.speed()
            ),
            "U uniform  O overlay  N denoise  C config  Space pause  P shot  R reset  H hide"
                .to_string(),
        ];
        let budget = self.options.budget_ms;
        if budget > 0.0 && frame_spp == [1, 1, 1] && frame_ms > 1.2 * budget {
            lines.push(format!(
                "over the {budget:.0} ms budget at one sample per block: the per-pixel passes \
                 dominate; try --render-scale 0.5"
            ));
        }
        lines
    }

    fn screenshot(&mut self, record: &FrameRecord) -> Result<()> {
        let renderer = self.renderer.as_mut().expect("the window is open");
        let mean = renderer.mean_hdr()?;
        let foveation = self.last_foveation.expect("a frame was rendered");
        let pose = self.fly.pose();
        let details = json!({
            "backend": renderer.backend_name,
            "device": renderer.device,
            "scene": self.options.scene,
            "seed": self.options.settings.seed,
            "camera": {
                "eye": fovea_scene::rebase::to_world(pose.eye.to_array(), self.scene.origin),
                "forward": pose.forward.to_array(),
                "fov_y_degrees": pose.fov_y_degrees,
            },
        });
        let path = write_screenshot(
            &self.options.screenshot_dir,
            &mean,
            self.options.settings.exposure_ev,
            &foveation,
            record,
            details,
        )?;
        if !self.options.quiet {
            eprintln!("screenshot: {}", path.display());
        }
        self.screenshots.push(path.display().to_string());
        Ok(())
    }

    /// After the event loop: the run's error, or the stats file and a summary line.
    fn finish(mut self) -> Result<()> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.write_stats(true)?;
        if !self.options.quiet {
            let frame_ms: Vec<f64> = self.records.iter().map(|r| r.frame_ms).collect();
            if let Some(m) = median(&frame_ms) {
                eprintln!(
                    "fovea view: {} frames, median {:.1} ms ({:.1} fps)",
                    self.records.len(),
                    m,
                    1e3 / m.max(1e-9)
                );
            }
        }
        // The renderer (and its surface) goes before the window.
        self.renderer = None;
        self.window = None;
        Ok(())
    }

    fn open_window(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let [w, h] = self.options.window_size;
        let attributes = Window::default_attributes()
            .with_title("fovea view")
            .with_inner_size(PhysicalSize::new(w, h));
        let window = event_loop
            .create_window(attributes)
            .map_err(|e| FoveaError::View(format!("cannot open a window: {e}")))?;
        let handles = fovea_vulkan::WindowHandles {
            display: window
                .display_handle()
                .map_err(|e| FoveaError::View(format!("the window has no display handle: {e}")))?
                .as_raw(),
            window: window
                .window_handle()
                .map_err(|e| FoveaError::View(format!("the window has no handle: {e}")))?
                .as_raw(),
        };
        let size = window.inner_size();
        self.window_size = [size.width, size.height];
        let renderer = LiveRenderer::new(
            handles,
            self.options.device,
            self.options.traversal,
            self.use_gpu,
            self.options.threads,
            &self.scene.packed,
            self.options.specialize,
        )?;
        self.renderer = Some(renderer);
        self.window = Some(window);
        self.request_redraw();
        Ok(())
    }
}

/// The viewer's key for a physical key, if it has one.
/// The HUD line of the frame's pass timings ("passes -" where the backend timed only the whole frame).
fn pass_line(stats: &fovea_cpu::RenderStats) -> String {
    if stats.passes.is_empty() {
        return "passes -".to_string();
    }
    let parts: Vec<String> = stats
        .passes
        .iter()
        .map(|(name, ms)| format!("{name} {ms:.1}"))
        .collect();
    format!("passes (ms) {}", parts.join("  "))
}

fn view_key(code: KeyCode) -> Option<ViewKey> {
    Some(match code {
        KeyCode::KeyW => ViewKey::W,
        KeyCode::KeyA => ViewKey::A,
        KeyCode::KeyS => ViewKey::S,
        KeyCode::KeyD => ViewKey::D,
        KeyCode::KeyQ => ViewKey::Q,
        KeyCode::KeyE => ViewKey::E,
        KeyCode::ShiftLeft | KeyCode::ShiftRight => ViewKey::Shift,
        KeyCode::KeyU => ViewKey::U,
        KeyCode::KeyO => ViewKey::O,
        KeyCode::KeyN => ViewKey::N,
        KeyCode::KeyC => ViewKey::C,
        KeyCode::Space => ViewKey::Space,
        KeyCode::KeyP => ViewKey::P,
        KeyCode::KeyR => ViewKey::R,
        KeyCode::KeyH => ViewKey::H,
        KeyCode::Escape => ViewKey::Escape,
        _ => return None,
    })
}

impl ApplicationHandler for Viewer {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() {
            if let Err(e) = self.open_window(event_loop) {
                self.fail(event_loop, e);
            }
        }
    }

    fn new_events(&mut self, event_loop: &ActiveEventLoop, cause: StartCause) {
        // A minimised, paused or converged scripted run still advances its clock, so that its
        // `restore` or `press Space` comes, and a run with `--exit-after-frames` still ends.
        if matches!(cause, StartCause::ResumeTimeReached { .. })
            && self.counts_idle_frames()
            && self.window.is_some()
            && !self.wants_frame()
            && !self.exit
        {
            self.next_idle_tick = Instant::now() + IDLE_TICK;
            self.tick(event_loop);
            self.request_redraw();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if self.exit {
            return;
        }
        match event {
            WindowEvent::CloseRequested => {
                self.exit = true;
                event_loop.exit();
            }
            WindowEvent::Resized(size) => {
                self.minimized = size.width == 0 || size.height == 0;
                if !self.minimized {
                    self.window_size = [size.width, size.height];
                }
                self.request_redraw();
            }
            WindowEvent::Occluded(occluded) if !self.scripted() => {
                self.minimized = occluded;
                self.request_redraw();
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    if let Some(k) = view_key(code) {
                        self.key(
                            k,
                            event.state == ElementState::Pressed,
                            event.repeat,
                            event_loop,
                        );
                        self.request_redraw();
                    }
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.cursor_moved(position.x, position.y, Instant::now());
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Right,
                ..
            } => {
                self.looking = state == ElementState::Pressed;
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.fly.scroll(steps);
                self.request_redraw();
            }
            WindowEvent::RedrawRequested if self.wants_frame() => self.tick(event_loop),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.exit {
            return;
        }
        let live_gaze = !matches!(self.options.gaze, GazeInput::Mouse);
        if live_gaze && !self.wants_frame() && !self.paused && !self.minimized {
            // Converged: a new gaze sample renders again (into the same history).
            self.poll_gaze();
        }
        if self.wants_frame() {
            self.request_redraw();
            event_loop.set_control_flow(ControlFlow::Wait);
        } else if self.counts_idle_frames() {
            event_loop.set_control_flow(ControlFlow::WaitUntil(
                self.next_idle_tick
                    .max(Instant::now() + Duration::from_millis(1)),
            ));
        } else if live_gaze && !self.paused && !self.minimized {
            // Converged: look for the eye tracker's next sample now and then.
            event_loop.set_control_flow(ControlFlow::WaitUntil(
                Instant::now() + Duration::from_millis(5),
            ));
        } else {
            // Minimised, paused or converged: sleep until input arrives (no busy spin).
            event_loop.set_control_flow(ControlFlow::Wait);
        }
    }
}
