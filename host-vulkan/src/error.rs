//! Errors of the Vulkan host. Every failure is reported as a value; the host never panics or waits forever
//! on the GPU.
use ash::vk;

/// What can go wrong while setting up Vulkan or rendering a frame.
#[derive(Debug, thiserror::Error)]
pub enum VulkanError {
    /// No Vulkan loader (`libvulkan.so.1`, `vulkan-1.dll`) could be opened.
    #[error("no Vulkan loader found ({0}); install the Vulkan loader and a driver (Debian/Ubuntu: libvulkan1 mesa-vulkan-drivers)")]
    NoLoader(String),
    /// The loader works but lists no device that can run the kernel.
    #[error("no Vulkan device with Vulkan 1.2 and a compute queue{0}")]
    NoDevice(String),
    /// `--device N` with N past the end of the device list.
    #[error("Vulkan device index {index} is out of range: {count} device(s) found (see `fovea devices`)")]
    DeviceIndexOutOfRange { index: usize, count: usize },
    /// The chosen device lacks something the kernel needs.
    #[error("Vulkan device '{device}' is unsuitable: {reason}")]
    UnsuitableDevice { device: String, reason: String },
    /// `FOVEA_VULKAN_VALIDATION=1` but `VK_LAYER_KHRONOS_validation` or `VK_EXT_debug_utils` is missing.
    #[error("Vulkan validation was requested but is unavailable: {0} (Debian/Ubuntu: apt install vulkan-validationlayers)")]
    ValidationUnavailable(String),
    /// The SPIR-V kernel was not built into this binary, or cannot be read.
    #[error("kernel not built: {0}")]
    KernelNotBuilt(String),
    /// The driver reported `VK_ERROR_DEVICE_LOST` (a crash or reset of the GPU).
    #[error("Vulkan device lost during {0}")]
    DeviceLost(&'static str),
    /// Device or host memory ran out.
    #[error("out of device memory while allocating {what} ({bytes} bytes)")]
    OutOfDeviceMemory { what: String, bytes: u64 },
    /// A buffer exceeds a device limit.
    #[error("{what} needs {bytes} bytes, more than the device's {limit_name} of {limit} bytes")]
    TooLarge {
        what: String,
        bytes: u64,
        limit_name: &'static str,
        limit: u64,
    },
    /// A fence wait ran past its timeout (the device may be hung; the context is unusable afterwards).
    #[error("the GPU did not finish {what} within {seconds} s")]
    Timeout { what: &'static str, seconds: u64 },
    /// The context hit a timeout or device loss earlier and refuses further work.
    #[error("the Vulkan context is unusable after an earlier device loss or timeout")]
    Poisoned,
    /// A window cannot be presented to (no surface support, no device that presents to it, ...).
    #[error("cannot present to the window: {0}")]
    NoPresentation(String),
    /// Invalid arguments (a scene from another context, bad frame parameters, ...).
    #[error("{0}")]
    Invalid(String),
    /// Any other Vulkan error code, with the call that returned it.
    #[error("Vulkan call {call} failed: {result}")]
    Vk {
        call: &'static str,
        result: vk::Result,
    },
    /// A memory-allocator failure other than running out of memory.
    #[error("GPU memory allocator: {0}")]
    Allocator(String),
}

impl VulkanError {
    /// Maps a Vulkan result code of `call` to the matching error (device loss and memory exhaustion get
    /// their own variants).
    #[must_use]
    pub fn vk(call: &'static str, result: vk::Result) -> Self {
        match result {
            vk::Result::ERROR_DEVICE_LOST => Self::DeviceLost(call),
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                Self::OutOfDeviceMemory {
                    what: call.to_string(),
                    bytes: 0,
                }
            }
            other => Self::Vk {
                call,
                result: other,
            },
        }
    }

    /// Whether the error leaves the device in an unknown state (device loss or a timeout).
    #[must_use]
    pub fn is_fatal(&self) -> bool {
        matches!(self, Self::DeviceLost(_) | Self::Timeout { .. })
    }
}

/// `Result` with [`VulkanError`].
pub type Result<T, E = VulkanError> = std::result::Result<T, E>;

/// Adds the name of the failing call to a Vulkan result.
pub(crate) trait VkContext<T> {
    fn during(self, call: &'static str) -> Result<T>;
}

impl<T> VkContext<T> for std::result::Result<T, vk::Result> {
    fn during(self, call: &'static str) -> Result<T> {
        self.map_err(|r| VulkanError::vk(call, r))
    }
}
