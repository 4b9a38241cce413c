//! `fovea-gpu-builder OUT.spv OUT-RAY-QUERY.spv`: compiles the rust-gpu kernel crate (`gpu-kernel/`,
//! which calls into `fovea-core`) to two SPIR-V modules for Vulkan 1.2: `OUT.spv`, which traverses the
//! software BVH, and `OUT-RAY-QUERY.spv`, built with the `RayQueryKHR` capability and
//! `SPV_KHR_ray_query`, whose traversal asks the driver's acceleration structures (`--traversal
//! hardware`). Capabilities are module-wide, so a device without ray queries could not even load a
//! module that declares them: hence two modules rather than one.
//!
//! spirv-builder runs a nested `cargo` with the pinned nightly and the `rustc_codegen_spirv` backend, then
//! runs spirv-opt and spirv-val on the result (the Debian `spirv-tools` through `use-installed-tools`).
//! spirv-opt stays on: it fuses `a * b + c` into `Fma`, but lavapipe splits `Fma` back into a multiply and
//! an add (llvmpipe's NIR option `lower_ffma32`), so `--no-spirv-opt` renders the same pixels there while
//! the module grows from 0.3 to 1.7 MB and pipeline creation and frames get slower (docs/architecture.md, "GPU build").
//! `host-vulkan/build.rs` runs this binary; it can also be run by hand:
//!
//! ```text
//! cargo +nightly-2026-08-15 run --release --manifest-path gpu-kernel/builder/Cargo.toml \
//!     --target-dir target/gpu-builder -- /tmp/fovea-kernel.spv /tmp/fovea-kernel-rq.spv
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
        .and_then(Path::parent)
        .expect("the builder lives in gpu-kernel/builder");
    root.canonicalize().unwrap_or_else(|_| root.to_path_buf())
}

/// The kernel's two builds: the plain module (software traversal) and the one with ray queries.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Variant {
    Software,
    RayQuery,
}

/// Builds one variant of the kernel into `out`.
fn build(variant: Variant, out: &Path) -> Result<(), String> {
    let root = repo_root();
    let kernel = root.join("gpu-kernel");
    // Separate target folders: the variants differ in their target features (rustflags), and sharing one
    // folder would rebuild `fovea-core` at every switch.
    let target_dir = root.join("target").join(match variant {
        Variant::Software => "spirv",
        Variant::RayQuery => "spirv-ray-query",
    });

    // ImageBuffer: the scene texel buffer core reads its large arrays from (core's `scene::source`).
    let mut builder =
        SpirvBuilder::new(&kernel, TARGET).capability(spirv_builder::Capability::ImageBuffer);
    if variant == Variant::RayQuery {
        // The kernel's `ray-query` feature turns on core's `bvh::hardware` (rust-gpu 0.11 does not make
        // capabilities visible as `cfg(target_feature)`, although its documentation says so).
        builder = builder
            .capability(spirv_builder::Capability::RayQueryKHR)
            .extension("SPV_KHR_ray_query")
            .shader_crate_features(["ray-query".to_string()]);
    }
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
    if args.len() != 2 || args.iter().any(|a| a.starts_with('-')) {
        eprintln!("usage: fovea-gpu-builder OUT.spv OUT-RAY-QUERY.spv");
        return ExitCode::from(2);
    }
    let result = build(Variant::Software, Path::new(&args[0]))
        .and_then(|()| build(Variant::RayQuery, Path::new(&args[1])));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("fovea-gpu-builder: {e}");
            ExitCode::FAILURE
        }
    }
}
