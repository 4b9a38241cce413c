//! FovVideoVDP (Mantiuk et al. 2021) on a report's sequence, through its Python package `pyfvvdp`,
//! which `scripts/setup-fvvdp.sh` sets up in its own virtual environment. fovea does not re-implement
//! the metric: it writes each sequence and its reference as raw 8-bit sRGB frames, with one fixation
//! per frame and its display model, and reads back the JOD and the metric's info string.
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use fovea_core::foveation::display::DisplayGeometry;

/// What FovVideoVDP (Mantiuk et al. 2021) said of a test sequence against its reference.
#[derive(Clone, Debug, PartialEq)]
pub struct FovVideoVdpScore {
    /// Just-objectionable differences: 10 is identical, 1 JOD less is preferred by 75 % of viewers.
    pub jod: f64,
    /// The metric's own description of its version and settings.
    pub info: String,
    /// Its run time, seconds.
    pub seconds: f64,
}

/// The scoring script, written next to the frames it scores.
const SCORE_SCRIPT: &str = include_str!("fvvdp_score.py");

/// The display's photometry the metric assumes: an SDR office monitor (peak 200 cd/m², 1000:1,
/// sRGB, no ambient light).
pub const PEAK_CD_M2: f64 = 200.0;
pub const CONTRAST: f64 = 1000.0;

/// Where `scripts/setup-fvvdp.sh` puts the environment: `$FOVEA_FVVDP_VENV`, else
/// `$XDG_CACHE_HOME/fovea/fvvdp-venv`, else `~/.cache/fovea/fvvdp-venv`.
#[must_use]
pub fn venv_dir() -> Option<PathBuf> {
    if let Some(v) = std::env::var_os("FOVEA_FVVDP_VENV") {
        return Some(PathBuf::from(v));
    }
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(cache.join("fovea").join("fvvdp-venv"))
}

/// A Python that imports `pyfvvdp`.
pub struct FovVideoVdp {
    python: PathBuf,
}

impl FovVideoVdp {
    /// The set-up environment, or why there is none (a sentence for the report).
    pub fn find() -> Result<Self, String> {
        let venv = venv_dir().ok_or("no home folder to look for its environment in")?;
        let python = venv.join("bin").join("python");
        let how =
            "run `bash scripts/setup-fvvdp.sh` once (or set FOVEA_FVVDP_VENV), then report again";
        if !python.is_file() {
            return Err(format!(
                "not set up ({} is missing): {how}",
                python.display()
            ));
        }
        let ok = Command::new(&python)
            .args(["-c", "import pyfvvdp, torch"])
            .output()
            .map_err(|e| format!("cannot run {}: {e}", python.display()))?;
        if !ok.status.success() {
            return Err(format!(
                "{} cannot import pyfvvdp: {}; {how}",
                python.display(),
                String::from_utf8_lossy(&ok.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
            ));
        }
        Ok(Self { python })
    }

    /// Scores the `frames` frames of `test` (raw RGB8, `width × height`) against `reference` (one frame
    /// or as many as `test`) at `fps`, with one fixation per frame in pixels, on `display`. `dir` holds
    /// the job file and script.
    #[allow(clippy::too_many_arguments)]
    pub fn score(
        &self,
        dir: &Path,
        test: &Path,
        reference: &Path,
        size: [u32; 2],
        frames: u32,
        fps: f64,
        fixations: &[[f32; 2]],
        display: &DisplayGeometry,
    ) -> Result<FovVideoVdpScore, String> {
        let script = dir.join("fvvdp_score.py");
        std::fs::write(&script, SCORE_SCRIPT)
            .map_err(|e| format!("cannot write {}: {e}", script.display()))?;
        // pyfvvdp's fixation is a pixel index (it adds 0.5 for the centre); fovea's gaze is continuous.
        let fixations: Vec<[f32; 2]> = fixations.iter().map(|g| [g[0] - 0.5, g[1] - 0.5]).collect();
        let job = serde_json::json!({
            "test": test,
            "reference": reference,
            "width": size[0],
            "height": size[1],
            "frames": frames,
            "fps": fps,
            "fixations": fixations,
            "display": {
                "width_cm": display.width_cm,
                "height_cm": display.height_cm,
                "distance_cm": display.distance_cm,
                "peak_cd_m2": PEAK_CD_M2,
                "contrast": CONTRAST,
            },
        });
        let job_path = dir.join("fvvdp_job.json");
        std::fs::write(&job_path, job.to_string())
            .map_err(|e| format!("cannot write {}: {e}", job_path.display()))?;
        let out = Command::new(&self.python)
            .arg(&script)
            .arg(&job_path)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", self.python.display()))?;
        let _ = std::fs::remove_file(&job_path);
        let _ = std::fs::remove_file(&script);
        if !out.status.success() {
            return Err(format!(
                "FovVideoVDP failed: {}",
                String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .last()
                    .unwrap_or("no message")
            ));
        }
        let stdout = String::from_utf8_lossy(&out.stdout);
        let line = stdout.lines().last().unwrap_or("");
        let v: serde_json::Value = serde_json::from_str(line)
            .map_err(|e| format!("FovVideoVDP's answer is not JSON ({e}): {line}"))?;
        Ok(FovVideoVdpScore {
            jod: v["jod"].as_f64().unwrap_or(f64::NAN),
            info: v["info"].as_str().unwrap_or("").to_string(),
            seconds: v["seconds"].as_f64().unwrap_or(f64::NAN),
        })
    }
}

/// Appends RGB8 frames to a raw file (frames × height × width × 3).
pub struct RawFrames {
    pub path: PathBuf,
    file: std::io::BufWriter<std::fs::File>,
}

impl RawFrames {
    pub fn create(path: PathBuf) -> Result<Self, String> {
        let file = std::fs::File::create(&path)
            .map_err(|e| format!("cannot create {}: {e}", path.display()))?;
        Ok(Self {
            path,
            file: std::io::BufWriter::new(file),
        })
    }

    pub fn push(&mut self, rgb8: &[u8]) -> Result<(), String> {
        self.file
            .write_all(rgb8)
            .map_err(|e| format!("cannot write {}: {e}", self.path.display()))
    }

    pub fn finish(mut self) -> Result<PathBuf, String> {
        self.file
            .flush()
            .map_err(|e| format!("cannot write {}: {e}", self.path.display()))?;
        Ok(self.path)
    }
}
