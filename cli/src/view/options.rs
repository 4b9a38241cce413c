//! `fovea view`'s command line, parsed and checked before a window opens: every bad value, missing
//! file or port in use fails here with a message that names the option.
use std::net::{Ipv4Addr, SocketAddr};
use std::path::PathBuf;

use crate::args::{Backend, GazeSourceArg, ViewArgs};
use crate::error::{FoveaError, Result};
use crate::gaze::{GazeConvention, GazeTrace, TraceTiming, UdpGazeSource};
use crate::scene_setup::Lighting;
use crate::schedule::FrameSettings;
use crate::values;
use crate::view::sampling::{configurations, SamplingConfig};
use crate::view::script::Script;

/// How region radii follow the window: fixed pixels (`--radii`), or eccentricity angles on the display
/// model, which the window's width fills (so the radii scale with the window).
#[derive(Clone, Copy, Debug)]
pub enum RadiiRule {
    Pixels([f32; 2]),
    Eccentricity {
        degrees: values::Eccentricity,
        display_cm: values::DisplayCm,
        distance_cm: f32,
    },
}

impl RadiiRule {
    /// The radii in pixels for a window of `size`.
    #[must_use]
    pub fn radii_px(&self, size: [u32; 2]) -> [f32; 2] {
        match *self {
            Self::Pixels(r) => r,
            Self::Eccentricity {
                degrees,
                display_cm,
                distance_cm,
            } => values::eccentricity_radii(
                degrees,
                &values::display_at(display_cm, distance_cm, size),
            ),
        }
    }
}

/// The live gaze source, opened.
pub enum GazeInput {
    Mouse,
    Udp(UdpGazeSource),
    Trace(GazeTrace),
}

impl GazeInput {
    /// "mouse", "udp 127.0.0.1:PORT" or "trace".
    pub fn describe(&self) -> String {
        match self {
            Self::Mouse => "mouse".into(),
            Self::Udp(u) => format!("udp {}", u.local_addr()),
            Self::Trace(_) => "trace".into(),
        }
    }
}

/// Everything the view needs, checked.
pub struct ViewOptions {
    pub scene: Option<PathBuf>,
    pub mtl: Option<PathBuf>,
    pub mtl_diffuse: fovea_scene::mesh::MtlDiffuse,
    pub lighting: Lighting,
    pub backend: Backend,
    pub device: Option<usize>,
    pub traversal: crate::args::Traversal,
    pub threads: Option<usize>,
    pub specialize: bool,
    pub window_size: [u32; 2],
    /// Frames are rendered at this fraction of the window's size.
    pub render_scale: f32,
    pub gaze: GazeInput,
    pub configs: Vec<SamplingConfig>,
    pub radii: RadiiRule,
    /// The fixation filter's radius in degrees (0: raw gaze) and the display model it is measured on.
    pub fixation_filter_deg: f32,
    pub display: (values::DisplayCm, f32),
    pub uniform: bool,
    pub overlay: bool,
    pub denoise: bool,
    pub budget_ms: f64,
    /// What every frame shares; its size is the first window's, and each frame takes the rendered
    /// size of its own ([`FrameSettings::with_size`]).
    pub settings: FrameSettings,
    /// `--eye`, `--target`, `--up`.
    pub camera: (Option<[f64; 3]>, Option<[f64; 3]>, [f32; 3]),
    pub fov: Option<f32>,
    pub script: Option<Script>,
    pub exit_after_frames: Option<u64>,
    pub screenshot_frames: Vec<u64>,
    pub screenshot_dir: PathBuf,
    pub stats: Option<PathBuf>,
    pub quiet: bool,
}

/// `--screenshot-dir` must be a folder or a path one can be made at (not through a file), checked at
/// start; a `--screenshot-at-frame` after `--exit-after-frames` would never come.
fn check_screenshots(args: &ViewArgs) -> Result<()> {
    let dir = &args.screenshot_dir;
    if dir.exists() && !dir.is_dir() {
        return Err(FoveaError::option(
            "--screenshot-dir",
            format!("'{}' is a file, not a folder", dir.display()),
        ));
    }
    // The folder, or the nearest one above it that exists (where it will be made), takes files: a
    // probe, so that a read-only mount or /proc is named now, not at the first screenshot.
    if let Some(existing) = dir
        .ancestors()
        .find(|a| a.is_dir() || a.as_os_str().is_empty())
    {
        let existing = if existing.as_os_str().is_empty() {
            std::path::Path::new(".")
        } else {
            existing
        };
        crate::output::check_folder_takes_files(existing)
            .map_err(|why| FoveaError::option("--screenshot-dir", why))?;
    }
    if let Some(file) = dir.ancestors().skip(1).find(|a| a.is_file()) {
        return Err(FoveaError::option(
            "--screenshot-dir",
            format!(
                "'{}' is a file, so '{}' cannot be a folder",
                file.display(),
                dir.display()
            ),
        ));
    }
    if let Some(exit) = args.exit_after_frames {
        if let Some(k) = args.screenshot_at_frame.iter().find(|&&k| k > exit) {
            return Err(FoveaError::option(
                "--screenshot-at-frame",
                format!("{k} comes after --exit-after-frames {exit}: the view ends first"),
            ));
        }
    }
    Ok(())
}

/// The memory the system can still give, from `/proc/meminfo`'s `MemAvailable` (Linux); `None`
/// elsewhere.
fn available_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The CPU backend's frames at `--size` × `--render-scale` must fit in `available` bytes: refused up
/// front, with the memory they would need, rather than aborting on allocation.
fn check_cpu_frame_memory(size: [u32; 2], render_scale: f32, available: Option<u64>) -> Result<()> {
    let Some(available) = available else {
        return Ok(());
    };
    let scaled = |e: u32| (f64::from(e) * f64::from(render_scale)).ceil().max(1.0) as u64;
    let needed = scaled(size[0]) * scaled(size[1]) * fovea_cpu::FRAME_BYTES_PER_PIXEL;
    if needed > available {
        let gib = |b: u64| b as f64 / f64::from(1u32 << 30);
        return Err(FoveaError::option(
            "--size",
            format!(
                "{}x{} needs about {:.1} GiB for the CPU backend's frames (history and denoiser \
                 included), and this machine has {:.1} GiB available: choose a smaller --size or \
                 --render-scale, or --backend vulkan",
                size[0],
                size[1],
                gib(needed),
                gib(available)
            ),
        ));
    }
    Ok(())
}

impl ViewOptions {
    pub fn from_args(args: &ViewArgs) -> Result<Self> {
        let (spp, blocks) = (args.foveation.spp.0, args.foveation.blocks.0);
        // The display model, checked as `render` checks it (the window's size only scales the radii;
        // its aspect follows the window, so no aspect warning here).
        values::display_geometry(
            args.foveation.display.display_cm,
            args.foveation.display.distance_cm,
            [1, 1],
        )?;
        let radii = match args.foveation.radii {
            Some(r) => RadiiRule::Pixels(r.0),
            None => RadiiRule::Eccentricity {
                degrees: args.foveation.display.eccentricity,
                display_cm: args.foveation.display.display_cm,
                distance_cm: args.foveation.display.distance_cm,
            },
        };
        if !(args.fixation_filter.is_finite() && (0.0..=30.0).contains(&args.fixation_filter)) {
            return Err(FoveaError::option(
                "--fixation-filter",
                "must be 0 (raw gaze) to 30 degrees",
            ));
        }
        let convention = if args.gaze_pixels {
            GazeConvention::PixelsBottomLeft
        } else {
            GazeConvention::Normalized
        };
        let gaze = match (&args.gaze_source, &args.gaze_trace) {
            (GazeSourceArg::Udp(_), Some(_)) => {
                return Err(FoveaError::option(
                    "--gaze-trace",
                    "replays a trace; it cannot be combined with --gaze-source udp:PORT",
                ))
            }
            (GazeSourceArg::Trace, None) => {
                return Err(FoveaError::option(
                    "--gaze-source",
                    "`trace` needs --gaze-trace FILE.csv",
                ))
            }
            (GazeSourceArg::Mouse | GazeSourceArg::Trace, Some(path)) => GazeInput::Trace(
                GazeTrace::read(path, convention, TraceTiming::Seconds)
                    .map_err(|e| FoveaError::option("--gaze-trace", e))?,
            ),
            (GazeSourceArg::Udp(port), None) => {
                let addr = SocketAddr::from((Ipv4Addr::LOCALHOST, *port));
                GazeInput::Udp(
                    UdpGazeSource::bind(addr, convention)
                        .map_err(|e| FoveaError::option("--gaze-source", e))?,
                )
            }
            (GazeSourceArg::Mouse, None) => {
                if args.gaze_pixels {
                    return Err(FoveaError::option(
                        "--gaze-pixels",
                        "applies to --gaze-source udp:PORT and --gaze-trace, not to the mouse",
                    ));
                }
                GazeInput::Mouse
            }
        };
        if !(args.budget_ms.is_finite() && (0.0..=60_000.0).contains(&args.budget_ms)) {
            return Err(FoveaError::option(
                "--budget-ms",
                "must be 0 (no budget) to 60000 milliseconds",
            ));
        }
        if args.target.backend == Backend::Cpu && args.target.device.is_some() {
            // The device still presents, so it is allowed: say what it does.
            eprintln!("note: --device selects the Vulkan device that presents the CPU's frames");
        }
        let script = args
            .script
            .as_deref()
            .map(Script::read)
            .transpose()
            .map_err(|e| FoveaError::option("--script", e.to_string()))?;
        if let Some(p) = &args.stats {
            crate::output::check_json_path(p, "--stats")?;
        }
        if !(args.render_scale.is_finite() && (0.1..=1.0).contains(&args.render_scale)) {
            return Err(FoveaError::option(
                "--render-scale",
                format!("{} is not between 0.1 and 1", args.render_scale),
            ));
        }
        if args.exit_after_frames == Some(0) {
            return Err(FoveaError::option(
                "--exit-after-frames",
                "must be at least 1",
            ));
        }
        check_screenshots(args)?;
        if args.target.backend != Backend::Vulkan {
            check_cpu_frame_memory(args.size.0, args.render_scale, available_memory_bytes())?;
        }
        let camera = args.camera.points();
        if let Some(f) = args.camera.fov {
            if !(f > 0.0 && f < 180.0) {
                return Err(FoveaError::option(
                    "--fov",
                    format!("{f} is not in (0, 180) degrees"),
                ));
            }
        }
        Ok(Self {
            scene: args.scene.clone(),
            mtl: args.materials.mtl.clone(),
            mtl_diffuse: args.materials.mtl_diffuse.into(),
            lighting: Lighting::from_args(&args.lighting)?,
            backend: args.target.backend,
            device: args.target.device,
            traversal: args.target.traversal,
            threads: args.target.threads,
            specialize: !args.no_specialize,
            window_size: args.size.0,
            render_scale: args.render_scale,
            gaze,
            configs: configurations(spp, blocks),
            radii,
            fixation_filter_deg: args.fixation_filter,
            display: (
                args.foveation.display.display_cm,
                args.foveation.display.distance_cm,
            ),
            uniform: args.foveation.uniform,
            overlay: args.overlay,
            denoise: args.denoise,
            budget_ms: args.budget_ms,
            settings: FrameSettings::new(args.size.0, &args.path, &args.image),
            camera,
            fov: args.camera.fov,
            script,
            exit_after_frames: args.exit_after_frames,
            screenshot_frames: args.screenshot_at_frame.clone(),
            screenshot_dir: args.screenshot_dir.clone(),
            stats: args.stats.clone(),
            quiet: args.quiet,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_size_whose_cpu_frames_do_not_fit_in_memory_is_refused_with_what_it_needs() {
        let gib = 1u64 << 30;
        assert!(check_cpu_frame_memory([1280, 720], 1.0, Some(gib)).is_ok());
        assert!(
            check_cpu_frame_memory([16384, 16384], 1.0, None).is_ok(),
            "unknown: allowed"
        );
        let e = check_cpu_frame_memory([16384, 16384], 1.0, Some(4 * gib))
            .unwrap_err()
            .to_string();
        let needed = 16384.0 * 16384.0 * fovea_cpu::FRAME_BYTES_PER_PIXEL as f64 / gib as f64;
        assert!(
            e.contains(&format!("needs about {needed:.1} GiB")) && e.contains("4.0 GiB available"),
            "{e}"
        );
        // --render-scale renders fewer pixels.
        assert!(check_cpu_frame_memory([16384, 16384], 0.1, Some(4 * gib)).is_ok());
    }
}
