//! Who creates the Vulkan instance and device a context runs on: fovea itself (the default), or an
//! OpenXR runtime through `XR_KHR_vulkan_enable2` (`crate::xr`), which adds the extensions its
//! compositor needs to fovea's create infos and chooses the physical device that drives the headset.
//! Either way the context asks for the same features and extensions, and renders the same way.
use std::sync::Arc;

use ash::vk;

use crate::error::Result;

/// Creates a context's Vulkan instance and device in place of `vkCreateInstance` and
/// `vkCreateDevice`.
pub trait DeviceFactory: std::fmt::Debug + Send + Sync {
    /// The instance for `info`, through `entry`'s loader.
    ///
    /// # Safety
    /// `info` and everything it points to are valid until the call returns.
    unsafe fn create_instance(
        &self,
        entry: &ash::Entry,
        info: &vk::InstanceCreateInfo<'_>,
    ) -> Result<ash::Instance>;

    /// The physical device the context must use, where the factory decides (a headset's GPU).
    fn physical_device(&self, instance: &ash::Instance) -> Result<Option<vk::PhysicalDevice>>;

    /// The device for `info` on `physical`.
    ///
    /// # Safety
    /// `physical` belongs to `instance`, and `info` and everything it points to are valid until the
    /// call returns.
    unsafe fn create_device(
        &self,
        entry: &ash::Entry,
        instance: &ash::Instance,
        physical: vk::PhysicalDevice,
        info: &vk::DeviceCreateInfo<'_>,
    ) -> Result<ash::Device>;

    /// Whether the context's queue must support graphics as well as compute (an OpenXR session
    /// submits work on its swapchain images to that queue).
    fn needs_graphics_queue(&self) -> bool {
        false
    }
}

/// A factory shared by the context options that carry it.
pub type SharedFactory = Arc<dyn DeviceFactory>;
