//! A headset through OpenXR (`fovea xr`): the runtime's instance and headset ([`XrSystem`]), and a
//! session ([`XrSession`]) whose swapchain the eyes' images go into.
//!
//! The runtime chooses the Vulkan instance and device (`XR_KHR_vulkan_enable2`): [`XrSystem`] is a
//! [`DeviceFactory`], so the [`VulkanContext`] that renders (or, with the CPU backend, only uploads)
//! is made by the runtime from fovea's own create infos, on the headset's GPU, with a queue that can
//! also do graphics. The session is created on that context's device; one swapchain of two array
//! layers holds the eyes, and each eye's RGBA8 image (the kernel's tone map output, still on the
//! device, or the CPU's pixels through a staging buffer) is copied into its layer right after the eye
//! is rendered, on the context's queue, with no round trip through the host. Pacing follows
//! `xrWaitFrame`, `xrBeginFrame` and `xrEndFrame`.
//!
//! Where the runtime offers `XR_EXT_eye_gaze_interaction`, the eyes' combined gaze ray is read each frame
//! ([`XrFrame::gaze_ray`]), for the command line to project into each eye.
//!
//! Tested headless against Monado's null compositor and simulated headset (`scripts/setup-monado.sh`).
use std::sync::Arc;

use ash::vk::{self, Handle};
use gpu_allocator::MemoryLocation;
use openxr as xr;

use crate::barrier::image_barrier;
use crate::buffer::GpuBuffer;
use crate::context::{VulkanContext, CHUNK_TIMEOUT};
use crate::error::{Result as VkResult, VulkanError};
use crate::factory::{DeviceFactory, SharedFactory};
use crate::present::PresentSource;

/// The views of a stereo headset: the left eye, then the right.
pub const XR_EYES: usize = 2;

/// How long a session may take to become ready (the runtime's `READY` state) before `fovea xr` gives up.
pub const READY_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(30);

const VIEW_TYPE: xr::ViewConfigurationType = xr::ViewConfigurationType::PRIMARY_STEREO;

/// The Vulkan version fovea's context asks for (the runtime must allow it).
const VULKAN_VERSION: xr::Version = xr::Version::new(1, 2, 0);

/// One eye as the runtime locates it for a frame: its pose in the session's local space (metres,
/// looking along -z, y up) and its field of view as `XrFovf`'s four angles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct XrEyeView {
    pub position: [f32; 3],
    /// Unit quaternion `x, y, z, w`.
    pub orientation: [f32; 4],
    /// `[left, right, up, down]` in radians.
    pub angles: [f32; 4],
}

/// A frame the runtime has begun: render it (if `should_render`), copy each eye in
/// ([`XrSession::copy_eye`]) and end it ([`XrSession::end_frame`]).
#[derive(Clone, Copy, Debug)]
pub struct XrFrame {
    predicted_display_time: xr::Time,
    pub should_render: bool,
    /// Whether the runtime tracks the head's orientation this frame (a simulated headset may not).
    pub orientation_tracked: bool,
    pub views: [XrEyeView; XR_EYES],
    /// The eyes' combined gaze ray from `XR_EXT_eye_gaze_interaction`, where the runtime tracks it
    /// this frame: its origin and unit direction in the session's local space.
    pub gaze_ray: Option<GazeRay>,
}

/// A gaze ray in the session's local space: its origin, and its unit direction.
pub type GazeRay = ([f32; 3], [f32; 3]);

/// The eye-gaze action (`XR_EXT_eye_gaze_interaction`): its action set and the space its pose is
/// located in.
struct EyeGaze {
    set: xr::ActionSet,
    /// Kept with its space.
    _action: xr::Action<xr::Posef>,
    space: xr::Space,
}

/// Where the session stands after the runtime's events are read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SessionStatus {
    /// Frames may be rendered.
    Running,
    /// Not yet (or no longer) visible: wait and poll again.
    Waiting,
    /// The session is over; the text says why (an exit fovea asked for, or the runtime's).
    Over(String),
}

/// An OpenXR error as text naming the call.
fn xr_error(call: &'static str) -> impl Fn(xr::sys::Result) -> String {
    move |r| format!("{call} failed: {r}")
}

/// The OpenXR runtime's instance and its head-mounted system.
pub struct XrSystem {
    instance: xr::Instance,
    system: xr::SystemId,
    blend: xr::EnvironmentBlendMode,
    /// The runtime's name and version.
    pub runtime: String,
    /// The headset's name.
    pub system_name: String,
    /// Each eye's image size the runtime recommends, and the largest it allows.
    pub recommended_size: [u32; 2],
    pub max_size: [u32; 2],
    /// Whether the runtime offers `XR_EXT_eye_gaze_interaction` (then enabled, and read each frame).
    pub eye_gaze_available: bool,
}

impl XrSystem {
    /// Loads the OpenXR loader, creates an instance with `XR_KHR_vulkan_enable2` on the runtime it
    /// names and finds a head-mounted system with a stereo view that allows Vulkan 1.2. The errors
    /// say what is missing and how to get it.
    pub fn new() -> Result<Self, String> {
        // SAFETY: loading the system's OpenXR loader runs its initialisation; we trust the loader.
        let entry = unsafe { xr::Entry::load(&()) }.map_err(|e| {
            format!(
                "no OpenXR loader ({e}); install one (Debian/Ubuntu: apt install libopenxr-loader1)"
            )
        })?;
        let no_runtime = |e: xr::sys::Result| {
            format!(
                "no OpenXR runtime ({e}); point XR_RUNTIME_JSON at a runtime's manifest (Monado: \
                 bash scripts/setup-monado.sh, then XR_RUNTIME_JSON=$HOME/.cache/fovea/monado/\
                 build/openxr_monado-dev.json)"
            )
        };
        let available = entry.enumerate_extensions().map_err(no_runtime)?;
        if !available.khr_vulkan_enable2 {
            return Err(
                "the OpenXR runtime has no Vulkan support (XR_KHR_vulkan_enable2); fovea renders \
                 through Vulkan"
                    .into(),
            );
        }
        let mut wanted = xr::ExtensionSet::default();
        wanted.khr_vulkan_enable2 = true;
        wanted.ext_eye_gaze_interaction = available.ext_eye_gaze_interaction;
        let instance = entry
            .create_instance(
                &xr::ApplicationInfo {
                    application_name: "fovea",
                    application_version: 0,
                    engine_name: "fovea",
                    engine_version: 0,
                    api_version: xr::Version::new(1, 0, 0),
                },
                &wanted,
                &[],
                &(),
            )
            .map_err(|e| match e {
                xr::sys::Result::ERROR_RUNTIME_UNAVAILABLE
                | xr::sys::Result::ERROR_RUNTIME_FAILURE => no_runtime(e),
                other => format!("xrCreateInstance failed: {other}"),
            })?;
        let properties = instance
            .properties()
            .map_err(xr_error("xrGetInstanceProperties"))?;
        let runtime = format!("{} {}", properties.runtime_name, properties.runtime_version);
        let system = instance
            .system(xr::FormFactor::HEAD_MOUNTED_DISPLAY)
            .map_err(|e| format!("the OpenXR runtime {runtime} finds no headset ({e})"))?;
        let system_name = instance
            .system_properties(system)
            .map(|p| p.system_name)
            .unwrap_or_default();
        let blend = instance
            .enumerate_environment_blend_modes(system, VIEW_TYPE)
            .map_err(xr_error("xrEnumerateEnvironmentBlendModes"))?
            .first()
            .copied()
            .ok_or("the headset offers no blend mode for a stereo view")?;
        let views = instance
            .enumerate_view_configuration_views(system, VIEW_TYPE)
            .map_err(|e| format!("the headset has no stereo view configuration ({e})"))?;
        if views.len() != XR_EYES {
            return Err(format!(
                "the headset's stereo view configuration has {} views, not 2",
                views.len()
            ));
        }
        // The runtime must be asked for its requirements before its Vulkan instance is made.
        let requirements = instance
            .graphics_requirements::<xr::Vulkan>(system)
            .map_err(xr_error("xrGetVulkanGraphicsRequirements2KHR"))?;
        if VULKAN_VERSION < requirements.min_api_version_supported
            || VULKAN_VERSION.major() > requirements.max_api_version_supported.major()
        {
            return Err(format!(
                "the OpenXR runtime needs Vulkan {} to {}, and fovea's kernel needs 1.2",
                requirements.min_api_version_supported, requirements.max_api_version_supported
            ));
        }
        Ok(Self {
            eye_gaze_available: available.ext_eye_gaze_interaction,
            instance,
            system,
            blend,
            runtime,
            system_name,
            recommended_size: [
                views[0].recommended_image_rect_width,
                views[0].recommended_image_rect_height,
            ],
            max_size: [
                views[0].max_image_rect_width,
                views[0].max_image_rect_height,
            ],
        })
    }

    /// What makes a [`VulkanContext`] on the headset's GPU ([`crate::ContextOptions::factory`]).
    #[must_use]
    pub fn device_factory(&self) -> SharedFactory {
        Arc::new(XrFactory {
            instance: self.instance.clone(),
            system: self.system,
        })
    }
}

/// Has the runtime create the context's instance and device (`xrCreateVulkanInstanceKHR`,
/// `xrGetVulkanGraphicsDevice2KHR`, `xrCreateVulkanDeviceKHR`).
struct XrFactory {
    instance: xr::Instance,
    system: xr::SystemId,
}

impl std::fmt::Debug for XrFactory {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("XrFactory").finish_non_exhaustive()
    }
}

/// The loader's `vkGetInstanceProcAddr` as OpenXR's function pointer type.
fn get_instance_proc_addr(entry: &ash::Entry) -> xr::sys::platform::VkGetInstanceProcAddr {
    // SAFETY: both are `extern "system"` functions of the same signature (OpenXR declares Vulkan's
    // handle types as opaque pointers).
    unsafe { std::mem::transmute(entry.static_fn().get_instance_proc_addr) }
}

impl DeviceFactory for XrFactory {
    unsafe fn create_instance(
        &self,
        entry: &ash::Entry,
        info: &vk::InstanceCreateInfo<'_>,
    ) -> VkResult<ash::Instance> {
        // SAFETY: the caller keeps `info` valid for the call; the loader's function pointer is valid.
        let raw = unsafe {
            self.instance.create_vulkan_instance(
                self.system,
                get_instance_proc_addr(entry),
                info as *const vk::InstanceCreateInfo<'_> as *const _,
            )
        }
        .map_err(|e| VulkanError::Invalid(format!("xrCreateVulkanInstanceKHR failed: {e}")))?
        .map_err(|r| VulkanError::vk("xrCreateVulkanInstanceKHR", vk::Result::from_raw(r)))?;
        // SAFETY: the runtime created this instance with the entry's loader.
        Ok(unsafe { ash::Instance::load(entry.static_fn(), vk::Instance::from_raw(raw as _)) })
    }

    fn physical_device(&self, instance: &ash::Instance) -> VkResult<Option<vk::PhysicalDevice>> {
        // SAFETY: the instance was created by this runtime (`create_instance`).
        let raw = unsafe {
            self.instance
                .vulkan_graphics_device(self.system, instance.handle().as_raw() as _)
        }
        .map_err(|e| VulkanError::Invalid(format!("xrGetVulkanGraphicsDevice2KHR failed: {e}")))?;
        Ok(Some(vk::PhysicalDevice::from_raw(raw as _)))
    }

    unsafe fn create_device(
        &self,
        entry: &ash::Entry,
        instance: &ash::Instance,
        physical: vk::PhysicalDevice,
        info: &vk::DeviceCreateInfo<'_>,
    ) -> VkResult<ash::Device> {
        // SAFETY: the caller keeps `info` valid and `physical` is the runtime's own device.
        let raw = unsafe {
            self.instance.create_vulkan_device(
                self.system,
                get_instance_proc_addr(entry),
                physical.as_raw() as _,
                info as *const vk::DeviceCreateInfo<'_> as *const _,
            )
        }
        .map_err(|e| VulkanError::Invalid(format!("xrCreateVulkanDeviceKHR failed: {e}")))?
        .map_err(|r| VulkanError::vk("xrCreateVulkanDeviceKHR", vk::Result::from_raw(r)))?;
        // SAFETY: the runtime created this device on `physical` of `instance`.
        Ok(unsafe { ash::Device::load(instance.fp_v1_0(), vk::Device::from_raw(raw as _)) })
    }

    fn needs_graphics_queue(&self) -> bool {
        true
    }
}

/// The runtime's swapchain: two array layers, one per eye.
struct EyeSwapchain {
    handle: xr::Swapchain<xr::Vulkan>,
    images: Vec<vk::Image>,
    size: [u32; 2],
    /// The image acquired for the frame being rendered.
    acquired: Option<vk::Image>,
}

/// An OpenXR session on a context the runtime made ([`XrSystem::device_factory`]). Drop it before
/// that context.
pub struct XrSession {
    /// The eyes' gaze, where the runtime offers it.
    eye_gaze: Option<EyeGaze>,
    /// Why the eye-gaze action could not be set up, if it could not.
    pub eye_gaze_note: Option<String>,
    swapchain: Option<EyeSwapchain>,
    /// Host pixels (the CPU backend's eyes) on their way into the swapchain.
    staging: Option<GpuBuffer>,
    space: xr::Space,
    stream: xr::FrameStream<xr::Vulkan>,
    waiter: xr::FrameWaiter,
    session: xr::Session<xr::Vulkan>,
    instance: xr::Instance,
    blend: xr::EnvironmentBlendMode,
    events: xr::EventDataBuffer,
    running: bool,
    exit_requested: bool,
}

impl XrSession {
    /// A session on `ctx`'s device and queue, with a local reference space.
    pub fn new(system: &XrSystem, ctx: &VulkanContext) -> Result<Self, String> {
        let device = ctx.device();
        // SAFETY: the handles are the runtime's own instance, physical device and device (made by
        // `system`'s factory), alive until the context is dropped, after this session.
        let (session, waiter, stream) = unsafe {
            system.instance.create_session::<xr::Vulkan>(
                system.system,
                &xr::vulkan::SessionCreateInfo {
                    instance: device.shared.instance.instance.handle().as_raw() as _,
                    physical_device: device.shared.physical_device.as_raw() as _,
                    device: device.shared.device.handle().as_raw() as _,
                    queue_family_index: device.queue_family,
                    queue_index: 0,
                },
            )
        }
        .map_err(xr_error("xrCreateSession"))?;
        let space = session
            .create_reference_space(xr::ReferenceSpaceType::LOCAL, xr::Posef::IDENTITY)
            .map_err(xr_error("xrCreateReferenceSpace"))?;
        let (eye_gaze, eye_gaze_note) = if system.eye_gaze_available {
            match eye_gaze_action(&system.instance, &session) {
                Ok(g) => (Some(g), None),
                Err(e) => (
                    None,
                    Some(format!("the eye-gaze action could not be set up: {e}")),
                ),
            }
        } else {
            (None, None)
        };
        Ok(Self {
            eye_gaze,
            eye_gaze_note,
            swapchain: None,
            staging: None,
            space,
            stream,
            waiter,
            session,
            instance: system.instance.clone(),
            blend: system.blend,
            events: xr::EventDataBuffer::new(),
            running: false,
            exit_requested: false,
        })
    }

    /// Makes the swapchain for eyes of `size` pixels (at most `system`'s [`XrSystem::max_size`]) in
    /// `R8G8B8A8_SRGB`, the layout of the kernel's 8-bit image, so that each eye is one copy.
    pub fn create_swapchain(&mut self, system: &XrSystem, size: [u32; 2]) -> Result<(), String> {
        let max = system.max_size;
        if size[0] == 0 || size[1] == 0 || size[0] > max[0] || size[1] > max[1] {
            return Err(format!(
                "{}x{} per eye is outside what the headset allows (1x1 to {}x{})",
                size[0], size[1], max[0], max[1]
            ));
        }
        let formats = self
            .session
            .enumerate_swapchain_formats()
            .map_err(xr_error("xrEnumerateSwapchainFormats"))?;
        let format = vk::Format::R8G8B8A8_SRGB;
        if !formats.contains(&(format.as_raw() as u32)) {
            return Err(format!(
                "the runtime offers no R8G8B8A8_SRGB swapchain (it offers Vulkan formats {formats:?}); \
                 fovea copies its 8-bit sRGB image into one"
            ));
        }
        let handle = self
            .session
            .create_swapchain(&xr::SwapchainCreateInfo {
                create_flags: xr::SwapchainCreateFlags::EMPTY,
                usage_flags: xr::SwapchainUsageFlags::COLOR_ATTACHMENT
                    | xr::SwapchainUsageFlags::TRANSFER_DST,
                format: format.as_raw() as u32,
                sample_count: 1,
                width: size[0],
                height: size[1],
                face_count: 1,
                array_size: XR_EYES as u32,
                mip_count: 1,
            })
            .map_err(xr_error("xrCreateSwapchain"))?;
        let images = handle
            .enumerate_images()
            .map_err(xr_error("xrEnumerateSwapchainImages"))?
            .into_iter()
            .map(vk::Image::from_raw)
            .collect();
        self.swapchain = Some(EyeSwapchain {
            handle,
            images,
            size,
            acquired: None,
        });
        Ok(())
    }

    /// Reads the runtime's events: begins the session when it is ready, ends it when it stops.
    pub fn poll(&mut self) -> Result<SessionStatus, String> {
        while let Some(event) = self
            .instance
            .poll_event(&mut self.events)
            .map_err(xr_error("xrPollEvent"))?
        {
            match event {
                xr::Event::SessionStateChanged(e) => match e.state() {
                    xr::SessionState::READY => {
                        self.session
                            .begin(VIEW_TYPE)
                            .map_err(xr_error("xrBeginSession"))?;
                        self.running = true;
                    }
                    xr::SessionState::STOPPING => {
                        self.session.end().map_err(xr_error("xrEndSession"))?;
                        self.running = false;
                    }
                    xr::SessionState::EXITING => {
                        return Ok(SessionStatus::Over(if self.exit_requested {
                            "the session ended as asked".into()
                        } else {
                            "the runtime ended the session (exit requested by the runtime)".into()
                        }))
                    }
                    xr::SessionState::LOSS_PENDING => {
                        return Ok(SessionStatus::Over(
                            "the runtime lost the session (XR_SESSION_STATE_LOSS_PENDING)".into(),
                        ))
                    }
                    _ => {}
                },
                xr::Event::InstanceLossPending(_) => {
                    return Ok(SessionStatus::Over(
                        "the OpenXR instance is being lost (the runtime is going away)".into(),
                    ))
                }
                _ => {}
            }
        }
        Ok(if self.running {
            SessionStatus::Running
        } else {
            SessionStatus::Waiting
        })
    }

    /// Asks the runtime to end the session (it then stops and exits through [`Self::poll`]).
    pub fn request_exit(&mut self) -> Result<(), String> {
        self.exit_requested = true;
        match self.session.request_exit() {
            Ok(()) | Err(xr::sys::Result::ERROR_SESSION_NOT_RUNNING) => Ok(()),
            Err(e) => Err(format!("xrRequestExitSession failed: {e}")),
        }
    }

    /// Waits for the runtime's next frame (`xrWaitFrame`), begins it, locates both eyes at its
    /// predicted display time and, when the frame is to be rendered, acquires the swapchain image
    /// the eyes are copied into.
    pub fn begin_frame(&mut self) -> Result<XrFrame, String> {
        let state = self.waiter.wait().map_err(xr_error("xrWaitFrame"))?;
        self.stream.begin().map_err(xr_error("xrBeginFrame"))?;
        let (flags, views) = self
            .session
            .locate_views(VIEW_TYPE, state.predicted_display_time, &self.space)
            .map_err(xr_error("xrLocateViews"))?;
        if views.len() != XR_EYES {
            return Err(format!("xrLocateViews gave {} views, not 2", views.len()));
        }
        let eye = |v: &xr::View| XrEyeView {
            position: [v.pose.position.x, v.pose.position.y, v.pose.position.z],
            orientation: [
                v.pose.orientation.x,
                v.pose.orientation.y,
                v.pose.orientation.z,
                v.pose.orientation.w,
            ],
            angles: [
                v.fov.angle_left,
                v.fov.angle_right,
                v.fov.angle_up,
                v.fov.angle_down,
            ],
        };
        if state.should_render {
            let swapchain = self
                .swapchain
                .as_mut()
                .ok_or("no swapchain: create_swapchain comes before the first frame")?;
            let index = swapchain
                .handle
                .acquire_image()
                .map_err(xr_error("xrAcquireSwapchainImage"))?;
            swapchain
                .handle
                .wait_image(xr::Duration::INFINITE)
                .map_err(xr_error("xrWaitSwapchainImage"))?;
            swapchain.acquired = Some(
                *swapchain
                    .images
                    .get(index as usize)
                    .ok_or("the runtime acquired an image it did not list")?,
            );
        }
        let gaze_ray = match &self.eye_gaze {
            Some(g) => self.locate_gaze(g, state.predicted_display_time)?,
            None => None,
        };
        Ok(XrFrame {
            predicted_display_time: state.predicted_display_time,
            should_render: state.should_render,
            orientation_tracked: flags.contains(xr::ViewStateFlags::ORIENTATION_TRACKED),
            views: [eye(&views[0]), eye(&views[1])],
            gaze_ray,
        })
    }

    /// The eye-gaze pose at `time` in the session's local space, as a ray, where it is tracked.
    fn locate_gaze(&self, g: &EyeGaze, time: xr::Time) -> Result<Option<GazeRay>, String> {
        self.session
            .sync_actions(&[xr::ActiveActionSet::new(&g.set)])
            .map_err(xr_error("xrSyncActions"))?;
        let location = g
            .space
            .locate(&self.space, time)
            .map_err(xr_error("xrLocateSpace"))?;
        let tracked = xr::SpaceLocationFlags::ORIENTATION_VALID
            | xr::SpaceLocationFlags::POSITION_VALID
            | xr::SpaceLocationFlags::ORIENTATION_TRACKED;
        if !location.location_flags.contains(tracked) {
            return Ok(None);
        }
        let p = location.pose.position;
        let q = location.pose.orientation;
        Ok(Some((
            [p.x, p.y, p.z],
            gaze_direction([q.x, q.y, q.z, q.w]),
        )))
    }

    /// Copies eye `eye`'s RGBA8 image into its layer of the acquired swapchain image, on `ctx`'s
    /// queue: the frame `ctx` rendered last ([`PresentSource::LastFrame`], still on the device), or
    /// host pixels through a staging buffer. The image is in `COLOR_ATTACHMENT_OPTIMAL` before and
    /// after, as OpenXR hands it over and takes it back.
    pub fn copy_eye(
        &mut self,
        ctx: &mut VulkanContext,
        eye: usize,
        source: PresentSource<'_>,
    ) -> Result<(), String> {
        let swapchain = self.swapchain.as_ref().ok_or("no swapchain")?;
        let image = swapchain
            .acquired
            .ok_or("no swapchain image is acquired (a frame the runtime did not want rendered)")?;
        let [w, h] = swapchain.size;
        let vk_err = |e: VulkanError| format!("copying eye {eye} into the swapchain: {e}");
        let buffer = match source {
            PresentSource::LastFrame => {
                let (buffer, fw, fh) = ctx
                    .last_ldr_buffer()
                    .ok_or("copy_eye: no frame has been rendered on this context")?;
                if [fw, fh] != [w, h] {
                    return Err(format!(
                        "eye {eye} was rendered at {fw}x{fh} for a {w}x{h} swapchain"
                    ));
                }
                buffer
            }
            PresentSource::Host {
                pixels,
                width,
                height,
            } => {
                if [width, height] != [w, h] || pixels.len() as u64 != u64::from(w) * u64::from(h) {
                    return Err(format!(
                        "eye {eye}: {} pixels of {width}x{height} for a {w}x{h} swapchain",
                        pixels.len()
                    ));
                }
                let bytes = u64::from(w) * u64::from(h) * 4;
                if self.staging.as_ref().is_none_or(|s| s.size < bytes) {
                    self.staging = Some(
                        GpuBuffer::new(
                            &ctx.device().shared,
                            "headset staging",
                            bytes,
                            vk::BufferUsageFlags::TRANSFER_SRC,
                            MemoryLocation::CpuToGpu,
                        )
                        .map_err(vk_err)?,
                    );
                }
                let staging = self.staging.as_mut().expect("just made");
                staging.write(pixels).map_err(vk_err)?;
                staging.buffer
            }
        };
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .base_mip_level(0)
            .level_count(1)
            .base_array_layer(eye as u32)
            .layer_count(1);
        let to_transfer = [vk::ImageMemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
            .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .old_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(range)];
        let back = [vk::ImageMemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_READ)
            .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .new_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(range)];
        let region = [vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .mip_level(0)
                    .base_array_layer(eye as u32)
                    .layer_count(1),
            )
            .image_extent(vk::Extent3D {
                width: w,
                height: h,
                depth: 1,
            })];
        ctx.device_mut()
            .submit_and_wait("a headset eye's copy", CHUNK_TIMEOUT, |device, cb| {
                image_barrier(
                    device,
                    cb,
                    (
                        vk::PipelineStageFlags::ALL_COMMANDS,
                        vk::PipelineStageFlags::TRANSFER,
                    ),
                    &to_transfer,
                );
                // SAFETY: the buffer holds `w · h` RGBA8 pixels and outlives the wait; the image is
                // the acquired swapchain image, in TRANSFER_DST_OPTIMAL after the barrier above.
                unsafe {
                    device.cmd_copy_buffer_to_image(
                        cb,
                        buffer,
                        image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &region,
                    );
                }
                image_barrier(
                    device,
                    cb,
                    (
                        vk::PipelineStageFlags::TRANSFER,
                        vk::PipelineStageFlags::ALL_COMMANDS,
                    ),
                    &back,
                );
            })
            .map_err(vk_err)
    }

    /// Ends `frame`: with `rendered`, releases the swapchain image (both eyes copied in) and submits
    /// it as a projection layer at the poses the eyes were rendered for; without, submits no layer (a
    /// frame the runtime did not want rendered).
    pub fn end_frame(&mut self, frame: &XrFrame, rendered: bool) -> Result<(), String> {
        let Some(swapchain) = self.swapchain.as_mut() else {
            return Err("no swapchain".into());
        };
        if swapchain.acquired.take().is_some() {
            swapchain
                .handle
                .release_image()
                .map_err(xr_error("xrReleaseSwapchainImage"))?;
        }
        if !rendered {
            return self
                .stream
                .end(frame.predicted_display_time, self.blend, &[])
                .map_err(xr_error("xrEndFrame"));
        }
        let [w, h] = swapchain.size;
        let rect = xr::Rect2Di {
            offset: xr::Offset2Di { x: 0, y: 0 },
            extent: xr::Extent2Di {
                width: w as i32,
                height: h as i32,
            },
        };
        let views = [0u32, 1].map(|layer| {
            let v = &frame.views[layer as usize];
            xr::CompositionLayerProjectionView::new()
                .pose(xr::Posef {
                    orientation: xr::Quaternionf {
                        x: v.orientation[0],
                        y: v.orientation[1],
                        z: v.orientation[2],
                        w: v.orientation[3],
                    },
                    position: xr::Vector3f {
                        x: v.position[0],
                        y: v.position[1],
                        z: v.position[2],
                    },
                })
                .fov(xr::Fovf {
                    angle_left: v.angles[0],
                    angle_right: v.angles[1],
                    angle_up: v.angles[2],
                    angle_down: v.angles[3],
                })
                .sub_image(
                    xr::SwapchainSubImage::new()
                        .swapchain(&swapchain.handle)
                        .image_array_index(layer)
                        .image_rect(rect),
                )
        });
        let layer = xr::CompositionLayerProjection::new()
            .space(&self.space)
            .views(&views);
        self.stream
            .end(frame.predicted_display_time, self.blend, &[&layer])
            .map_err(xr_error("xrEndFrame"))
    }
}

/// The direction a pose looks along (its -z) for the unit quaternion `x, y, z, w`.
#[must_use]
pub fn gaze_direction([x, y, z, w]: [f32; 4]) -> [f32; 3] {
    // The third column of the rotation matrix, negated.
    [
        -(2.0 * (x * z + w * y)),
        -(2.0 * (y * z - w * x)),
        -(1.0 - 2.0 * (x * x + y * y)),
    ]
}

/// The eye-gaze action of `XR_EXT_eye_gaze_interaction`, bound to its interaction profile's gaze
/// pose, attached to `session`, and its space.
fn eye_gaze_action(
    instance: &xr::Instance,
    session: &xr::Session<xr::Vulkan>,
) -> Result<EyeGaze, String> {
    let set = instance
        .create_action_set("fovea_gaze", "fovea gaze", 0)
        .map_err(xr_error("xrCreateActionSet"))?;
    let action = set
        .create_action::<xr::Posef>("eye_gaze", "Eye gaze", &[])
        .map_err(xr_error("xrCreateAction"))?;
    let profile = instance
        .string_to_path("/interaction_profiles/ext/eye_gaze_interaction")
        .map_err(xr_error("xrStringToPath"))?;
    let pose = instance
        .string_to_path("/user/eyes_ext/input/gaze_ext/pose")
        .map_err(xr_error("xrStringToPath"))?;
    instance
        .suggest_interaction_profile_bindings(profile, &[xr::Binding::new(&action, pose)])
        .map_err(xr_error("xrSuggestInteractionProfileBindings"))?;
    session
        .attach_action_sets(&[&set])
        .map_err(xr_error("xrAttachSessionActionSets"))?;
    let space = action
        .create_space(session, xr::Path::NULL, xr::Posef::IDENTITY)
        .map_err(xr_error("xrCreateActionSpace"))?;
    Ok(EyeGaze {
        set,
        _action: action,
        space,
    })
}

impl std::fmt::Debug for XrSession {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("XrSession")
            .field("running", &self.running)
            .finish_non_exhaustive()
    }
}
