//! Presenting frames to a window (the live view, `fovea view`).
//!
//! The context is created with the window's surface ([`crate::ContextOptions::window`]) and a compute
//! queue that can present to it. [`crate::VulkanContext::present`] ([`present`] here) then shows a frame without a read-back: the
//! RGBA8 image (the kernel's `tonemap`/`overlay_regions` output, still on the device, or a frame the CPU
//! host rendered, uploaded) is copied into a frame-sized `R8G8B8A8` image and blitted to the acquired
//! swapchain image, which converts to the swapchain's format (BGRA on most X11 drivers) and scales to
//! the window's size (a render scale below 1, or a resize in flight); the on-screen figures (a small
//! RGBA8 image) are then copied over the swapchain image's corner. One submission per present, waited
//! on with a fence: the live view renders and presents one frame at a time, so nothing more elaborate
//! is needed. The swapchain's objects are [`crate::swapchain`]'s.
//!
//! Present mode: `MAILBOX` where the driver has it (no tearing, no waiting for vertical blank), else
//! `FIFO`, which every driver has. A window with a zero-sized surface (minimised) is not presented to:
//! [`PresentOutcome::presented`] is false and the viewer waits for events instead of spinning.
use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::barrier::image_barrier;
use crate::buffer::GpuBuffer;
use crate::context::CHUNK_TIMEOUT;
use crate::device::Device;
use crate::error::{Result, VkContext, VulkanError};
pub use crate::swapchain::WindowHandles;
use crate::swapchain::{choose_format, frame_format_for, OwnedImage, Presenter};

/// What to present.
#[derive(Clone, Copy, Debug)]
pub enum PresentSource<'a> {
    /// The last frame rendered on this context (its RGBA8 image on the device).
    LastFrame,
    /// An RGBA8 image from the host (the CPU backend's frame), `width · height` pixels, R in the low
    /// byte.
    Host {
        pixels: &'a [u32],
        width: u32,
        height: u32,
    },
}

impl PresentSource<'_> {
    /// Bytes of host pixels the source puts in the staging buffer (before the HUD's).
    fn host_bytes(&self) -> u64 {
        match self {
            Self::Host { pixels, .. } => pixels.len() as u64 * 4,
            Self::LastFrame => 0,
        }
    }
}

/// A small RGBA8 image drawn over the window's top-left corner at (`x`, `y`) (the on-screen figures),
/// clipped to the window; grey pixels (it is copied into BGRA swapchains unswizzled).
#[derive(Clone, Copy, Debug)]
pub struct HudOverlay<'a> {
    pub pixels: &'a [u32],
    pub width: u32,
    pub height: u32,
    pub x: u32,
    pub y: u32,
}

/// What a present did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PresentOutcome {
    /// False when nothing was shown: the window is minimised (zero-sized surface).
    pub presented: bool,
    /// The swapchain's size.
    pub extent: [u32; 2],
    /// "mailbox" or "fifo".
    pub present_mode: &'static str,
    /// Whether the swapchain was (re-)created for this present (first frame, resize).
    pub recreated: bool,
}

/// Presents `source` with `hud` over its corner to the window, at `window_size` (the window's inner
/// size in pixels, used where the surface leaves the size to the application). Creates the swapchain
/// on first use and re-creates it after a resize. A minimised window presents nothing.
pub(crate) fn present(
    device: &mut Device,
    slot: &mut Option<Presenter>,
    last_frame: Option<(vk::Buffer, u32, u32)>,
    source: PresentSource<'_>,
    hud: Option<HudOverlay<'_>>,
    window_size: [u32; 2],
) -> Result<PresentOutcome> {
    device.check_usable()?;
    let (frame_w, frame_h) = match source {
        PresentSource::LastFrame => {
            let (_, w, h) = last_frame.ok_or_else(|| {
                VulkanError::Invalid("present: no frame has been rendered yet".into())
            })?;
            (w, h)
        }
        PresentSource::Host {
            pixels,
            width,
            height,
        } => {
            if pixels.len() as u64 != u64::from(width) * u64::from(height) || width == 0 {
                return Err(VulkanError::Invalid(format!(
                    "present: {} pixels are not a {width}x{height} image",
                    pixels.len()
                )));
            }
            (width, height)
        }
    };
    let (loader, surface) = match device.shared.instance.surface.as_ref() {
        Some((l, s)) => (l.clone(), *s),
        None => {
            return Err(VulkanError::NoPresentation(
                "this context was created without a window".into(),
            ))
        }
    };
    let pd = device.shared.physical_device;
    // SAFETY: valid device and surface of this instance.
    let caps = unsafe { loader.get_physical_device_surface_capabilities(pd, surface) }
        .during("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
    let extent = if caps.current_extent.width != u32::MAX {
        [caps.current_extent.width, caps.current_extent.height]
    } else {
        [
            window_size[0].clamp(caps.min_image_extent.width, caps.max_image_extent.width),
            window_size[1].clamp(caps.min_image_extent.height, caps.max_image_extent.height),
        ]
    };
    if extent[0] == 0 || extent[1] == 0 {
        return Ok(PresentOutcome {
            presented: false,
            extent,
            present_mode: present_mode_name(slot),
            recreated: false,
        });
    }
    let mut recreated = false;
    let needs_swapchain = match &*slot {
        None => true,
        Some(p) => p.stale || p.extent != extent || p.swapchain == vk::SwapchainKHR::null(),
    };
    if needs_swapchain {
        create_swapchain(device, slot, &loader, surface, &caps, extent)?;
        recreated = true;
    }
    ensure_present_resources(device, slot, [frame_w, frame_h], source, hud)?;

    let presenter = slot.as_ref().expect("swapchain was created");
    let (swap_loader, swapchain, acquired) = (
        presenter.loader.clone(),
        presenter.swapchain,
        presenter.acquired,
    );
    // SAFETY: valid swapchain; the semaphore is unsignalled (its last signal was waited on by the
    // previous copy submission, which finished before this call).
    let acquire = unsafe {
        swap_loader.acquire_next_image(swapchain, 5_000_000_000, acquired, vk::Fence::null())
    };
    let index = match acquire {
        Ok((index, suboptimal)) => {
            if suboptimal {
                slot.as_mut().expect("presenter exists").stale = true;
            }
            index
        }
        Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
            // Resized between the capability query and the acquire: try again next frame.
            slot.as_mut().expect("presenter exists").stale = true;
            return Ok(PresentOutcome {
                presented: false,
                extent,
                present_mode: present_mode_name(slot),
                recreated,
            });
        }
        Err(r) => return Err(VulkanError::vk("vkAcquireNextImageKHR", r)),
    };
    record_and_submit_copy(device, slot, last_frame, index, source, hud)?;

    let presenter = slot.as_ref().expect("presenter exists");
    let waits = [presenter.copied[index as usize]];
    let swapchains = [presenter.swapchain];
    let indices = [index];
    let info = vk::PresentInfoKHR::default()
        .wait_semaphores(&waits)
        .swapchains(&swapchains)
        .image_indices(&indices);
    // SAFETY: the image was acquired and its copy submitted, signalling the semaphore waited on here.
    let result = unsafe { swap_loader.queue_present(device.queue, &info) };
    match result {
        Ok(false) => {}
        Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
            slot.as_mut().expect("presenter exists").stale = true;
        }
        Err(r) => return Err(device.poison_on_fatal(VulkanError::vk("vkQueuePresentKHR", r))),
    }
    Ok(PresentOutcome {
        presented: true,
        extent,
        present_mode: present_mode_name(slot),
        recreated,
    })
}

fn present_mode_name(slot: &Option<Presenter>) -> &'static str {
    match slot.as_ref().map(|p| p.present_mode) {
        Some(vk::PresentModeKHR::MAILBOX) => "mailbox",
        Some(vk::PresentModeKHR::IMMEDIATE) => "immediate",
        _ => "fifo",
    }
}

/// (Re-)creates the swapchain at `extent`, handing the old one over as `oldSwapchain`.
fn create_swapchain(
    device: &Device,
    slot: &mut Option<Presenter>,
    loader: &ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
    caps: &vk::SurfaceCapabilitiesKHR,
    extent: [u32; 2],
) -> Result<()> {
    let pd = device.shared.physical_device;
    if !caps
        .supported_usage_flags
        .contains(vk::ImageUsageFlags::TRANSFER_DST)
    {
        return Err(VulkanError::NoPresentation(
            "the surface's images cannot be copied to (no TRANSFER_DST usage)".into(),
        ));
    }
    // SAFETY: valid device and surface.
    let formats = unsafe { loader.get_physical_device_surface_formats(pd, surface) }
        .during("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
    let format = choose_format(&formats)
        .ok_or_else(|| VulkanError::NoPresentation("the surface offers no image format".into()))?;
    // SAFETY: as above.
    let modes = unsafe { loader.get_physical_device_surface_present_modes(pd, surface) }
        .during("vkGetPhysicalDeviceSurfacePresentModesKHR")?;
    let present_mode = if modes.contains(&vk::PresentModeKHR::MAILBOX) {
        vk::PresentModeKHR::MAILBOX
    } else {
        vk::PresentModeKHR::FIFO
    };
    let mut image_count = caps.min_image_count + 1;
    if caps.max_image_count > 0 {
        image_count = image_count.min(caps.max_image_count);
    }
    let composite = [
        vk::CompositeAlphaFlagsKHR::OPAQUE,
        vk::CompositeAlphaFlagsKHR::INHERIT,
        vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
        vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
    ]
    .into_iter()
    .find(|&c| caps.supported_composite_alpha.contains(c))
    .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);

    if slot.is_none() {
        let swap_loader = ash::khr::swapchain::Device::new(
            &device.shared.instance.instance,
            &device.shared.device,
        );
        // SAFETY: valid device and create info.
        let acquired = unsafe {
            device
                .shared
                .device
                .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
        }
        .during("vkCreateSemaphore")?;
        *slot = Some(Presenter {
            shared: device.shared.clone(),
            loader: swap_loader,
            swapchain: vk::SwapchainKHR::null(),
            images: Vec::new(),
            extent: [0, 0],
            format: format.format,
            present_mode,
            acquired,
            copied: Vec::new(),
            frame: None,
            staging: None,
            stale: false,
        });
    }
    let p = slot.as_mut().expect("presenter was just created");
    let old = p.swapchain;
    let info = vk::SwapchainCreateInfoKHR::default()
        .surface(surface)
        .min_image_count(image_count)
        .image_format(format.format)
        .image_color_space(format.color_space)
        .image_extent(vk::Extent2D {
            width: extent[0],
            height: extent[1],
        })
        .image_array_layers(1)
        .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
        .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
        .pre_transform(caps.current_transform)
        .composite_alpha(composite)
        .present_mode(present_mode)
        .clipped(true)
        .old_swapchain(old);
    // SAFETY: valid device, surface and create info; the old swapchain (retired by this call) is
    // destroyed below, after the device is idle.
    let swapchain =
        unsafe { p.loader.create_swapchain(&info, None) }.during("vkCreateSwapchainKHR")?;
    p.destroy_swapchain();
    p.swapchain = swapchain;
    // SAFETY: the swapchain was just created.
    p.images =
        unsafe { p.loader.get_swapchain_images(swapchain) }.during("vkGetSwapchainImagesKHR")?;
    for _ in 0..p.images.len() {
        // SAFETY: valid device and create info; stored at once so Drop destroys it.
        let s = unsafe {
            p.shared
                .device
                .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
        }
        .during("vkCreateSemaphore")?;
        p.copied.push(s);
    }
    p.extent = extent;
    p.format = format.format;
    p.present_mode = present_mode;
    p.stale = false;
    Ok(())
}

/// The frame image of the frame's size and a staging buffer for host pixels and the HUD.
fn ensure_present_resources(
    device: &Device,
    slot: &mut Option<Presenter>,
    frame_size: [u32; 2],
    source: PresentSource<'_>,
    hud: Option<HudOverlay<'_>>,
) -> Result<()> {
    let shared = device.shared.clone();
    let p = slot.as_mut().expect("swapchain was created");
    let format = frame_format_for(p.format);
    if p.frame.as_ref().map(|f| f.size) != Some(frame_size) {
        p.frame = None;
        p.frame = Some(OwnedImage::new(&shared, frame_size, format)?);
    }
    let host_bytes = source.host_bytes();
    let hud_bytes = hud.map_or(0, |h| h.pixels.len() as u64 * 4);
    let needed = host_bytes + hud_bytes;
    if needed > 0 && p.staging.as_ref().is_none_or(|s| s.size < needed) {
        p.staging = None;
        p.staging = Some(GpuBuffer::new(
            &shared,
            "present staging",
            needed,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?);
    }
    if let Some(staging) = p.staging.as_mut() {
        let mut parts: Vec<(u64, &[u8])> = Vec::new();
        if let PresentSource::Host { pixels, .. } = source {
            parts.push((0, bytemuck::cast_slice(pixels)));
        }
        if let Some(h) = hud {
            parts.push((host_bytes, bytemuck::cast_slice(h.pixels)));
        }
        if !parts.is_empty() {
            staging.write_parts(&parts)?;
        }
    }
    Ok(())
}

/// Records and submits the copies of one present into swapchain image `index`: source → frame image,
/// frame image → swapchain image (blit), HUD → the swapchain image's corner, then the layout for
/// presenting.
///
/// Long because presenting is one command buffer of dependent steps: the image's barriers, the copy
/// or blit, the HUD's copy, the layout transitions, the submission.
fn record_and_submit_copy(
    device: &mut Device,
    slot: &mut Option<Presenter>,
    last_frame: Option<(vk::Buffer, u32, u32)>,
    index: u32,
    source: PresentSource<'_>,
    hud: Option<HudOverlay<'_>>,
) -> Result<()> {
    let p = slot.as_ref().expect("presenter exists");
    let frame = p.frame.as_ref().expect("frame image exists");
    let (frame_image, [fw, fh]) = (frame.image, frame.size);
    let swap_image = p.images[index as usize];
    let extent = p.extent;
    let staging = p.staging.as_ref().map(|s| s.buffer);
    let (acquired, copied) = (p.acquired, p.copied[index as usize]);
    let (src_buffer, src_offset) = match source {
        PresentSource::LastFrame => (last_frame.expect("checked by present").0, 0u64),
        PresentSource::Host { .. } => (staging.expect("staging holds the host frame"), 0),
    };
    let hud_offset = source.host_bytes();
    // The HUD goes straight onto the swapchain image, after the (possibly scaling) blit, so its text
    // stays sharp at any render scale. Its pixels are grey, so RGBA and BGRA read the same; other
    // swapchain formats get no HUD.
    let byte_format = matches!(
        p.format,
        vk::Format::B8G8R8A8_UNORM
            | vk::Format::R8G8B8A8_UNORM
            | vk::Format::B8G8R8A8_SRGB
            | vk::Format::R8G8B8A8_SRGB
    );
    let hud_copy = hud.filter(|_| byte_format).and_then(|h| {
        let w = h.width.min(extent[0].saturating_sub(h.x));
        let hh = h.height.min(extent[1].saturating_sub(h.y));
        (w > 0 && hh > 0 && h.pixels.len() as u64 >= u64::from(h.width) * u64::from(h.height))
            .then_some((h, w, hh))
    });
    let color = vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .layer_count(1);
    let layers = vk::ImageSubresourceLayers::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .layer_count(1);
    let transition = |image: vk::Image,
                      from: vk::ImageLayout,
                      to: vk::ImageLayout,
                      src_access: vk::AccessFlags,
                      dst_access: vk::AccessFlags| {
        vk::ImageMemoryBarrier::default()
            .image(image)
            .old_layout(from)
            .new_layout(to)
            .src_access_mask(src_access)
            .dst_access_mask(dst_access)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .subresource_range(color)
    };
    device.submit_and_wait_with(
        "a present copy",
        CHUNK_TIMEOUT,
        Some((acquired, vk::PipelineStageFlags::TRANSFER)),
        Some(copied),
        |device, cb| {
            // SAFETY: (whole closure) recording into a command buffer in the recording state; every
            // buffer and image is alive until the submission's fence is waited on, and the regions
            // lie inside them (the HUD copy is clipped to the swapchain image).
            unsafe {
                // The kernel's writes (an earlier submission) and host writes before the copies.
                let memory = [vk::MemoryBarrier::default()
                    .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::HOST_WRITE)
                    .dst_access_mask(vk::AccessFlags::TRANSFER_READ)];
                let to_dst = [transition(
                    frame_image,
                    vk::ImageLayout::UNDEFINED,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::AccessFlags::empty(),
                    vk::AccessFlags::TRANSFER_WRITE,
                )];
                device.cmd_pipeline_barrier(
                    cb,
                    vk::PipelineStageFlags::COMPUTE_SHADER
                        | vk::PipelineStageFlags::HOST
                        | vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::DependencyFlags::empty(),
                    &memory,
                    &[],
                    &to_dst,
                );
                let full = [vk::BufferImageCopy::default()
                    .buffer_offset(src_offset)
                    .image_subresource(layers)
                    .image_extent(vk::Extent3D {
                        width: fw,
                        height: fh,
                        depth: 1,
                    })];
                device.cmd_copy_buffer_to_image(
                    cb,
                    src_buffer,
                    frame_image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &full,
                );
                let to_blit = [
                    transition(
                        frame_image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                        vk::AccessFlags::TRANSFER_WRITE,
                        vk::AccessFlags::TRANSFER_READ,
                    ),
                    transition(
                        swap_image,
                        vk::ImageLayout::UNDEFINED,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        vk::AccessFlags::empty(),
                        vk::AccessFlags::TRANSFER_WRITE,
                    ),
                ];
                let transfer = (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::TRANSFER,
                );
                image_barrier(device, cb, transfer, &to_blit);
                let corner = |w: u32, h: u32| {
                    [
                        vk::Offset3D::default(),
                        vk::Offset3D {
                            x: w as i32,
                            y: h as i32,
                            z: 1,
                        },
                    ]
                };
                let blit = [vk::ImageBlit::default()
                    .src_subresource(layers)
                    .src_offsets(corner(fw, fh))
                    .dst_subresource(layers)
                    .dst_offsets(corner(extent[0], extent[1]))];
                let filter = if [fw, fh] == extent {
                    vk::Filter::NEAREST
                } else {
                    vk::Filter::LINEAR
                };
                device.cmd_blit_image(
                    cb,
                    frame_image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    swap_image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &blit,
                    filter,
                );
                if let (Some((h, w, hh)), Some(staging)) = (hud_copy, staging) {
                    let again = [transition(
                        swap_image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        vk::AccessFlags::TRANSFER_WRITE,
                        vk::AccessFlags::TRANSFER_WRITE,
                    )];
                    image_barrier(device, cb, transfer, &again);
                    let region = [vk::BufferImageCopy::default()
                        .buffer_offset(hud_offset)
                        .buffer_row_length(h.width)
                        .image_subresource(layers)
                        .image_offset(vk::Offset3D {
                            x: h.x as i32,
                            y: h.y as i32,
                            z: 0,
                        })
                        .image_extent(vk::Extent3D {
                            width: w,
                            height: hh,
                            depth: 1,
                        })];
                    device.cmd_copy_buffer_to_image(
                        cb,
                        staging,
                        swap_image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &region,
                    );
                }
                let to_present = [transition(
                    swap_image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::ImageLayout::PRESENT_SRC_KHR,
                    vk::AccessFlags::TRANSFER_WRITE,
                    vk::AccessFlags::empty(),
                )];
                image_barrier(
                    device,
                    cb,
                    (
                        vk::PipelineStageFlags::TRANSFER,
                        vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                    ),
                    &to_present,
                );
            }
        },
    )
}
