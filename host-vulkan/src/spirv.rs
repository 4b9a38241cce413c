//! The SPIR-V kernel: where it comes from and which device features its capabilities need.
use crate::error::{Result, VulkanError};

/// The kernel module built by `host-vulkan/build.rs` (rust-gpu), embedded in the binary.
pub static EMBEDDED_KERNEL: &[u8] = include_bytes!(env!("FOVEA_KERNEL_SPV"));
/// The same kernel built with ray queries (`--traversal hardware`; core's `bvh::hardware`); empty
/// where the build had none (a prebuilt software module without its twin).
pub static EMBEDDED_RAY_QUERY_KERNEL: &[u8] = include_bytes!(env!("FOVEA_KERNEL_RQ_SPV"));

/// Entry points the host creates a pipeline for: every frame pass's, in core's order (a pipeline's
/// index is its entry's index here).
pub use fovea_core::passes::KERNEL_ENTRIES as ENTRY_POINTS;

/// The probe entry points (cross-backend tests), whose pipelines are created on first use.
pub const PROBE_ENTRY_POINT: &str = "probe";
pub const PROBE_SCENE_ENTRY_POINT: &str = "probe_scene";

/// SPIR-V magic number (first word of every module).
const MAGIC: u32 = 0x0723_0203;
/// `OpCapability`.
const OP_CAPABILITY: u32 = 17;
/// `OpEntryPoint`.
const OP_ENTRY_POINT: u32 = 15;

/// The kernel's words: the embedded module, or the file named by `FOVEA_KERNEL_SPV` in the environment at
/// run time (for experiments with other builds of the kernel).
pub fn load_kernel() -> Result<Vec<u32>> {
    load_module("FOVEA_KERNEL_SPV", EMBEDDED_KERNEL, "kernel")
}

/// The ray-query kernel's words: the embedded module, or the file named by `FOVEA_KERNEL_RQ_SPV` at run
/// time.
pub fn load_ray_query_kernel() -> Result<Vec<u32>> {
    if EMBEDDED_RAY_QUERY_KERNEL.is_empty() && std::env::var_os("FOVEA_KERNEL_RQ_SPV").is_none() {
        return Err(VulkanError::KernelNotBuilt(
            "this binary has no ray-query kernel (it was built from a prebuilt software module); \
             use --traversal software"
                .into(),
        ));
    }
    load_module(
        "FOVEA_KERNEL_RQ_SPV",
        EMBEDDED_RAY_QUERY_KERNEL,
        "ray-query kernel",
    )
}

/// A module's words from the file named by the environment variable `variable`, else from `embedded`.
fn load_module(variable: &str, embedded: &[u8], what: &str) -> Result<Vec<u32>> {
    match std::env::var(variable).ok().filter(|p| !p.is_empty()) {
        Some(path) => {
            let bytes = std::fs::read(&path)
                .map_err(|e| VulkanError::KernelNotBuilt(format!("cannot read '{path}': {e}")))?;
            words_from_bytes(&bytes)
                .map_err(|e| VulkanError::KernelNotBuilt(format!("'{path}': {e}")))
        }
        None => words_from_bytes(embedded).map_err(|e| {
            VulkanError::KernelNotBuilt(format!("the embedded {what} is unusable: {e}"))
        }),
    }
}

/// SPIR-V words from little-endian bytes, checking the magic number.
pub fn words_from_bytes(bytes: &[u8]) -> std::result::Result<Vec<u32>, String> {
    if !bytes.len().is_multiple_of(4) || bytes.len() < 20 {
        return Err(format!("{} bytes is not a SPIR-V module", bytes.len()));
    }
    let words: Vec<u32> = bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    if words[0] != MAGIC {
        return Err("not a SPIR-V module (bad magic number)".into());
    }
    Ok(words)
}

/// What a module declares: its capabilities and entry-point names.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ModuleInfo {
    pub capabilities: Vec<u32>,
    pub entry_points: Vec<String>,
}

/// Scans the module's instructions for `OpCapability` and `OpEntryPoint`.
pub fn module_info(words: &[u32]) -> ModuleInfo {
    let mut info = ModuleInfo::default();
    let mut i = 5;
    while i < words.len() {
        let count = (words[i] >> 16) as usize;
        let opcode = words[i] & 0xffff;
        if count == 0 || i + count > words.len() {
            break;
        }
        if opcode == OP_CAPABILITY && count >= 2 {
            info.capabilities.push(words[i + 1]);
        } else if opcode == OP_ENTRY_POINT && count >= 4 {
            let mut name = Vec::new();
            'words: for w in &words[i + 3..i + count] {
                for b in w.to_le_bytes() {
                    if b == 0 {
                        break 'words;
                    }
                    name.push(b);
                }
            }
            info.entry_points
                .push(String::from_utf8_lossy(&name).into_owned());
        }
        i += count;
    }
    info
}

/// SPIR-V capability numbers the host knows how to enable.
pub mod capability {
    pub const SHADER: u32 = 1;
    pub const FLOAT64: u32 = 10;
    pub const INT64: u32 = 11;
    pub const INT16: u32 = 22;
    pub const INT8: u32 = 39;
    pub const STORAGE_BUFFER_16BIT_ACCESS: u32 = 4433;
    pub const STORAGE_BUFFER_8BIT_ACCESS: u32 = 4448;
    pub const VULKAN_MEMORY_MODEL: u32 = 5345;
    pub const VULKAN_MEMORY_MODEL_DEVICE_SCOPE: u32 = 5346;
    pub const VARIABLE_POINTERS_STORAGE_BUFFER: u32 = 4441;
    pub const VARIABLE_POINTERS: u32 = 4442;
    pub const PHYSICAL_STORAGE_BUFFER_ADDRESSES: u32 = 5347;
    pub const GROUP_NON_UNIFORM: u32 = 61;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hand-assembled module header plus `OpCapability Shader`, `OpCapability VulkanMemoryModel` and an
    /// `OpEntryPoint GLCompute %1 "main"`.
    fn tiny_module() -> Vec<u32> {
        let mut w = vec![MAGIC, 0x0001_0500, 0, 10, 0];
        w.extend([(2 << 16) | OP_CAPABILITY, capability::SHADER]);
        w.extend([(2 << 16) | OP_CAPABILITY, capability::VULKAN_MEMORY_MODEL]);
        let name = u32::from_le_bytes(*b"main");
        w.extend([(5 << 16) | OP_ENTRY_POINT, 5, 1, name, 0]);
        w
    }

    #[test]
    fn parses_capabilities_and_entry_points() {
        let info = module_info(&tiny_module());
        assert_eq!(
            info.capabilities,
            vec![capability::SHADER, capability::VULKAN_MEMORY_MODEL]
        );
        assert_eq!(info.entry_points, vec!["main".to_string()]);
    }

    #[test]
    fn rejects_non_spirv_bytes() {
        assert!(words_from_bytes(b"hello world, this is no module").is_err());
        assert!(words_from_bytes(&[1, 2, 3]).is_err());
        let bytes: Vec<u8> = tiny_module().iter().flat_map(|w| w.to_le_bytes()).collect();
        assert_eq!(words_from_bytes(&bytes).unwrap(), tiny_module());
    }

    #[test]
    fn embedded_kernel_has_every_entry_point() {
        let words = words_from_bytes(EMBEDDED_KERNEL).expect("the build embeds a SPIR-V module");
        let info = module_info(&words);
        let probes = [PROBE_ENTRY_POINT, PROBE_SCENE_ENTRY_POINT];
        for name in ENTRY_POINTS.iter().chain(&probes) {
            assert!(
                info.entry_points.iter().any(|e| e == name),
                "{name}: {info:?}"
            );
        }
        assert!(info.capabilities.contains(&capability::SHADER));
    }

    #[test]
    fn truncated_instructions_stop_the_scan() {
        let mut w = tiny_module();
        w.push((9 << 16) | OP_CAPABILITY); // claims 9 words, only 1 left
        assert_eq!(module_info(&w).capabilities.len(), 2);
    }
}
