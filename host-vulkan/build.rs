//! Builds the SPIR-V kernel's two modules and hands their paths to the crate as `FOVEA_KERNEL_SPV`
//! (software traversal) and `FOVEA_KERNEL_RQ_SPV` (ray queries; `include_bytes!(env!(..))`).
//!
//! The kernel (`gpu-kernel/`, calling into `core/`) is compiled by rust-gpu, which needs a pinned nightly,
//! so this script runs `gpu-kernel/builder/` (its own workspace, pinned to that nightly) in a nested cargo:
//!
//! ```text
//! cargo +nightly-2026-08-15 run --release --manifest-path gpu-kernel/builder/Cargo.toml \
//!     --target-dir target/gpu-builder -- $OUT_DIR/fovea-kernel.spv $OUT_DIR/fovea-kernel-ray-query.spv
//! ```
//!
//! with an environment cleaned of everything the outer cargo set for this script. The first build compiles
//! the rust-gpu backend (minutes); later kernel rebuilds take about a second. Missing prerequisites (the
//! nightly with `rust-src`, `rustc-dev`, `llvm-tools`; `spirv-val`/`spirv-opt` from `spirv-tools`) fail with
//! one line naming `bash scripts/setup.sh`.
//!
//! `FOVEA_KERNEL_SPV_PREBUILT=/path/to/fovea-kernel.spv` skips the nested build and uses that module (for
//! machines without the nightly, e.g. a GPU box that only runs a module built elsewhere), with
//! `FOVEA_KERNEL_RQ_SPV_PREBUILT` as its ray-query twin (without it, the binary has software traversal
//! only).
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The nightly rust-gpu 0.11.0 needs (also in `gpu-kernel/builder/rust-toolchain.toml` and `scripts/setup.sh`).
const NIGHTLY: &str = "nightly-2026-08-15";
/// Components of [`NIGHTLY`] that spirv-builder needs.
const COMPONENTS: [&str; 3] = ["rust-src", "rustc-dev", "llvm-tools"];
/// Tools of Debian's `spirv-tools` that spirv-builder runs (`use-installed-tools`).
const SPIRV_TOOLS: [&str; 2] = ["spirv-val", "spirv-opt"];
/// How to install what is missing.
const SETUP_HINT: &str = "install them with `bash scripts/setup.sh`";
/// Lines of the nested build's output repeated as warnings when it fails.
const FAILURE_TAIL_LINES: usize = 40;

/// Asks cargo to rerun this script when `path` changes: the path itself (a folder's entries added or
/// removed) and, for a folder, every file under it. Cargo's own check of a folder named in
/// `rerun-if-changed` missed edits to files in its subfolders here (an edit to
/// `core/src/temporal/*.rs` left a stale kernel), so each file is named.
fn rerun_if_changed(path: &Path) {
    println!("cargo:rerun-if-changed={}", path.display());
    if let Ok(entries) = std::fs::read_dir(path) {
        for entry in entries.flatten() {
            rerun_if_changed(&entry.path());
        }
    }
}

fn main() {
    let manifest_dir = PathBuf::from(env("CARGO_MANIFEST_DIR"));
    let repo = manifest_dir
        .parent()
        .expect("vulkan lives in the repository root")
        .to_path_buf();
    let out = PathBuf::from(env("OUT_DIR")).join("fovea-kernel.spv");
    let out_rq = PathBuf::from(env("OUT_DIR")).join("fovea-kernel-ray-query.spv");

    for dir in [
        "core/src",
        "core/Cargo.toml",
        "gpu-kernel/src",
        "gpu-kernel/Cargo.toml",
        "gpu-kernel/Cargo.lock",
        "gpu-kernel/builder/src",
        "gpu-kernel/builder/Cargo.toml",
        "gpu-kernel/builder/Cargo.lock",
        "gpu-kernel/builder/rust-toolchain.toml",
    ] {
        rerun_if_changed(&repo.join(dir));
    }
    println!("cargo:rerun-if-env-changed=FOVEA_KERNEL_SPV_PREBUILT");
    println!("cargo:rerun-if-env-changed=FOVEA_KERNEL_RQ_SPV_PREBUILT");
    println!("cargo:rustc-env=FOVEA_KERNEL_SPV={}", out.display());
    println!("cargo:rustc-env=FOVEA_KERNEL_RQ_SPV={}", out_rq.display());

    if let Some(prebuilt) = std::env::var_os("FOVEA_KERNEL_SPV_PREBUILT") {
        let prebuilt = PathBuf::from(prebuilt);
        println!("cargo:rerun-if-changed={}", prebuilt.display());
        if let Err(e) = std::fs::copy(&prebuilt, &out) {
            fail(&format!(
                "copying FOVEA_KERNEL_SPV_PREBUILT={} to {}: {e}",
                prebuilt.display(),
                out.display()
            ));
        }
        // The ray-query twin, if given; else none (hardware traversal then says so at run time).
        let copied = match std::env::var_os("FOVEA_KERNEL_RQ_SPV_PREBUILT") {
            Some(rq) => std::fs::copy(&rq, &out_rq).map(|_| ()),
            None => std::fs::write(&out_rq, []),
        };
        if let Err(e) = copied {
            fail(&format!("writing {}: {e}", out_rq.display()));
        }
        return;
    }

    if let Err(missing) = check_prerequisites() {
        fail(&format!(
            "building the GPU kernel needs {missing}; {SETUP_HINT}"
        ));
    }

    let mut cmd = Command::new(rustup_tool("cargo"));
    cmd.arg(format!("+{NIGHTLY}"))
        .args(["run", "--release", "--quiet", "--manifest-path"])
        .arg(repo.join("gpu-kernel/builder/Cargo.toml"))
        .arg("--target-dir")
        .arg(repo.join("target").join("gpu-builder"))
        .arg("--")
        .arg(&out)
        .arg(&out_rq)
        .current_dir(repo.join("gpu-kernel/builder"));
    sanitise_env(&mut cmd);

    let output = match cmd.output() {
        Ok(o) => o,
        Err(e) => fail(&format!(
            "could not run `cargo +{NIGHTLY}` ({e}); {SETUP_HINT}"
        )),
    };
    let log = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    // The whole log: on this script's stderr (shown by `cargo build -vv` and on failure) and in OUT_DIR.
    eprint!("{log}");
    let log_path = out.with_file_name("gpu-build.log");
    let _ = std::fs::write(&log_path, &log);

    if !output.status.success() || !out.is_file() || !out_rq.is_file() {
        let lines: Vec<&str> = log.lines().filter(|l| !l.trim().is_empty()).collect();
        let start = lines.len().saturating_sub(FAILURE_TAIL_LINES);
        for line in &lines[start..] {
            println!("cargo:warning={line}");
        }
        fail(&format!(
            "building the GPU kernel failed ({}); full log: {}",
            output.status,
            log_path.display()
        ));
    }
}

/// A variable cargo always sets for build scripts.
fn env(key: &str) -> String {
    std::env::var(key).unwrap_or_else(|_| panic!("cargo did not set {key}"))
}

/// Fails the build with one clear line.
fn fail(message: &str) -> ! {
    println!("cargo::error=fovea-vulkan: {message}");
    eprintln!("fovea-vulkan: {message}");
    std::process::exit(1);
}

/// `Err` names what is missing: the nightly, its components, or the SPIR-V tools.
fn check_prerequisites() -> Result<(), String> {
    let mut missing = Vec::new();
    let tools: Vec<&str> = SPIRV_TOOLS
        .iter()
        .copied()
        .filter(|t| find_in_path(t).is_none())
        .collect();

    // `rustup component list --installed` answers both "is the toolchain there" and "are its components".
    let mut rustup = Command::new(rustup_tool("rustup"));
    rustup.args(["component", "list", "--installed", "--toolchain", NIGHTLY]);
    sanitise_env(&mut rustup);
    match rustup.output() {
        Ok(o) if o.status.success() => {
            let installed = String::from_utf8_lossy(&o.stdout);
            let absent: Vec<&str> = COMPONENTS
                .iter()
                .copied()
                .filter(|c| {
                    !installed
                        .lines()
                        .any(|l| l == *c || l.starts_with(&format!("{c}-")))
                })
                .collect();
            if !absent.is_empty() {
                missing.push(format!("the {NIGHTLY} components {}", absent.join(", ")));
            }
        }
        Ok(_) => missing.push(format!("Rust {NIGHTLY} (with {})", COMPONENTS.join(", "))),
        // No rustup: nothing to check here; `cargo +nightly` will say what is wrong.
        Err(_) => {}
    }
    if !tools.is_empty() {
        missing.push(format!(
            "{} (Debian/Ubuntu package spirv-tools)",
            tools.join(", ")
        ));
    }
    if missing.is_empty() {
        Ok(())
    } else {
        Err(missing.join(" and "))
    }
}

/// `name` from `PATH`, else from `$CARGO_HOME/bin` or `~/.cargo/bin` (rustup's proxies, which understand
/// `+toolchain`), else plain `name`.
fn rustup_tool(name: &str) -> PathBuf {
    if let Some(p) = find_in_path(name) {
        return p;
    }
    let homes = [
        std::env::var_os("CARGO_HOME").map(PathBuf::from),
        std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")),
    ];
    for home in homes.into_iter().flatten() {
        let p = home.join("bin").join(name);
        if is_executable(&p) {
            return p;
        }
    }
    PathBuf::from(name)
}

/// The first executable `name` on `PATH`.
fn find_in_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join(name))
        .find(|p| is_executable(p))
}

fn is_executable(p: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        p.metadata()
            .map(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
            .unwrap_or(false)
    }
    #[cfg(not(unix))]
    {
        p.is_file()
    }
}

/// Removes what the outer cargo set for this build script (compiler, flags, target dir, toolchain pin,
/// jobserver, package metadata, `DEP_*` links data), so the nested cargo behaves as if run from a shell.
/// User configuration (`CARGO_HOME`, `CARGO_NET_*`, `CARGO_HTTP_*`, registries, terminal) is kept.
fn sanitise_env(cmd: &mut Command) {
    const REMOVE: [&str; 18] = [
        "RUSTC",
        "RUSTC_WRAPPER",
        "RUSTC_WORKSPACE_WRAPPER",
        "RUSTC_LINKER",
        "RUSTDOC",
        "RUSTFLAGS",
        "RUSTDOCFLAGS",
        "RUSTUP_TOOLCHAIN",
        "OUT_DIR",
        "TARGET",
        "HOST",
        "NUM_JOBS",
        "OPT_LEVEL",
        "DEBUG",
        "PROFILE",
        "CARGO_MAKEFLAGS",
        "MAKEFLAGS",
        "MFLAGS",
    ];
    const KEEP_PREFIXES: [&str; 6] = [
        "CARGO_HOME",
        "CARGO_NET_",
        "CARGO_HTTP_",
        "CARGO_REGISTRIES_",
        "CARGO_REGISTRY_",
        "CARGO_TERM_",
    ];
    for key in REMOVE {
        cmd.env_remove(key);
    }
    for (key, _) in std::env::vars_os() {
        let Some(k) = key.to_str() else { continue };
        let cargo_set = k.starts_with("CARGO_") || k == "CARGO";
        let kept = KEEP_PREFIXES.iter().any(|p| k.starts_with(p));
        if (cargo_set && !kept) || k.starts_with("DEP_") {
            cmd.env_remove(OsStr::new(k));
        }
    }
    // Set after the loop above (which removes the outer cargo's own `CARGO_ENCODED_RUSTFLAGS`): empty, it
    // takes precedence over the repository's `.cargo/config.toml` (`target-cpu=native` for the hosts),
    // which the nested cargo would otherwise read too, so the kernel builder keeps its own cache.
    cmd.env("CARGO_ENCODED_RUSTFLAGS", "");
}
