//! Which traversal a device runs: software (the kernel's BVH) or hardware (the driver's acceleration
//! structures through `VK_KHR_ray_query`), from what was asked for and what the device offers. Below the
//! context, which asks it while it chooses a device.
use ash::vk;

use crate::instance::InstanceHandle;

/// How rays find triangles on the device.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Traversal {
    /// Hardware where the device has ray queries and is a GPU, else software (see
    /// [`resolve_traversal`]).
    #[default]
    Auto,
    /// The kernel's own BVH traversal (core's `bvh::traverse`), on any device.
    Software,
    /// The driver's acceleration structures through `VK_KHR_ray_query` (core's `bvh::hardware`); an
    /// error where the device has no ray queries.
    Hardware,
}

/// What a device offers for hardware traversal: `None` if it has everything, else what it lacks.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RayQuerySupport {
    pub missing: Option<String>,
}

/// The traversal a context uses for `requested` on a device of `device_type` ("discrete", "cpu", ...)
/// with `support`, and a note when `Auto` fell back or chose for a reason worth saying.
///
/// `Auto` takes hardware only on GPUs: lavapipe (a CPU device) has ray queries, but its acceleration
/// structures are traversed by the same CPU cores, slower than the kernel's own BVH (docs/architecture.md, "Hardware
/// traversal"), so `Auto` keeps software there.
pub fn resolve_traversal(
    requested: Traversal,
    device_type: &str,
    support: &RayQuerySupport,
) -> std::result::Result<(bool, Option<String>), String> {
    match (requested, &support.missing) {
        (Traversal::Software, _) => Ok((false, None)),
        (Traversal::Hardware, None) => Ok((true, None)),
        (Traversal::Hardware, Some(why)) => Err(format!(
            "--traversal hardware needs ray queries, and this device lacks {why}; use --traversal \
             software or auto"
        )),
        (Traversal::Auto, Some(why)) => Ok((
            false,
            Some(format!("software traversal: the device lacks {why}")),
        )),
        (Traversal::Auto, None) if device_type == "cpu" => Ok((
            false,
            Some(
                "software traversal: this CPU device's ray queries are slower than fovea's own BVH \
                 (--traversal hardware forces them)"
                    .into(),
            ),
        )),
        (Traversal::Auto, None) => Ok((true, None)),
    }
}

/// The device extensions hardware traversal enables.
pub(crate) const DEVICE_EXTENSIONS: [&std::ffi::CStr; 3] = [
    ash::khr::acceleration_structure::NAME,
    ash::khr::ray_query::NAME,
    ash::khr::deferred_host_operations::NAME,
];

/// What `pd` offers for hardware traversal (extensions, then features).
pub(crate) fn ray_query_support(
    instance: &InstanceHandle,
    pd: vk::PhysicalDevice,
) -> RayQuerySupport {
    // SAFETY: `pd` belongs to this instance.
    let extensions =
        unsafe { instance.instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let absent: Vec<String> = DEVICE_EXTENSIONS
        .iter()
        .filter(|name| {
            !extensions
                .iter()
                .any(|e| e.extension_name_as_c_str().ok() == Some(**name))
        })
        .map(|n| n.to_string_lossy().into_owned())
        .collect();
    if !absent.is_empty() {
        return RayQuerySupport {
            missing: Some(absent.join(", ")),
        };
    }
    let mut accel = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut ray_query = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut features = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut accel)
        .push_next(&mut ray_query)
        .push_next(&mut v12);
    // SAFETY: valid chain of feature structs of extensions the device has.
    unsafe {
        instance
            .instance
            .get_physical_device_features2(pd, &mut features)
    };
    let mut lacking = Vec::new();
    if accel.acceleration_structure == vk::FALSE {
        lacking.push("accelerationStructure");
    }
    if ray_query.ray_query == vk::FALSE {
        lacking.push("rayQuery");
    }
    if v12.buffer_device_address == vk::FALSE {
        lacking.push("bufferDeviceAddress");
    }
    RayQuerySupport {
        missing: (!lacking.is_empty()).then(|| lacking.join(", ")),
    }
}

/// `minAccelerationStructureScratchOffsetAlignment`, or 256 where the device has no acceleration
/// structures (then unused).
pub(crate) fn scratch_alignment(instance: &InstanceHandle, pd: vk::PhysicalDevice) -> u32 {
    if ray_query_support(instance, pd).missing.is_some() {
        return 256;
    }
    let mut accel = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
    let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut accel);
    // SAFETY: valid property chain of an extension the device has.
    unsafe {
        instance
            .instance
            .get_physical_device_properties2(pd, &mut props)
    };
    accel
        .min_acceleration_structure_scratch_offset_alignment
        .max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn traversal_is_resolved_from_the_request_the_device_and_its_support() {
        let yes = RayQuerySupport { missing: None };
        let no = RayQuerySupport {
            missing: Some("VK_KHR_ray_query".into()),
        };
        assert_eq!(
            resolve_traversal(Traversal::Auto, "discrete", &yes),
            Ok((true, None))
        );
        let (hw, note) = resolve_traversal(Traversal::Auto, "discrete", &no).unwrap();
        assert!(
            !hw && note.unwrap().contains("VK_KHR_ray_query"),
            "falls back with a note"
        );
        let (hw, note) = resolve_traversal(Traversal::Auto, "cpu", &yes).unwrap();
        assert!(!hw && note.unwrap().contains("--traversal hardware"));
        assert_eq!(
            resolve_traversal(Traversal::Hardware, "cpu", &yes),
            Ok((true, None))
        );
        let e = resolve_traversal(Traversal::Hardware, "discrete", &no).unwrap_err();
        assert!(e.contains("VK_KHR_ray_query") && e.contains("--traversal software"));
        assert_eq!(
            resolve_traversal(Traversal::Software, "discrete", &yes),
            Ok((false, None))
        );
    }
}
