//! `fovea-gpu-builder OUT.spv`: compiles the rust-gpu kernel crate (`gpu-kernel/`, which calls into
//! `fovea-core`) to one SPIR-V module for Vulkan 1.2 and copies it to `OUT.spv`.
//!
//! spirv-builder runs a nested `cargo` with the pinned nightly and the `rustc_codegen_spirv` backend, then
//! runs spirv-opt and spirv-val on the result (the Debian `spirv-tools` through `use-installed-tools`).
//! spirv-opt stays on: it fuses `a * b + c` into `Fma`, but lavapipe splits `Fma` back into a multiply and
//! an add (llvmpipe's NIR option `lower_ffma32`), so `--no-spirv-opt` renders the same pixels there while
//! the module grows from 0.3 to 1.7 MB and pipeline creation and frames get slower (README, "GPU build").
//! `host-vulkan/build.rs` runs this binary; it can also be run by hand:
//!
//! ```text
//! cargo +nightly-2026-08-15 run --release --manifest-path gpu-builder/Cargo.toml \
//!     --target-dir target/gpu-builder -- /tmp/fovea-kernel.spv
//! ```
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use spirv_builder::{ModuleResult, SpirvBuilder};

/// The nightly rust-gpu 0.11.0 needs (also pinned in `rust-toolchain.toml` and `scripts/setup.sh`).
const NIGHTLY: &str = "nightly-2026-08-15";
/// The SPIR-V target: Vulkan 1.2 (storage buffers, no extensions beyond core).
const TARGET: &str = "spirv-unknown-vulkan1.2";

fn repo_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let root = here
        .parent()
        .expect("gpu-builder lives in the repository root");
    root.canonicalize().unwrap_or_else(|_| root.to_path_buf())
}

fn run(out: &Path) -> Result<(), String> {
    let root = repo_root();
    let kernel = root.join("gpu-kernel");
    let target_dir = root.join("target").join("spirv");

    // ImageBuffer: the scene texel buffer core reads its large arrays from (core's `scene::source`).
    let mut builder =
        SpirvBuilder::new(&kernel, TARGET).capability(spirv_builder::Capability::ImageBuffer);
    builder.toolchain_overwrite = Some(NIGHTLY.into());
    builder.target_dir_path = Some(target_dir);
    let result = builder
        .build()
        .map_err(|e| format!("building {} failed: {e}", kernel.display()))?;
    let module = match result.module {
        ModuleResult::SingleModule(path) => path,
        ModuleResult::MultiModule(_) => return Err("expected a single SPIR-V module".into()),
    };

    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
    }
    // Copy then rename, so a reader never sees a half-written module.
    let tmp = out.with_extension("spv.tmp");
    std::fs::copy(&module, &tmp)
        .map_err(|e| format!("copying {} to {}: {e}", module.display(), tmp.display()))?;
    std::fs::rename(&tmp, out).map_err(|e| format!("renaming to {}: {e}", out.display()))?;
    let size = std::fs::metadata(out).map(|m| m.len()).unwrap_or(0);
    eprintln!(
        "fovea-gpu-builder: {} ({size} bytes, {} entry points)",
        out.display(),
        result.entry_points.len()
    );
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 1 || args[0].starts_with('-') {
        eprintln!("usage: fovea-gpu-builder OUT.spv");
        return ExitCode::from(2);
    }
    match run(Path::new(&args[0])) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("fovea-gpu-builder: {e}");
            ExitCode::FAILURE
        }
    }
}
