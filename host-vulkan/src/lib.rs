//! The ash Vulkan host of fovea.
//!
//! It will own the Vulkan instance and device, upload the packed scene buffers of `fovea-scene` once per
//! scene and dispatch the SPIR-V kernel of `fovea-gpu-kernel`. Not built yet: `fovea render --backend
//! vulkan` reports that the Vulkan backend is not available in this build.
