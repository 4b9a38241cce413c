//! The window's surface and swapchain as resources (`fovea view`): the handles a window gives, the
//! surface and device checks the context makes while it chooses a device, and the presenter's objects
//! (swapchain, semaphores, the frame-sized blit source, the staging buffer), which destroy themselves.
//! Presenting itself is [`crate::present`]. Below the context, which holds the presenter.
use std::ffi::CStr;
use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use crate::buffer::GpuBuffer;
use crate::error::{Result, VkContext, VulkanError};
use crate::instance::{InstanceHandle, Shared};

/// The raw handles of the window to present to. The window must outlive the context.
#[derive(Clone, Copy, Debug)]
pub struct WindowHandles {
    pub display: RawDisplayHandle,
    pub window: RawWindowHandle,
}

/// The instance extensions a surface of this display needs.
pub(crate) fn surface_extensions(window: &WindowHandles) -> Result<Vec<&'static CStr>> {
    let names = ash_window::enumerate_required_extensions(window.display).map_err(|r| {
        VulkanError::NoPresentation(format!(
            "this window system has no Vulkan surface support ({r})"
        ))
    })?;
    Ok(names
        .iter()
        // SAFETY: ash-window returns pointers to ash's static, NUL-terminated extension names.
        .map(|&p| unsafe { CStr::from_ptr(p) })
        .collect())
}

/// Creates the window's surface and stores it in `instance` (destroyed with it).
pub(crate) fn create_surface(instance: &mut InstanceHandle, window: &WindowHandles) -> Result<()> {
    // SAFETY: the handles come from a live window, which the caller keeps alive until the context (and
    // so the surface) is dropped.
    let surface = unsafe {
        ash_window::create_surface(
            &instance.entry,
            &instance.instance,
            window.display,
            window.window,
            None,
        )
    }
    .map_err(|r| VulkanError::NoPresentation(format!("vkCreate*SurfaceKHR failed: {r}")))?;
    let loader = ash::khr::surface::Instance::new(&instance.entry, &instance.instance);
    instance.surface = Some((loader, surface));
    Ok(())
}

/// The first queue family of `pd` with compute that can present to the instance's surface.
pub(crate) fn present_queue_family(
    instance: &InstanceHandle,
    pd: vk::PhysicalDevice,
) -> Option<u32> {
    let (loader, surface) = instance.surface.as_ref()?;
    // SAFETY: `pd` belongs to this instance.
    let families = unsafe {
        instance
            .instance
            .get_physical_device_queue_family_properties(pd)
    };
    (0..families.len() as u32).find(|&i| {
        families[i as usize]
            .queue_flags
            .contains(vk::QueueFlags::COMPUTE)
            // SAFETY: valid device, family index and surface of this instance.
            && unsafe { loader.get_physical_device_surface_support(pd, i, *surface) }
                .unwrap_or(false)
    })
}

/// Fails unless `pd` has `VK_KHR_swapchain`.
pub(crate) fn check_swapchain_extension(
    instance: &InstanceHandle,
    pd: vk::PhysicalDevice,
    device_name: &str,
) -> Result<()> {
    // SAFETY: `pd` belongs to this instance.
    let extensions = unsafe { instance.instance.enumerate_device_extension_properties(pd) }
        .during("vkEnumerateDeviceExtensionProperties")?;
    if extensions
        .iter()
        .any(|e| e.extension_name_as_c_str().ok() == Some(ash::khr::swapchain::NAME))
    {
        Ok(())
    } else {
        Err(VulkanError::NoPresentation(format!(
            "device '{device_name}' has no VK_KHR_swapchain"
        )))
    }
}

/// An image with its own allocation (the frame-sized blit source).
pub(crate) struct OwnedImage {
    shared: Arc<Shared>,
    pub image: vk::Image,
    allocation: Option<Allocation>,
    pub size: [u32; 2],
}

impl OwnedImage {
    pub fn new(shared: &Arc<Shared>, size: [u32; 2], format: vk::Format) -> Result<Self> {
        let device = &shared.device;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D {
                width: size[0],
                height: size[1],
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device and create info.
        let image = unsafe { device.create_image(&info, None) }.during("vkCreateImage")?;
        let mut out = Self {
            shared: shared.clone(),
            image,
            allocation: None,
            size,
        };
        // SAFETY: the image was just created on this device.
        let requirements = unsafe { device.get_image_memory_requirements(image) };
        let allocation = shared
            .allocator
            .lock()
            .map_err(|_| VulkanError::Allocator("allocator lock poisoned".into()))?
            .allocate(&AllocationCreateDesc {
                name: "presented frame",
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| VulkanError::Allocator(format!("presented frame: {e}")))?;
        out.allocation = Some(allocation);
        let a = out.allocation.as_ref().expect("allocation was just set");
        // SAFETY: the allocation satisfies the image's requirements, is alive while `out` is and is bound
        // once; on failure `out`'s Drop destroys the image and frees the allocation.
        unsafe { device.bind_image_memory(image, a.memory(), a.offset()) }
            .during("vkBindImageMemory")?;
        Ok(out)
    }
}

impl Drop for OwnedImage {
    fn drop(&mut self) {
        // SAFETY: every submission using the image was waited on before the presenter drops it.
        unsafe { self.shared.device.destroy_image(self.image, None) };
        if let Some(a) = self.allocation.take() {
            if let Ok(mut alloc) = self.shared.allocator.lock() {
                let _ = alloc.free(a);
            }
        }
    }
}

/// The swapchain and what presenting through it needs.
pub(crate) struct Presenter {
    pub shared: Arc<Shared>,
    pub loader: ash::khr::swapchain::Device,
    pub swapchain: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    pub extent: [u32; 2],
    pub format: vk::Format,
    pub present_mode: vk::PresentModeKHR,
    /// Signalled by the acquire, waited on by the copy submission.
    pub acquired: vk::Semaphore,
    /// One per swapchain image: signalled by the copy submission, waited on by its present.
    pub copied: Vec<vk::Semaphore>,
    /// The frame as an image of the frame's size, in the format that matches the swapchain's encoding.
    pub frame: Option<OwnedImage>,
    /// Host pixels (CPU frames) and the on-screen figures, uploaded per present.
    pub staging: Option<GpuBuffer>,
    /// The swapchain reported itself out of date or suboptimal: re-create before the next acquire.
    pub stale: bool,
}

impl Presenter {
    pub fn destroy_swapchain(&mut self) {
        let device = &self.shared.device;
        // SAFETY: the device is idle (every submission was waited on, and presents finish before the
        // device-wait below); the semaphores and the swapchain are not in use.
        unsafe {
            let _ = device.device_wait_idle();
            for s in self.copied.drain(..) {
                device.destroy_semaphore(s, None);
            }
            if self.swapchain != vk::SwapchainKHR::null() {
                self.loader.destroy_swapchain(self.swapchain, None);
                self.swapchain = vk::SwapchainKHR::null();
            }
        }
        self.images.clear();
    }
}

impl Drop for Presenter {
    fn drop(&mut self) {
        self.destroy_swapchain();
        self.frame = None;
        self.staging = None;
        // SAFETY: the device is idle (see `destroy_swapchain`).
        unsafe { self.shared.device.destroy_semaphore(self.acquired, None) };
    }
}

/// The `R8G8B8A8` format whose encoding matches `swapchain_format`, so that the blit copies the
/// kernel's sRGB-encoded bytes unchanged: UNORM for a UNORM swapchain, SRGB (decoded and re-encoded,
/// which is the identity) for an SRGB one.
pub(crate) fn frame_format_for(swapchain_format: vk::Format) -> vk::Format {
    match swapchain_format {
        vk::Format::B8G8R8A8_SRGB
        | vk::Format::R8G8B8A8_SRGB
        | vk::Format::A8B8G8R8_SRGB_PACK32 => vk::Format::R8G8B8A8_SRGB,
        _ => vk::Format::R8G8B8A8_UNORM,
    }
}

/// Prefers 8-bit UNORM BGRA/RGBA in the sRGB colour space (the kernel's bytes are already sRGB-encoded),
/// then their SRGB twins, then whatever comes first.
pub(crate) fn choose_format(formats: &[vk::SurfaceFormatKHR]) -> Option<vk::SurfaceFormatKHR> {
    let preference = [
        vk::Format::B8G8R8A8_UNORM,
        vk::Format::R8G8B8A8_UNORM,
        vk::Format::B8G8R8A8_SRGB,
        vk::Format::R8G8B8A8_SRGB,
    ];
    preference
        .iter()
        .find_map(|&f| {
            formats
                .iter()
                .find(|s| s.format == f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
        })
        .or_else(|| formats.first())
        .copied()
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unorm_swapchains_are_preferred_and_the_frame_format_matches_their_encoding() {
        let f = |format| vk::SurfaceFormatKHR {
            format,
            color_space: vk::ColorSpaceKHR::SRGB_NONLINEAR,
        };
        let offered = [f(vk::Format::B8G8R8A8_SRGB), f(vk::Format::B8G8R8A8_UNORM)];
        assert_eq!(
            choose_format(&offered).unwrap().format,
            vk::Format::B8G8R8A8_UNORM
        );
        assert_eq!(
            frame_format_for(vk::Format::B8G8R8A8_UNORM),
            vk::Format::R8G8B8A8_UNORM
        );
        assert_eq!(
            frame_format_for(vk::Format::B8G8R8A8_SRGB),
            vk::Format::R8G8B8A8_SRGB
        );
        assert!(choose_format(&[]).is_none());
    }
}
