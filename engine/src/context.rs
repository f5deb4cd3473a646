//! The Vulkan context: loader loaded at run time, instance, validation,
//! physical-device choice, logical device with Vulkan 1.3 dynamic rendering and
//! synchronization2, one graphics+compute queue, and the memory allocator.

use std::ffi::{c_char, CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use winit::raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use crate::device_choice::{choose_device, DeviceCandidate, DeviceKind};
use crate::error::{EngineError, Result, VkContext};
use crate::validation::{debug_callback, ValidationLog};

/// The environment variable that picks a device by name, like `--device`.
pub const DEVICE_ENV: &str = "INLAY_DEVICE";
const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create a [`Context`].
#[derive(Debug, Clone, Default)]
pub struct ContextOptions {
    /// Turn on the Khronos validation layer (with synchronization validation);
    /// creation fails if the layer is not installed.
    pub validate: bool,
    /// Pick the device whose name contains this (case-insensitive); when
    /// `None`, the `INLAY_DEVICE` environment variable is consulted.
    pub device: Option<String>,
}

/// GPU memory held through the engine's allocator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryUsage {
    /// Live allocations.
    pub allocations: usize,
    /// Bytes they use.
    pub allocated_bytes: u64,
    /// Bytes of the memory blocks holding them.
    pub block_bytes: u64,
}

/// Native handles of a window to present to (from winit's raw-window-handle).
#[derive(Debug, Clone, Copy)]
pub struct WindowHandles {
    /// The display connection.
    pub display: RawDisplayHandle,
    /// The window.
    pub window: RawWindowHandle,
}

/// Facts about the chosen device that passes and tools report or depend on.
#[derive(Debug, Clone)]
pub struct DeviceInfo {
    /// Driver-reported device name.
    pub name: String,
    /// Its kind.
    pub kind: DeviceKind,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period_ns: f64,
    /// Largest push-constant block in bytes.
    pub max_push_constants: u32,
    /// Largest storage-buffer binding in bytes.
    pub max_storage_buffer_range: u32,
    /// Largest width or height of a 2D image (render targets, textures).
    pub max_image_dimension_2d: u32,
    /// Size of the largest device-local memory heap in bytes.
    pub device_heap_bytes: u64,
    /// Whether shaders may add 32-bit floats atomically in storage buffers
    /// (VK_EXT_shader_atomic_float's shaderBufferFloat32AtomicAdd, enabled
    /// when the device has it).
    pub float_atomic_add: bool,
    /// The most loop iterations one shader invocation runs, all its loops
    /// together, on devices that stop it there: Mesa's llvmpipe (lavapipe)
    /// ends every loop of an invocation once [`LLVMPIPE_LOOP_LIMIT`]
    /// iterations have run and carries on after them, so a kernel that
    /// loops longer returns a wrong result with no error. None where no
    /// such limit is known.
    pub loop_iteration_limit: Option<u64>,
}

/// llvmpipe's limit on the loop iterations of one invocation
/// (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS, counted over all of an
/// invocation's loops; measured in this project on the SSDF bake, the
/// near-field trace, the march and the probe trace).
pub const LLVMPIPE_LOOP_LIMIT: u64 = 65535;

/// A surface and its loader, present when the context was made for a window.
pub(crate) struct SurfaceParts {
    pub(crate) loader: ash::khr::surface::Instance,
    pub(crate) surface: vk::SurfaceKHR,
    pub(crate) swapchain: ash::khr::swapchain::Device,
}

/// The Vulkan instance, device, queue and allocator shared by everything the
/// engine creates. Held in an `Arc`; resources keep it alive until they drop.
pub struct Context {
    pub(crate) device: ash::Device,
    pub(crate) queue: vk::Queue,
    /// Held around every use of `queue` (Vulkan requires queue access to be
    /// externally synchronised: frames, presents and uploads may come from
    /// different threads).
    pub(crate) queue_lock: Mutex<()>,
    pub(crate) queue_family: u32,
    pub(crate) physical: vk::PhysicalDevice,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    pub(crate) surface: Option<SurfaceParts>,
    info: DeviceInfo,
    validation: Box<ValidationLog>,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub(crate) instance: ash::Instance,
    _entry: ash::Entry,
}

impl Context {
    /// Loads the Vulkan loader, creates the instance (with validation when
    /// asked), picks a device and creates it. With `window`, also creates a
    /// surface and requires a queue that can present to it.
    pub fn new(options: &ContextOptions, window: Option<WindowHandles>) -> Result<Arc<Self>> {
        // SAFETY: loading the system's libvulkan; its symbols are only used
        // through ash's typed function tables.
        let entry =
            unsafe { ash::Entry::load() }.map_err(|e| EngineError::Loader(e.to_string()))?;
        let validation = Box::new(ValidationLog::default());
        let instance = create_instance(&entry, options.validate, window)?;
        let debug = if options.validate {
            match create_messenger(&entry, &instance, &validation) {
                Ok(d) => Some(d),
                Err(e) => {
                    unsafe { instance.destroy_instance(None) };
                    return Err(e);
                }
            }
        } else {
            None
        };
        let surface = match window {
            Some(w) => {
                let loader = ash::khr::surface::Instance::new(&entry, &instance);
                // SAFETY: the handles come from a live winit window that the
                // caller keeps alive for the lifetime of the context.
                let surface = unsafe {
                    ash_window::create_surface(&entry, &instance, w.display, w.window, None)
                }
                .vk("vkCreateSurfaceKHR")?;
                Some((loader, surface))
            }
            None => None,
        };
        let wanted = options
            .device
            .clone()
            .or_else(|| std::env::var(DEVICE_ENV).ok());
        let (physical, queue_family, info) =
            pick_physical(&instance, surface.as_ref(), wanted.as_deref())?;
        let device = create_device(
            &instance,
            physical,
            queue_family,
            surface.is_some(),
            info.float_atomic_add,
        )?;
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|e| EngineError::Allocation {
            what: "the allocator".into(),
            message: e.to_string(),
        })?;
        let surface = surface.map(|(loader, surface)| SurfaceParts {
            swapchain: ash::khr::swapchain::Device::new(&instance, &device),
            loader,
            surface,
        });
        log::info!("Vulkan device: {} ({:?})", info.name, info.kind);
        Ok(Arc::new(Self {
            device,
            queue,
            queue_lock: Mutex::new(()),
            queue_family,
            physical,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            surface,
            info,
            validation,
            debug,
            instance,
            _entry: entry,
        }))
    }

    /// The chosen device's name, kind and limits.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// Whether the validation layer is on.
    pub fn validating(&self) -> bool {
        self.debug.is_some()
    }

    /// What the engine holds in GPU memory now: live allocations, their
    /// bytes, and the bytes of the memory blocks they live in (for soak
    /// tests: all three stay flat frame after frame).
    pub fn memory_usage(&self) -> MemoryUsage {
        let report = self.allocator().generate_report();
        MemoryUsage {
            allocations: report.allocations.len(),
            allocated_bytes: report.total_allocated_bytes,
            block_bytes: report.total_capacity_bytes,
        }
    }

    /// The messages the validation layer reported so far.
    pub fn validation_log(&self) -> &ValidationLog {
        &self.validation
    }

    /// Fails with the first validation error if any was reported since the
    /// last call, and forgets them.
    pub fn check_validation(&self) -> Result<()> {
        let errors = self.validation.take_errors();
        match errors.first() {
            None => Ok(()),
            Some(first) => Err(EngineError::Validation {
                count: errors.len(),
                first: first.clone(),
            }),
        }
    }

    /// Waits until the device has finished all submitted work. For shutdown,
    /// resizing and tests, never per frame.
    pub fn wait_idle(&self) -> Result<()> {
        // vkDeviceWaitIdle needs every queue externally synchronised.
        let _queue = self.lock_queue();
        unsafe { self.device.device_wait_idle() }.vk("vkDeviceWaitIdle")
    }

    /// Exclusive use of the queue for a submit or present.
    pub(crate) fn lock_queue(&self) -> MutexGuard<'_, ()> {
        self.queue_lock.lock().unwrap_or_else(|p| p.into_inner())
    }

    pub(crate) fn allocator(&self) -> MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Makes the validation layer report one genuine error (a buffer created
    /// with size 0, which the Vulkan spec forbids), so tests can check that
    /// errors are caught and fail the run. The buffer is destroyed at once.
    pub fn provoke_validation_error(&self) {
        let info = vk::BufferCreateInfo::default()
            .size(0)
            .usage(vk::BufferUsageFlags::STORAGE_BUFFER);
        // SAFETY: lavapipe and real drivers accept the call; only the layer
        // objects. The handle, if any, is destroyed right away.
        unsafe {
            if let Ok(b) = self.device.create_buffer(&info, None) {
                self.device.destroy_buffer(b, None);
            }
        }
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some(s) = self.surface.take() {
                s.loader.destroy_surface(s.surface, None);
            }
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

fn create_instance(
    entry: &ash::Entry,
    validate: bool,
    window: Option<WindowHandles>,
) -> Result<ash::Instance> {
    let version = unsafe { entry.try_enumerate_instance_version() }
        .vk("vkEnumerateInstanceVersion")?
        .unwrap_or(vk::API_VERSION_1_0);
    if version < vk::API_VERSION_1_3 {
        return Err(EngineError::Missing(format!(
            "the Vulkan loader supports only {}.{}; Vulkan 1.3 is required",
            vk::api_version_major(version),
            vk::api_version_minor(version)
        )));
    }
    let app_name = CString::new("inlay").unwrap_or_default();
    let app = vk::ApplicationInfo::default()
        .application_name(&app_name)
        .engine_name(&app_name)
        .api_version(vk::API_VERSION_1_3);
    let mut layers: Vec<*const c_char> = Vec::new();
    let mut extensions: Vec<*const c_char> = Vec::new();
    if validate {
        let available = unsafe { entry.enumerate_instance_layer_properties() }
            .vk("vkEnumerateInstanceLayerProperties")?;
        let found = available
            .iter()
            .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
        if !found {
            return Err(EngineError::Missing(
                "validation was requested but VK_LAYER_KHRONOS_validation is not installed; on Debian/Ubuntu: `apt-get install vulkan-validationlayers`".into(),
            ));
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        // Needed for VkValidationFeaturesEXT (synchronization validation) to take effect.
        extensions.push(ash::ext::validation_features::NAME.as_ptr());
    }
    if let Some(w) = window {
        let required = ash_window::enumerate_required_extensions(w.display)
            .vk("vkEnumerateInstanceExtensionProperties (surface)")?;
        extensions.extend_from_slice(required);
    }
    let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    if validate {
        info = info.push_next(&mut features);
    }
    unsafe { entry.create_instance(&info, None) }.vk("vkCreateInstance")
}

fn create_messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
    log: &ValidationLog,
) -> Result<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)> {
    let loader = ash::ext::debug_utils::Instance::new(entry, instance);
    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::INFO,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(log as *const ValidationLog as *mut std::ffi::c_void);
    // SAFETY: `log` lives in a Box owned by the Context, which destroys the
    // messenger before dropping the box.
    let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }
        .vk("vkCreateDebugUtilsMessengerEXT")?;
    Ok((loader, messenger))
}

fn pick_physical(
    instance: &ash::Instance,
    surface: Option<&(ash::khr::surface::Instance, vk::SurfaceKHR)>,
    wanted: Option<&str>,
) -> Result<(vk::PhysicalDevice, u32, DeviceInfo)> {
    let physicals =
        unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    let mut candidates = Vec::new();
    let mut details = Vec::new();
    for &pd in &physicals {
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let name = props
            .device_name_as_c_str()
            .map(|c| c.to_string_lossy().into_owned())
            .unwrap_or_default();
        let kind = match props.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => DeviceKind::Discrete,
            vk::PhysicalDeviceType::INTEGRATED_GPU => DeviceKind::Integrated,
            vk::PhysicalDeviceType::VIRTUAL_GPU => DeviceKind::Virtual,
            vk::PhysicalDeviceType::CPU => DeviceKind::Cpu,
            _ => DeviceKind::Other,
        };
        let (family, unusable) = check_physical(instance, pd, &props, surface);
        candidates.push(DeviceCandidate {
            name: name.clone(),
            kind,
            unusable,
        });
        details.push((pd, family, props, name, kind));
    }
    let index = choose_device(&candidates, wanted).map_err(EngineError::NoDevice)?;
    let (pd, family, props, name, kind) = details.swap_remove(index);
    let info = DeviceInfo {
        loop_iteration_limit: loop_iteration_limit(&name, kind),
        name,
        kind,
        timestamp_period_ns: props.limits.timestamp_period as f64,
        max_push_constants: props.limits.max_push_constants_size,
        max_storage_buffer_range: props.limits.max_storage_buffer_range,
        max_image_dimension_2d: props.limits.max_image_dimension2_d,
        device_heap_bytes: largest_device_heap(instance, pd),
        float_atomic_add: has_float_atomic_add(instance, pd),
    };
    Ok((pd, family.unwrap_or(0), info))
}

/// The loop limit of a device named `name` ([`DeviceInfo::loop_iteration_limit`]):
/// llvmpipe's (Mesa names its CPU device "llvmpipe (LLVM …)").
fn loop_iteration_limit(name: &str, kind: DeviceKind) -> Option<u64> {
    (kind == DeviceKind::Cpu && name.starts_with("llvmpipe")).then_some(LLVMPIPE_LOOP_LIMIT)
}

/// Whether `pd` has VK_EXT_shader_atomic_float with
/// shaderBufferFloat32AtomicAdd.
fn has_float_atomic_add(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    // SAFETY: `pd` was enumerated from `instance`, which is alive.
    let extensions =
        unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let listed = extensions.iter().any(|e| {
        e.extension_name_as_c_str()
            .is_ok_and(|n| n == ash::ext::shader_atomic_float::NAME)
    });
    if !listed {
        return false;
    }
    let mut atomic = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut atomic);
    // SAFETY: as above; the chain lives until the call returns.
    unsafe { instance.get_physical_device_features2(pd, &mut features) };
    atomic.shader_buffer_float32_atomic_add == vk::TRUE
}

/// The size of the largest device-local heap (on a CPU device, its only
/// heap).
fn largest_device_heap(instance: &ash::Instance, pd: vk::PhysicalDevice) -> u64 {
    // SAFETY: `pd` was enumerated from `instance`, which is alive.
    let memory = unsafe { instance.get_physical_device_memory_properties(pd) };
    let heaps = &memory.memory_heaps[..memory.memory_heap_count as usize];
    heaps
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .or_else(|| heaps.iter().map(|h| h.size).max())
        .unwrap_or(0)
}

/// Returns the queue family to use and, if the device is unusable, why.
fn check_physical(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    props: &vk::PhysicalDeviceProperties,
    surface: Option<&(ash::khr::surface::Instance, vk::SurfaceKHR)>,
) -> (Option<u32>, Option<String>) {
    if props.api_version < vk::API_VERSION_1_3 {
        return (None, Some("no Vulkan 1.3".into()));
    }
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
    unsafe { instance.get_physical_device_features2(pd, &mut features) };
    if f13.dynamic_rendering == vk::FALSE || f13.synchronization2 == vk::FALSE {
        return (
            None,
            Some("no dynamic rendering or synchronization2".into()),
        );
    }
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let wanted = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    let family = families.iter().enumerate().position(|(i, f)| {
        let presents = surface.is_none_or(|(loader, s)| unsafe {
            loader
                .get_physical_device_surface_support(pd, i as u32, *s)
                .unwrap_or(false)
        });
        f.queue_flags.contains(wanted) && f.timestamp_valid_bits > 0 && presents
    });
    match family {
        Some(i) => (Some(i as u32), None),
        None => (
            None,
            Some(
                "no graphics+compute queue with timestamps (and presentation, for a window)".into(),
            ),
        ),
    }
}

fn create_device(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    family: u32,
    swapchain: bool,
    float_atomic_add: bool,
) -> Result<ash::Device> {
    let priorities = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&priorities)];
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(true)
        .synchronization2(true);
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default().host_query_reset(true);
    let mut extensions: Vec<*const c_char> = if swapchain {
        vec![ash::khr::swapchain::NAME.as_ptr()]
    } else {
        vec![]
    };
    let mut atomic = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
        .shader_buffer_float32_atomic_add(true);
    let mut info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .push_next(&mut f13)
        .push_next(&mut f12);
    if float_atomic_add {
        extensions.push(ash::ext::shader_atomic_float::NAME.as_ptr());
        info = info.push_next(&mut atomic);
    }
    let info = info.enabled_extension_names(&extensions);
    unsafe { instance.create_device(pd, &info, None) }.vk("vkCreateDevice")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_llvmpipe_has_a_loop_limit() {
        let limit = |name, kind| loop_iteration_limit(name, kind);
        assert_eq!(
            limit("llvmpipe (LLVM 15.0.6, 256 bits)", DeviceKind::Cpu),
            Some(LLVMPIPE_LOOP_LIMIT)
        );
        assert_eq!(limit("NVIDIA H200", DeviceKind::Discrete), None);
        assert_eq!(limit("SwiftShader Device", DeviceKind::Cpu), None);
    }
}
