//! Command-line options of `fovea` (clap).
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::values::{
    whole_number, ArrayTask, BlockTriple, DisplayCm, Eccentricity, Ipd, PixelPoint, Point3,
    PointLight, RadiiPx, Resolution, Rgb, SampleSelection, SppTriple,
};

/// fovea: a foveated real-time path tracer (after Mohanto, Kluge and Staadt 2023).
#[derive(Parser, Debug)]
#[command(name = "fovea", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene (the bundled Lost Empire when no SCENE is given).
    Render(Box<RenderArgs>),
    /// Merge the parts of a render split by samples (`render --samples A..B -o PART.fvpart`) into its
    /// image, after checking that they belong to one render and tile its samples.
    Merge(MergeArgs),
    /// How far one linear HDR image (.exr) is from another: the share of pixels that agree within
    /// 1e-3, the largest difference, relMSE and mean FLIP (a render against a reference, the CPU's
    /// frame against a GPU's, fovea against another renderer).
    Compare(CompareArgs),
    /// Error against run time: foveated and uniform configurations measured against a converged
    /// reference (FLIP and relMSE per region, render time, speed-up), written as Markdown, JSON, CSV,
    /// images and an SVG plot.
    Report(Box<ReportArgs>),
    /// Benchmarks: BVH build throughput, ray traversal throughput, and a generated 10 M-triangle scene
    /// (load, build, render, peak memory).
    Bench(BenchArgs),
    /// Live view: a window whose fovea follows the gaze (mouse, an eye tracker over UDP, or a trace),
    /// with fly controls, per-pixel history that survives gaze and camera moves, and a frame-time budget.
    View(Box<ViewArgs>),
    /// A headset through OpenXR: both eyes rendered each frame at the poses and fields of view the
    /// runtime gives, each with its own gaze, foveation and history, into the runtime's swapchain.
    Xr(Box<XrArgs>),
    /// List the devices fovea can render on.
    Devices,
}

/// Where the live view's gaze comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GazeSourceArg {
    /// The mouse pointer.
    Mouse,
    /// Datagrams `t,x,y` on this UDP port of 127.0.0.1.
    Udp(u16),
    /// The `--gaze-trace` file, replayed with its timestamps.
    Trace,
}

impl std::str::FromStr for GazeSourceArg {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let lower = s.to_ascii_lowercase();
        match lower.as_str() {
            "mouse" => Ok(Self::Mouse),
            "trace" => Ok(Self::Trace),
            _ => match lower.strip_prefix("udp:") {
                Some(port) => port
                    .parse::<u16>()
                    .ok()
                    .filter(|&p| p > 0)
                    .map(Self::Udp)
                    .ok_or_else(|| format!("'{port}' is not a UDP port (1 to 65535)")),
                None => Err(format!(
                    "'{s}' is not a gaze source: use mouse, udp:PORT or trace"
                )),
            },
        }
    }
}

/// `WxH` window size, parsed at the edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WindowSize(pub [u32; 2]);

impl std::str::FromStr for WindowSize {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let parts: Vec<&str> = s.split(['x', 'X']).collect();
        let parsed: Option<Vec<u32>> = parts.iter().map(|p| p.trim().parse().ok()).collect();
        match parsed.as_deref() {
            Some(&[w, h]) if (1..=16384).contains(&w) && (1..=16384).contains(&h) => {
                Ok(Self([w, h]))
            }
            _ => Err(format!(
                "'{s}' is not a window size WxH with each edge 1 to 16384"
            )),
        }
    }
}

#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// Scene file (.gltf, .glb or .obj). Default: the bundled Lost Empire.
    pub scene: Option<PathBuf>,

    /// Initial window size (the frame is rendered at the window's size).
    #[arg(
        long,
        default_value = "1280x720",
        value_name = "WxH",
        allow_hyphen_values = true
    )]
    pub size: WindowSize,
    /// Render at this fraction of the window's size (0.1 to 1); the presenter scales the frame up.
    /// Trades sharpness for speed where the per-pixel passes alone exceed the budget.
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "S",
        allow_hyphen_values = true
    )]
    pub render_scale: f32,
    /// Where the gaze comes from: `mouse` (the pointer), `udp:PORT` (an eye tracker sending `t,x,y`
    /// datagrams to 127.0.0.1:PORT; see docs/view.md, "Eye-tracker protocol") or `trace` (--gaze-trace).
    #[arg(long, default_value = "mouse", value_name = "SOURCE")]
    pub gaze_source: GazeSourceArg,
    /// Gaze trace to replay: timed lines `t,x,y` (seconds, counted from the first sample; the default)
    /// or, after a header `frame,x,y`, one line per frame; coordinates as for UDP; commas between the
    /// fields; at most 1,000,000 samples. Implies --gaze-source trace.
    #[arg(long, value_name = "FILE.csv")]
    pub gaze_trace: Option<PathBuf>,
    /// Gaze coordinates are window pixels with the origin at the bottom left (as Pupil exports),
    /// instead of 0..1 of the window with the origin at the top left (as Tobii reports).
    #[arg(long)]
    pub gaze_pixels: bool,
    /// Fixation filter for eye-tracker gaze (udp and trace): I-DT with this dispersion radius in
    /// degrees of visual angle on the display model; the regions sit on each fixation's centroid and
    /// jump at saccades. 0 follows every raw sample.
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "DEG",
        allow_hyphen_values = true
    )]
    pub fixation_filter: f32,
    #[command(flatten)]
    pub foveation: FoveationArgs,
    /// Frame-time budget in milliseconds: frames that would take longer render a fraction of the
    /// configuration's samples and accumulation completes it while the eye rests (0: no budget).
    #[arg(
        long,
        default_value_t = 33.0,
        value_name = "MS",
        allow_hyphen_values = true
    )]
    pub budget_ms: f64,
    #[command(flatten)]
    pub image: ImageArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub lighting: LightingArgs,
    #[command(flatten)]
    pub materials: MtlArgs,
    /// Render with every optional feature on.
    #[arg(long)]
    pub no_specialize: bool,
    /// Start with the region overlay on (toggle with O).
    #[arg(long)]
    pub overlay: bool,
    /// Start with the denoiser on (toggle with N; `fovea_core::denoise`).
    #[arg(long)]
    pub denoise: bool,
    /// Replay timed input events from FILE (see docs/view.md, "Scripted runs").
    #[arg(long, value_name = "FILE")]
    pub script: Option<PathBuf>,
    /// Exit (status 0) after this many frames.
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole_number::<u64>)]
    pub exit_after_frames: Option<u64>,
    /// Take a screenshot after frame K (repeat for several).
    #[arg(long, value_name = "K", allow_hyphen_values = true, value_parser = whole_number::<u64>)]
    pub screenshot_at_frame: Vec<u64>,
    /// Folder for screenshots (P key): fovea_view_FRAME.png, .exr, _regions.png and .json.
    #[arg(long, default_value = "screenshots", value_name = "DIR")]
    pub screenshot_dir: PathBuf,
    /// Write every frame's figures (time, samples, gaze, accumulation, latency) as JSON at exit, and
    /// every few seconds while the view runs ("complete": false), so that a run ended by Ctrl-C or
    /// SIGTERM keeps its figures up to the last few seconds.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// No summary line at exit.
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub target: BackendArgs,
    #[command(flatten)]
    pub path: PathArgs,
}

/// `fovea xr`.
#[derive(Args, Debug, Clone)]
pub struct XrArgs {
    /// Scene file (.gltf, .glb or .obj). Default: the bundled Lost Empire.
    pub scene: Option<PathBuf>,
    /// Each eye's image size (default: the size the runtime recommends).
    #[arg(long, value_name = "WxH", allow_hyphen_values = true)]
    pub size: Option<Resolution>,
    /// End the session after this many rendered frames (default: run until the runtime ends it).
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole_number::<u32>)]
    pub frames: Option<u32>,
    /// Where each eye's gaze comes from: `ahead` (the point straight ahead of each eye) or
    /// `udp:PORT` (an eye tracker's `t,x,y` datagrams, 0..1 of each eye's image, as for `view`).
    #[arg(long, default_value = "ahead", value_name = "SOURCE")]
    pub gaze_source: XrGazeSource,
    /// Scene units per metre of the headset's tracking space (the scene's camera is the origin of
    /// that space).
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "S",
        allow_hyphen_values = true
    )]
    pub world_scale: f64,
    /// Render each frame alone, without each eye's history.
    #[arg(long)]
    pub no_history: bool,
    /// The denoiser after each eye's history.
    #[arg(long)]
    pub denoise: bool,
    #[command(flatten)]
    pub foveation: FoveationArgs,
    #[command(flatten)]
    pub image: ImageArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub lighting: LightingArgs,
    #[command(flatten)]
    pub materials: MtlArgs,
    /// Render with every optional feature on.
    #[arg(long)]
    pub no_specialize: bool,
    /// Write each frame's eye poses (`views.csv`, the format of `render --stereo-views`), each eye's
    /// gaze (`gaze.csv`, a binocular `--gaze-trace`) and each eye's linear image (`f_left_00012.exr`)
    /// to this folder, so that `render` can reproduce the session.
    #[arg(long, value_name = "DIR")]
    pub record: Option<PathBuf>,
    /// Write the session's figures (per eye and frame) as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub target: BackendArgs,
    #[command(flatten)]
    pub path: PathArgs,
}

/// Where `fovea xr` takes each eye's gaze from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum XrGazeSource {
    /// Straight ahead of each eye.
    Ahead,
    /// Datagrams on this UDP port of 127.0.0.1.
    Udp(u16),
}

impl std::str::FromStr for XrGazeSource {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.trim() {
            "ahead" => Ok(Self::Ahead),
            other => match other.strip_prefix("udp:") {
                Some(port) => port
                    .parse::<u16>()
                    .ok()
                    .filter(|&p| p > 0)
                    .map(Self::Udp)
                    .ok_or_else(|| format!("'{port}' is not a UDP port (1 to 65535)")),
                None => Err(format!("'{other}': expected ahead or udp:PORT")),
            },
        }
    }
}

/// Which backend renders.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// Vulkan on a hardware device when there is one, else the CPU.
    Auto,
    Cpu,
    Vulkan,
}

/// How rays find triangles on a Vulkan device.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum Traversal {
    /// Hardware on a GPU with ray queries, else software.
    Auto,
    /// The kernel's own BVH traversal.
    Software,
    /// The driver's acceleration structures (VK_KHR_ray_query); an error without them.
    Hardware,
}

#[cfg(feature = "vulkan")]
impl From<Traversal> for fovea_vulkan::Traversal {
    fn from(t: Traversal) -> Self {
        match t {
            Traversal::Auto => Self::Auto,
            Traversal::Software => Self::Software,
            Traversal::Hardware => Self::Hardware,
        }
    }
}

/// How an OBJ scene's purely diffuse MTL materials (`Ks 0 0 0`, no PBR keys) reflect.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum MtlDiffuse {
    /// Burley's diffuse of the Disney BRDF, the paper's model.
    Disney,
    /// Lambertian, as Mitsuba's and pbrt's `diffuse` material (for comparisons with them).
    Lambert,
}

impl From<MtlDiffuse> for fovea_scene::mesh::MtlDiffuse {
    fn from(m: MtlDiffuse) -> Self {
        match m {
            MtlDiffuse::Disney => Self::Disney,
            MtlDiffuse::Lambert => Self::Lambert,
        }
    }
}

/// How pixels that a block leaves empty are filled.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum Fill {
    /// Bilinear interpolation between neighbouring block-sample centres (the paper's text).
    Bilinear,
    /// Every pixel of a block takes the block's value (the reference code).
    Replicate,
}

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// Scene file (.gltf, .glb or .obj). Default: the bundled Lost Empire.
    pub scene: Option<PathBuf>,

    /// Image size WxH in pixels.
    #[arg(
        long,
        default_value = "1920x1080",
        value_name = "WxH",
        allow_hyphen_values = true
    )]
    pub resolution: Resolution,
    /// Fixation in pixels X,Y (default: the image centre). A gaze off the image is allowed.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub gaze: Option<PixelPoint>,
    #[command(flatten)]
    pub sequence: SequenceArgs,
    #[command(flatten)]
    pub stereo: StereoArgs,
    /// Temporal reuse over the frames of a --gaze-trace: each frame joins every pixel's history
    /// (weighted by its samples and their footprint, as `fovea view` does) and each output image is
    /// the history's mean, not the frame alone.
    #[arg(long)]
    pub history: bool,
    /// Denoise each frame (after the history, if any): an SVGF-like filter whose strength follows the
    /// samples behind each pixel, so the fovea keeps its detail and the periphery is smoothed
    /// (`fovea_core::denoise`).
    #[arg(long)]
    pub denoise: bool,
    /// With --denoise, also write the image as the denoiser found it (the frame, or the history's
    /// mean), .png or .exr; numbered like --output over a sequence.
    #[arg(long, value_name = "FILE")]
    pub keep_raw: Option<PathBuf>,
    #[command(flatten)]
    pub foveation: FoveationArgs,
    #[command(flatten)]
    pub image: ImageArgs,
    /// Frame index (part of the random-number key).
    #[arg(
        long,
        default_value_t = 0,
        value_name = "N",
        allow_hyphen_values = true
    )]
    pub frame: u32,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub lighting: LightingArgs,
    #[command(flatten)]
    pub materials: MtlArgs,
    /// Output image: .png (tone-mapped sRGB) or .exr (linear HDR); with --samples, a part file
    /// (.fvpart).
    #[arg(short, long, default_value = "fovea.png", value_name = "FILE")]
    pub output: PathBuf,
    /// Render one part of a render split over machines: samples A..B of every pixel and block (each
    /// block's own count caps the range), or I/N, part I (from 0) of N equal parts. --output must be
    /// a .fvpart file; `fovea merge` joins the parts into the image the whole render gives. CPU only.
    #[arg(long, value_name = "A..B|I/N", allow_hyphen_values = true)]
    pub samples: Option<SampleSelection>,
    /// Write an image of the regions and blocks over the render.
    #[arg(long, value_name = "FILE.png")]
    pub regions_overlay: Option<PathBuf>,
    /// Write render statistics as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// Print scene details and warnings.
    #[arg(short, long)]
    pub verbose: bool,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    pub quiet: bool,
    /// Render with every optional feature on (the general path), instead of leaving out what the scene
    /// lacks; for comparison (the image is the same).
    #[arg(long)]
    pub no_specialize: bool,
    /// Check the command line (every option, the output paths, that the scene file can be read) and
    /// render nothing: what `scripts/slurm/submit.sh` runs before it submits.
    #[arg(long)]
    pub dry_run: bool,
    #[command(flatten)]
    pub target: BackendArgs,
    #[command(flatten)]
    pub path: PathArgs,
}

#[derive(Args, Debug, Clone)]
pub struct ReportArgs {
    /// Scene files (.gltf, .glb or .obj). Default: the bundled Lost Empire. Several scenes get one
    /// subfolder of --out each.
    pub scenes: Vec<PathBuf>,

    /// Output folder (created if missing).
    #[arg(long, default_value = "report", value_name = "DIR")]
    pub out: PathBuf,
    /// Image size WxH in pixels (default 3840x2160, the paper's; 320x180 with --quick).
    #[arg(long, value_name = "WxH", allow_hyphen_values = true)]
    pub resolution: Option<Resolution>,
    /// Fixation in pixels X,Y (default: the image centre).
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub gaze: Option<PixelPoint>,
    /// Your own samples per pixel / block, measured as one more configuration (with --blocks,
    /// --radii, --eccentricity; the others default to the paper's).
    #[arg(long, value_name = "F,I,P", allow_hyphen_values = true)]
    pub spp: Option<SppTriple>,
    /// Block edges of your own configuration.
    #[arg(long, value_name = "F,I,P", allow_hyphen_values = true)]
    pub blocks: Option<BlockTriple>,
    /// Region radii in pixels of your own configuration (instead of --eccentricity).
    #[arg(long, value_name = "R1,R2", allow_hyphen_values = true)]
    pub radii: Option<RadiiPx>,
    /// Timed runs per configuration; the median render time is reported (default 3; 1 with --quick).
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub runs: Option<u32>,
    /// Samples per pixel of the converged reference (default 1024; 256 with --quick).
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub reference_spp: Option<u32>,
    /// Largest spp of the uniform sweep 1, 2, 4, ... (default 64; 8 with --quick).
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub sweep_max: Option<u32>,
    /// The diffuse lobe of purely diffuse MTL materials (as for `render`).
    #[arg(long, value_enum, default_value = "disney")]
    pub mtl_diffuse: MtlDiffuse,
    /// Small and fast: 320x180, 1 run, a 256 spp reference, sweep to 8 (explicit options still win).
    #[arg(long)]
    pub quick: bool,
    /// Folder of cached references (default: $FOVEA_CACHE_DIR, else $XDG_CACHE_HOME/fovea, else
    /// $HOME/.cache/fovea).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Render the reference again even when a cached one exists (and replace it).
    #[arg(long)]
    pub no_cache: bool,
    /// A folder of parts of the references (a split over machines, docs/cluster.md): with
    /// --reference-part, where this run writes its part; without, where a reference that is not
    /// cached is merged from (all its parts must be there) instead of being rendered.
    #[arg(long, value_name = "DIR")]
    pub reference_parts: Option<PathBuf>,
    /// Render only part I of N of each scene's reference into --reference-parts, and no report (one
    /// task of a job array; CPU backend).
    #[arg(long, value_name = "I/N", allow_hyphen_values = true)]
    pub reference_part: Option<SampleSelection>,
    /// Measure only the scenes of task I of N (every N-th scene from the I-th, counted from 0), each
    /// into its folder under --out, and write no combined report.md: one task of a job array over the
    /// scenes (docs/cluster.md). Each scene's configurations stay on one machine, so that their
    /// speed-ups compare run times of the same hardware.
    #[arg(long, value_name = "I/N", allow_hyphen_values = true)]
    pub task: Option<ArrayTask>,
    /// Render nothing: write the combined report.md of several scenes from their folders under
    /// --out, which --task runs wrote.
    #[arg(long)]
    pub combine: bool,
    // Also judge a sequence (with --gaze-trace): each configuration is rendered frame by frame,
    // uniform and the paper's foveated ones, with and without history, and the error is pooled by
    // eccentricity band and over time (flicker). A --camera-path gives each camera its own
    // converged reference (cached), and history follows the camera as in `view`.
    #[command(flatten)]
    pub sequence: SequenceArgs,
    /// Render at most this many frames of the gaze trace.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub sequence_frames: Option<u32>,
    /// Width of the eccentricity bands the sequence's error is pooled in, in degrees.
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "DEG",
        allow_hyphen_values = true
    )]
    pub band_deg: f32,
    /// Do not score the sequence with FovVideoVDP even where scripts/setup-fvvdp.sh has set it up.
    #[arg(long)]
    pub no_fovvideovdp: bool,

    #[command(flatten)]
    pub display: DisplayArgs,
    #[command(flatten)]
    pub image: ImageArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub lighting: LightingArgs,
    /// No progress bar and no summary.
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub target: BackendArgs,
    #[command(flatten)]
    pub path: PathArgs,
}

/// Where frames render (`render`, `report`, `view`).
#[derive(Args, Debug, Clone, Copy)]
pub struct BackendArgs {
    /// `vulkan`: the rust-gpu kernel on a Vulkan device (lavapipe included); `cpu`: the CPU host;
    /// `auto`: Vulkan on a hardware GPU, else the CPU. (`view --backend cpu` presents through Vulkan.)
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: Backend,
    /// Vulkan device index (see `fovea devices`); default: the first discrete, else integrated GPU.
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    pub device: Option<usize>,
    /// Ray traversal on a Vulkan device: `hardware` uses the driver's acceleration structures
    /// (VK_KHR_ray_query), `software` the kernel's BVH, `auto` hardware on a GPU that has ray queries.
    #[arg(long, value_enum, default_value = "auto")]
    pub traversal: Traversal,
    /// Worker threads of the CPU backend (default: all cores).
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    pub threads: Option<usize>,
}

/// How paths are traced and blocks filled (`render`, `report`, `view`).
#[derive(Args, Debug, Clone)]
pub struct PathArgs {
    /// Bounces per path (3: camera -> x1 -> x2 -> x3 -> light; at most 64).
    #[arg(long, default_value_t = 3, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=64), allow_hyphen_values = true)]
    pub depth: u32,
    /// Russian roulette from this bounce on (0: off).
    #[arg(
        long,
        default_value_t = 0,
        value_name = "N",
        allow_hyphen_values = true
    )]
    pub russian_roulette: u32,
    /// How block pixels are filled.
    #[arg(long, value_enum, default_value = "bilinear")]
    pub fill: Fill,
    /// Which mip level a camera ray's first hit reads: `off`, level 0 (bilinear only); `pixel`, the
    /// footprint of its pixel; `block`, of the sample's block (a periphery sample stands for 4x4 pixels:
    /// two levels coarser than the fovea). Off by default: on texture atlases such as Lost Empire's,
    /// coarse levels mix neighbouring tiles (see docs/performance.md, "Texture level of detail").
    #[arg(long, value_enum, default_value = "off")]
    pub texture_lod: TextureLod,
}

/// `--texture-lod`: see [`PathArgs::texture_lod`].
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureLod {
    Off,
    Pixel,
    Block,
}

impl PathArgs {
    /// The integrator's settings.
    #[must_use]
    pub fn integrator(&self) -> fovea_core::integrator::IntegratorSettings {
        use fovea_core::integrator::path::{TEXTURE_LOD_BLOCK, TEXTURE_LOD_OFF, TEXTURE_LOD_PIXEL};
        fovea_core::integrator::IntegratorSettings {
            max_bounces: self.depth,
            russian_roulette_start: self.russian_roulette,
            texture_lod: match self.texture_lod {
                TextureLod::Off => TEXTURE_LOD_OFF,
                TextureLod::Pixel => TEXTURE_LOD_PIXEL,
                TextureLod::Block => TEXTURE_LOD_BLOCK,
            },
            ..Default::default()
        }
    }

    /// `FILL_BILINEAR` or `FILL_REPLICATE`.
    #[must_use]
    pub fn fill_mode(&self) -> u32 {
        match self.fill {
            Fill::Bilinear => fovea_core::foveation::fill::FILL_BILINEAR,
            Fill::Replicate => fovea_core::foveation::fill::FILL_REPLICATE,
        }
    }
}

/// The camera (`render` and `report`; `report` applies it to every scene).
#[derive(Args, Debug, Clone)]
pub struct CameraArgs {
    /// Camera position (with --target).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub eye: Option<Point3>,
    /// Camera target point (with --eye).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub target: Option<Point3>,
    /// Camera up vector.
    #[arg(
        long,
        default_value = "0,1,0",
        value_name = "X,Y,Z",
        allow_hyphen_values = true
    )]
    pub up: Point3,
    /// Vertical field of view in degrees.
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub fov: Option<f32>,
}

impl CameraArgs {
    /// `--eye`, `--target` (world space, f64) and `--up` (their consistency is checked where the camera
    /// is made).
    #[must_use]
    pub fn points(&self) -> (Option<[f64; 3]>, Option<[f64; 3]>, [f32; 3]) {
        (
            self.eye.map(|p| p.0),
            self.target.map(|p| p.0),
            self.up.0.map(|c| c as f32),
        )
    }
}

/// Light added on the command line (`render` and `report`; `report` applies it to every scene).
#[derive(Args, Debug, Clone)]
pub struct LightingArgs {
    /// Constant environment ("sky") radiance (default: the bundled scene's sky for Lost Empire, none
    /// for other scenes).
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true)]
    pub sky: Option<Rgb>,
    /// Adds a point light at X,Y,Z with intensity R,G,B in W/sr (repeat for several), e.g. to light a
    /// scene that has no emitters.
    #[arg(
        long = "point-light",
        value_name = "X,Y,Z,R,G,B",
        allow_hyphen_values = true
    )]
    pub point_lights: Vec<PointLight>,
    /// Equirectangular HDR environment map (.hdr or .exr), importance-sampled.
    #[arg(long, value_name = "FILE")]
    pub env_map: Option<PathBuf>,
    /// Scale of --env-map.
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "S",
        allow_hyphen_values = true
    )]
    pub env_scale: f32,
}

/// The foveation: which samples each region gets (`render`, `view`; `report` measures its own
/// configurations and takes these as an extra one).
#[derive(Args, Debug, Clone)]
pub struct FoveationArgs {
    /// Render every pixel at the fovea's samples per pixel (the paper's baseline; `view`: start so,
    /// toggle with U).
    #[arg(long)]
    pub uniform: bool,
    /// Samples per pixel (fovea) and per block (intermediate, periphery); in `view`, the first
    /// configuration C cycles through.
    #[arg(
        long,
        default_value = "32,16,8",
        value_name = "F,I,P",
        allow_hyphen_values = true
    )]
    pub spp: SppTriple,
    /// Block edge in pixels per region; each must divide the next.
    #[arg(
        long,
        default_value = "1,2,4",
        value_name = "F,I,P",
        allow_hyphen_values = true
    )]
    pub blocks: BlockTriple,
    /// Region radii in pixels (instead of eccentricity angles).
    #[arg(long, value_name = "R1,R2", allow_hyphen_values = true)]
    pub radii: Option<RadiiPx>,
    #[command(flatten)]
    pub display: DisplayArgs,
}

/// How paths become an image: their random numbers and the exposure (`render`, `report`, `view`).
#[derive(Args, Debug, Clone, Copy)]
pub struct ImageArgs {
    /// Exposure compensation in EV (stops) before tone mapping (PNGs, the window, and `report`'s FLIP).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "EV",
        allow_hyphen_values = true,
        value_parser = crate::values::exposure_ev
    )]
    pub exposure: f32,
    /// Seed of all random numbers (`report`'s references use another, so their noise is
    /// independent).
    #[arg(
        long,
        default_value_t = 0,
        value_name = "N",
        allow_hyphen_values = true
    )]
    pub seed: u32,
}

/// A sequence of frames from files (`render`, `report`): a gaze trace, a camera path, or both.
#[derive(Args, Debug, Clone)]
pub struct SequenceArgs {
    /// CSV gaze trace: lines `frame,x,y` (one frame per line) or, after a header `t,x,y`, timed
    /// samples rendered at --trace-fps from the first sample (Unix-epoch seconds work); x,y in image
    /// pixels, origin top-left (or --gaze-normalized); commas between the fields; at most 1,000,000
    /// samples and frames. `render` writes one numbered image per frame.
    #[arg(long, value_name = "FILE.csv")]
    pub gaze_trace: Option<PathBuf>,
    /// Frames per second at which a timed gaze trace (`t,x,y`) is rendered.
    #[arg(
        long,
        default_value_t = 30.0,
        value_name = "FPS",
        allow_hyphen_values = true
    )]
    pub trace_fps: f64,
    /// The gaze trace's x,y are 0..1 of the image (origin top-left), as `fovea view` reads them.
    #[arg(long)]
    pub gaze_normalized: bool,
    /// CSV camera path with lines `frame,eye_x,eye_y,eye_z,target_x,target_y,target_z` (world
    /// coordinates; a header line names those columns, commas between the fields; at most
    /// 1,000,000 frames): each frame's camera. With a --gaze-trace it must give every frame the
    /// trace gives; without one, `render` takes its frames from the path (the gaze stays at --gaze or
    /// the centre), and `report` needs a trace.
    #[arg(long, value_name = "FILE.csv")]
    pub camera_path: Option<PathBuf>,
}

/// Both eyes (`render`): each frame is a left and a right view, each with its own camera, gaze,
/// foveation and history, written as `_left` and `_right` images.
#[derive(Args, Debug, Clone, Default)]
pub struct StereoArgs {
    /// Render both eyes, IPD apart (scene units: 0.064 for a scene in metres), the camera between
    /// them, both looking its way with its frustum. With a --gaze-trace of both eyes (header
    /// `t,lx,ly,rx,ry` or `frame,lx,ly,rx,ry`) each eye gets its own gaze; else both get the one.
    #[arg(long, value_name = "IPD", allow_hyphen_values = true)]
    pub stereo: Option<Ipd>,
    /// Render both eyes from each frame's eye poses and frusta, in OpenXR's conventions: lines
    /// `frame,eye,x,y,z,qx,qy,qz,qw,angle_left,angle_right,angle_up,angle_down` (eye `left` or
    /// `right`, world position, unit quaternion of the eye looking along -z, angles in radians);
    /// the foveation radii follow each eye's angles; a header line names those columns, commas
    /// between the fields; at most 1,000,000 frames. Without a --gaze-trace the file numbers the
    /// frames.
    #[arg(long, value_name = "FILE.csv", conflicts_with = "stereo")]
    pub stereo_views: Option<PathBuf>,
}

/// How an OBJ's materials are read (`render`, `view`; `report` takes `--mtl-diffuse` alone).
#[derive(Args, Debug, Clone)]
pub struct MtlArgs {
    /// MTL file to use instead of the one the OBJ names (e.g. Lost Empire's torch variant).
    #[arg(long, value_name = "FILE.mtl")]
    pub mtl: Option<PathBuf>,
    /// The diffuse lobe of purely diffuse MTL materials (`Ks 0 0 0` and no `Pm`, `Pr`, `Ps`, `Pc`,
    /// `aniso`): `lambert` makes an OBJ scene the same scene to Mitsuba or pbrt, whose `diffuse` it is.
    #[arg(long, value_enum, default_value = "disney")]
    pub mtl_diffuse: MtlDiffuse,
}

/// The display model that turns eccentricity angles into region radii (`render`, `report`, `compare`).
#[derive(Args, Debug, Clone)]
pub struct DisplayArgs {
    /// Eccentricity angles in degrees bounding the fovea and the intermediate region.
    #[arg(
        long,
        default_value = "5.2,17",
        value_name = "E1,E2",
        allow_hyphen_values = true
    )]
    pub eccentricity: Eccentricity,
    /// Physical display size in centimetres (the image fills it, whatever --resolution is).
    #[arg(
        long,
        default_value = "70.848x39.852",
        value_name = "WxH",
        allow_hyphen_values = true
    )]
    pub display_cm: DisplayCm,
    /// Viewing distance in centimetres.
    #[arg(
        long,
        default_value_t = 60.0,
        value_name = "D",
        allow_hyphen_values = true
    )]
    pub distance_cm: f32,
}

/// `fovea merge`: the parts of a split render into its image (see `crate::merge`).
#[derive(Args, Debug, Clone)]
pub struct MergeArgs {
    /// Part files (.fvpart) written by `fovea render --samples A..B`, in any order.
    #[arg(required = true, value_name = "PARTS")]
    pub parts: Vec<PathBuf>,
    /// Output image: .png (tone-mapped sRGB) or .exr (linear HDR).
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// Exposure compensation in EV (stops) before tone mapping (PNG only).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "EV",
        allow_hyphen_values = true,
        value_parser = crate::values::exposure_ev
    )]
    pub exposure: f32,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

/// `fovea compare`: one image against another (see `crate::compare`).
#[derive(Args, Debug, Clone)]
pub struct CompareArgs {
    /// The image to judge (.exr, linear HDR).
    #[arg(value_name = "TEST")]
    pub test: PathBuf,
    /// The image it is judged against (.exr, linear HDR).
    #[arg(value_name = "REFERENCE")]
    pub reference: PathBuf,
    /// Exposure compensation in EV of the tone mapping that FLIP sees (both images).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "EV",
        allow_hyphen_values = true,
        value_parser = crate::values::exposure_ev
    )]
    pub exposure: f32,
    /// Fixation in pixels X,Y: also pool relMSE and FLIP by the foveation regions around it (bounded
    /// by --eccentricity on the display), FLIP at the display's pixels per degree, as `report` does.
    /// The display options below are used only with it.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub gaze: Option<PixelPoint>,
    #[command(flatten)]
    pub display: DisplayArgs,
    /// Also write the figures as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

/// `fovea bench`: build, traversal and scale benchmarks (see `crate::bench`).
#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub what: BenchCommand,
    /// Worker threads (default: all cores).
    #[arg(long, global = true, value_name = "N", allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    pub threads: Option<usize>,
    /// Also write the figures as JSON to this file.
    #[arg(long, global = true, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

#[derive(Subcommand, Debug, Clone)]
pub enum BenchCommand {
    /// BVH build throughput on a scene (default: the bundled Lost Empire).
    Build {
        /// Scene file (.gltf, .glb or .obj).
        scene: Option<PathBuf>,
        /// Builds to time; the median is reported.
        #[arg(long, default_value_t = 5)]
        runs: u32,
    },
    /// Ray-traversal throughput alone: closest-hit and occlusion queries, no shading.
    Rays {
        /// Scene file (.gltf, .glb or .obj); default: the bundled Lost Empire.
        scene: Option<PathBuf>,
        /// Ray file: little-endian f32 records of origin xyz, direction xyz, t_max (inf: none) and
        /// kind (0 closest hit, 1 occlusion). Default: `--count` rays generated in the scene's bounds.
        #[arg(long, value_name = "FILE")]
        rays: Option<PathBuf>,
        /// Rays to generate (half closest-hit, half occlusion) when no ray file is given.
        #[arg(long, default_value_t = 1 << 21)]
        count: usize,
        /// Seed of the generated rays.
        #[arg(long, default_value_t = 1)]
        seed: u32,
        /// Timed passes over all rays; the median is reported (after one untimed warm-up pass).
        #[arg(long, default_value_t = 5)]
        runs: u32,
    },
    /// Generate, build and render a procedural scene of N triangles; report times and peak memory.
    /// The CPU's specialised render path (only the features the scene uses compiled in) against the
    /// general one (`--no-specialize`), one frame rendered by each in turn in one process: each
    /// path's median frame time, their ratio, and whether their images are identical.
    Paths(Box<PathsArgs>),
    Scale {
        /// Triangles to generate.
        #[arg(long, default_value_t = 10_000_000)]
        triangles: u64,
        /// Image size WxH.
        #[arg(
            long,
            default_value = "3840x2160",
            value_name = "WxH",
            allow_hyphen_values = true
        )]
        resolution: Resolution,
    },
}

/// `fovea bench paths`: the frame both CPU paths render.
#[derive(Args, Debug, Clone)]
pub struct PathsArgs {
    /// Scene file (.gltf, .glb or .obj). Default: the bundled Lost Empire.
    pub scene: Option<PathBuf>,
    /// Image size WxH in pixels.
    #[arg(
        long,
        default_value = "1920x1080",
        value_name = "WxH",
        allow_hyphen_values = true
    )]
    pub resolution: Resolution,
    /// Rounds; each renders the frame once with each path (the order alternates).
    #[arg(long, default_value_t = 5, value_parser = whole_number::<u32>)]
    pub rounds: u32,
    #[command(flatten)]
    pub foveation: FoveationArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub lighting: LightingArgs,
    #[command(flatten)]
    pub materials: MtlArgs,
    #[command(flatten)]
    pub path: PathArgs,
}
