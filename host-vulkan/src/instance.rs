//! The Vulkan instance, the validation messenger and the device objects shared by everything that holds
//! GPU memory ([`Shared`]), plus the device list of `fovea devices`.
use std::ffi::{c_void, CStr};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::Allocator;

use crate::error::{Result, VkContext, VulkanError};

/// Messages the validation layer reported (warnings and errors), shared with the debug callback.
pub type MessageLog = Arc<Mutex<Vec<String>>>;

/// The validation layer's name.
const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// The instance, its loader and (with validation) the debug-utils messenger. Destroyed last.
pub(crate) struct InstanceHandle {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Owned here so the pointer the callback receives stays valid until the messenger is destroyed.
    _log_box: Box<MessageLog>,
    pub log: MessageLog,
    /// A window's surface (the live view), destroyed before the instance; every swapchain on it is
    /// destroyed earlier, with the context.
    pub surface: Option<(ash::khr::surface::Instance, vk::SurfaceKHR)>,
}

/// Records every warning or error the validation layer sends.
// SAFETY: only the loader calls this, with the messenger's user data (see below).
unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the loader passes a valid callback-data pointer for the duration of the call, and `user` is
    // the `Box<MessageLog>` owned by the `InstanceHandle` that outlives the messenger.
    let (message, log) = unsafe {
        let message = data
            .as_ref()
            .and_then(|d| d.message_as_c_str())
            .map(|m| m.to_string_lossy().into_owned())
            .unwrap_or_default();
        (message, &*(user as *const MessageLog))
    };
    if let Ok(mut log) = log.lock() {
        log.push(format!("[{severity:?} {kind:?}] {message}"));
    }
    vk::FALSE
}

impl InstanceHandle {
    /// Loads Vulkan and creates an instance (API 1.2). With `validation`, enables the Khronos validation
    /// layer and a messenger that records warnings and errors.
    pub fn new(validation: bool) -> Result<Self> {
        Self::with_extensions(validation, &[], None)
    }

    /// [`Self::new`] with `extra_extensions` enabled besides (a window's surface extensions); a missing
    /// one is an error that names it. With `factory`, it creates the instance from fovea's create info
    /// (an OpenXR runtime, which adds its own extensions).
    pub fn with_extensions(
        validation: bool,
        extra_extensions: &[&CStr],
        factory: Option<&dyn crate::factory::DeviceFactory>,
    ) -> Result<Self> {
        // SAFETY: loading the system Vulkan loader runs its initialisation code; we trust the loader.
        let entry =
            unsafe { ash::Entry::load() }.map_err(|e| VulkanError::NoLoader(e.to_string()))?;
        // SAFETY: plain query on a loaded entry.
        let version = unsafe { entry.try_enumerate_instance_version() }
            .during("vkEnumerateInstanceVersion")?
            .unwrap_or(vk::API_VERSION_1_0);
        if version < vk::API_VERSION_1_2 {
            return Err(VulkanError::NoDevice(format!(
                " (the loader only supports Vulkan {}.{})",
                vk::api_version_major(version),
                vk::api_version_minor(version)
            )));
        }
        let mut layers = Vec::new();
        let mut extensions = Vec::new();
        if validation {
            // SAFETY: plain queries on a loaded entry.
            let available = unsafe { entry.enumerate_instance_layer_properties() }
                .during("vkEnumerateInstanceLayerProperties")?;
            if !available
                .iter()
                .any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER))
            {
                return Err(VulkanError::ValidationUnavailable(
                    "VK_LAYER_KHRONOS_validation is not installed".into(),
                ));
            }
            // SAFETY: as above.
            let ext = unsafe { entry.enumerate_instance_extension_properties(None) }
                .during("vkEnumerateInstanceExtensionProperties")?;
            if !ext
                .iter()
                .any(|e| e.extension_name_as_c_str().ok() == Some(ash::ext::debug_utils::NAME))
            {
                return Err(VulkanError::ValidationUnavailable(
                    "VK_EXT_debug_utils is not available".into(),
                ));
            }
            layers.push(VALIDATION_LAYER.as_ptr());
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        if !extra_extensions.is_empty() {
            // SAFETY: plain query on a loaded entry.
            let available = unsafe { entry.enumerate_instance_extension_properties(None) }
                .during("vkEnumerateInstanceExtensionProperties")?;
            for &name in extra_extensions {
                if !available
                    .iter()
                    .any(|e| e.extension_name_as_c_str().ok() == Some(name))
                {
                    return Err(VulkanError::NoPresentation(format!(
                        "the Vulkan loader lacks the instance extension {} that this window system needs",
                        name.to_string_lossy()
                    )));
                }
                extensions.push(name.as_ptr());
            }
        }
        let app = vk::ApplicationInfo::default()
            .application_name(c"fovea")
            .engine_name(c"fovea")
            .api_version(vk::API_VERSION_1_2);
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        let instance = match factory {
            // SAFETY: `info` and the name arrays it points to live until the call returns.
            Some(factory) => unsafe { factory.create_instance(&entry, &info) }?,
            // SAFETY: as above.
            None => unsafe { entry.create_instance(&info, None) }.map_err(|r| match r {
                vk::Result::ERROR_INCOMPATIBLE_DRIVER => {
                    VulkanError::NoDevice(" (the loader found no compatible driver)".into())
                }
                other => VulkanError::vk("vkCreateInstance", other),
            })?,
        };
        let log: MessageLog = Arc::default();
        let log_box = Box::new(log.clone());
        let mut handle = Self {
            entry,
            instance,
            debug: None,
            _log_box: log_box,
            log,
            surface: None,
        };
        if validation {
            let loader = ash::ext::debug_utils::Instance::new(&handle.entry, &handle.instance);
            let user = &*handle._log_box as *const MessageLog as *mut c_void;
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                        | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback))
                .user_data(user);
            // SAFETY: the callback and its user data (boxed in `handle`) outlive the messenger, which
            // `Drop` destroys before the instance.
            let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }
                .during("vkCreateDebugUtilsMessengerEXT")?;
            handle.debug = Some((loader, messenger));
        }
        Ok(handle)
    }

    /// The physical devices in the loader's order (the order `--device N` indexes).
    pub fn physical_devices(&self) -> Result<Vec<vk::PhysicalDevice>> {
        // SAFETY: valid instance.
        unsafe { self.instance.enumerate_physical_devices() }.during("vkEnumeratePhysicalDevices")
    }

    /// The driver's name and version string (e.g. "llvmpipe, Mesa 25.0.7 (LLVM 15.0.6)"), from
    /// `VkPhysicalDeviceDriverProperties` (core in Vulkan 1.2); empty if the driver leaves it blank.
    fn driver(&self, pd: vk::PhysicalDevice) -> String {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        // SAFETY: `pd` was enumerated from this instance, which was created for Vulkan 1.2, and the
        // caller checked that the device supports 1.2 (where the query and the struct are core).
        unsafe {
            self.instance
                .get_physical_device_properties2(pd, &mut props)
        };
        let text = |c: Result<&std::ffi::CStr, _>| {
            c.map(|c| c.to_string_lossy().trim().to_string())
                .unwrap_or_default()
        };
        let name = text(driver.driver_name_as_c_str());
        let info = text(driver.driver_info_as_c_str());
        match (name.is_empty(), info.is_empty()) {
            (false, false) => format!("{name}, {info}"),
            (false, true) => name,
            _ => info,
        }
    }

    /// Describes one physical device.
    pub fn describe(&self, index: usize, pd: vk::PhysicalDevice) -> DeviceInfo {
        // SAFETY: `pd` was enumerated from this instance.
        let props = unsafe { self.instance.get_physical_device_properties(pd) };
        // SAFETY: as above.
        let queues = unsafe {
            self.instance
                .get_physical_device_queue_family_properties(pd)
        };
        let name = props
            .device_name_as_c_str()
            .map(|c| c.to_string_lossy().into_owned())
            .unwrap_or_else(|_| "unnamed device".into());
        let v = props.api_version;
        let driver = if v >= vk::API_VERSION_1_2 {
            self.driver(pd)
        } else {
            String::new()
        };
        let has_compute = queues
            .iter()
            .any(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE));
        let unsuitable = if v < vk::API_VERSION_1_2 {
            Some("needs Vulkan 1.2".to_string())
        } else if !has_compute {
            Some("no compute queue".to_string())
        } else {
            None
        };
        DeviceInfo {
            index,
            name,
            driver,
            device_type: device_type_name(props.device_type),
            api_version: [
                vk::api_version_major(v),
                vk::api_version_minor(v),
                vk::api_version_patch(v),
            ],
            preference: device_preference(props.device_type),
            unsuitable,
        }
    }
}

impl Drop for InstanceHandle {
    fn drop(&mut self) {
        // SAFETY: every child object (device, surface, messenger) is destroyed here or before, in order.
        unsafe {
            if let Some((loader, surface)) = self.surface.take() {
                loader.destroy_surface(surface, None);
            }
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// One Vulkan device as `fovea devices` lists it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceInfo {
    /// Position in the loader's list (what `--device` takes).
    pub index: usize,
    pub name: String,
    /// The driver and its version, e.g. "llvmpipe, Mesa 25.0.7 (LLVM 15.0.6)"; empty if unknown.
    pub driver: String,
    /// "discrete", "integrated", "virtual", "cpu" or "other".
    pub device_type: &'static str,
    /// Vulkan version the device supports: major, minor, patch.
    pub api_version: [u32; 3],
    /// Lower is preferred by automatic selection (discrete, integrated, virtual, cpu, other).
    pub preference: u32,
    /// Why the device cannot run fovea, if it cannot.
    pub unsuitable: Option<String>,
}

impl DeviceInfo {
    /// The name, then the driver if known: "NAME; DRIVER".
    #[must_use]
    pub fn description(&self) -> String {
        if self.driver.is_empty() {
            self.name.clone()
        } else {
            format!("{}; {}", self.name, self.driver)
        }
    }
}

fn device_type_name(t: vk::PhysicalDeviceType) -> &'static str {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual",
        vk::PhysicalDeviceType::CPU => "cpu",
        _ => "other",
    }
}

fn device_preference(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Picks a device: `requested` by index, else the most preferred suitable one (ties: loader order).
pub(crate) fn choose_device(devices: &[DeviceInfo], requested: Option<usize>) -> Result<usize> {
    if let Some(index) = requested {
        let info = devices
            .get(index)
            .ok_or(VulkanError::DeviceIndexOutOfRange {
                index,
                count: devices.len(),
            })?;
        if let Some(reason) = &info.unsuitable {
            return Err(VulkanError::UnsuitableDevice {
                device: info.name.clone(),
                reason: reason.clone(),
            });
        }
        return Ok(index);
    }
    devices
        .iter()
        .filter(|d| d.unsuitable.is_none())
        .min_by_key(|d| (d.preference, d.index))
        .map(|d| d.index)
        .ok_or_else(|| {
            if devices.is_empty() {
                VulkanError::NoDevice(" (the loader lists no device)".into())
            } else {
                VulkanError::NoDevice(format!(" ({} device(s), none suitable)", devices.len()))
            }
        })
}

/// Lists the Vulkan devices (no validation, no device creation).
pub fn list_devices() -> Result<Vec<DeviceInfo>> {
    let handle = InstanceHandle::new(false)?;
    let devices = handle.physical_devices()?;
    Ok(devices
        .iter()
        .enumerate()
        .map(|(i, &pd)| handle.describe(i, pd))
        .collect())
}

/// The logical device and its memory allocator, shared (through `Arc`) by the context and every buffer,
/// so the device is destroyed only after the last buffer is freed.
pub(crate) struct Shared {
    pub device: ash::Device,
    pub allocator: ManuallyDrop<Mutex<Allocator>>,
    pub physical_device: vk::PhysicalDevice,
    /// Declared last: dropped after the device.
    pub instance: InstanceHandle,
}

impl Drop for Shared {
    fn drop(&mut self) {
        // SAFETY: no buffer holds the allocator any more (they hold `Arc<Shared>`), so the allocator can
        // release its memory blocks and the device can go; the instance is dropped after this.
        unsafe {
            let _ = self.device.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(index: usize, preference: u32, ok: bool) -> DeviceInfo {
        DeviceInfo {
            index,
            name: format!("dev{index}"),
            driver: String::new(),
            device_type: "other",
            api_version: [1, 3, 0],
            preference,
            unsuitable: if ok { None } else { Some("no".into()) },
        }
    }

    #[test]
    fn automatic_choice_prefers_discrete_then_integrated_then_cpu() {
        let devs = [info(0, 3, true), info(1, 1, true), info(2, 0, false)];
        assert_eq!(choose_device(&devs, None).unwrap(), 1);
        let devs = [info(0, 3, true), info(1, 3, true)];
        assert_eq!(choose_device(&devs, None).unwrap(), 0);
        assert!(matches!(
            choose_device(&[info(0, 0, false)], None),
            Err(VulkanError::NoDevice(_))
        ));
        assert!(matches!(
            choose_device(&[], None),
            Err(VulkanError::NoDevice(_))
        ));
    }

    #[test]
    fn explicit_index_is_checked() {
        let devs = [info(0, 3, true), info(1, 0, false)];
        assert_eq!(choose_device(&devs, Some(0)).unwrap(), 0);
        let e = choose_device(&devs, Some(5)).unwrap_err();
        assert!(matches!(
            e,
            VulkanError::DeviceIndexOutOfRange { index: 5, count: 2 }
        ));
        assert!(e.to_string().contains("out of range"));
        assert!(matches!(
            choose_device(&devs, Some(1)),
            Err(VulkanError::UnsuitableDevice { .. })
        ));
    }
}
