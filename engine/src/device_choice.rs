//! Physical-device choice: discrete > integrated > virtual > CPU, or the
//! device whose name contains a user-given string. Pure, so it is unit-tested.

/// What kind of adapter a physical device is, in order of preference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum DeviceKind {
    /// A separate GPU.
    Discrete,
    /// A GPU sharing memory with the CPU.
    Integrated,
    /// A GPU behind a hypervisor.
    Virtual,
    /// A software rasteriser such as lavapipe.
    Cpu,
    /// Anything else.
    Other,
}

/// A physical device as the chooser sees it.
#[derive(Debug, Clone)]
pub struct DeviceCandidate {
    /// The driver-reported device name.
    pub name: String,
    /// Its kind.
    pub kind: DeviceKind,
    /// Why it cannot be used, if it cannot (no Vulkan 1.3, no features…).
    pub unusable: Option<String>,
}

/// Picks a device: the first usable one whose name contains `wanted`
/// (case-insensitive) when given, else the usable one of the best kind.
/// The error lists every device and why it was passed over.
pub fn choose_device(
    candidates: &[DeviceCandidate],
    wanted: Option<&str>,
) -> Result<usize, String> {
    let listing = || {
        candidates
            .iter()
            .map(|c| match &c.unusable {
                None => format!("  {} ({:?})", c.name, c.kind),
                Some(why) => format!("  {} ({:?}, unusable: {why})", c.name, c.kind),
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    if candidates.is_empty() {
        return Err("no Vulkan physical device found; on Debian/Ubuntu install Mesa's lavapipe with `apt-get install mesa-vulkan-drivers`".into());
    }
    if let Some(wanted) = wanted.filter(|w| !w.is_empty()) {
        let needle = wanted.to_lowercase();
        return candidates
            .iter()
            .position(|c| c.unusable.is_none() && c.name.to_lowercase().contains(&needle))
            .ok_or_else(|| {
                format!("no usable Vulkan device matches `{wanted}` (from --device or INLAY_DEVICE); devices:\n{}", listing())
            });
    }
    candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.unusable.is_none())
        .min_by_key(|(i, c)| (c.kind, *i))
        .map(|(i, _)| i)
        .ok_or_else(|| format!("no usable Vulkan device; devices:\n{}", listing()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dev(name: &str, kind: DeviceKind) -> DeviceCandidate {
        DeviceCandidate {
            name: name.into(),
            kind,
            unusable: None,
        }
    }

    #[test]
    fn prefers_discrete_then_integrated_then_cpu() {
        let list = [
            dev("llvmpipe", DeviceKind::Cpu),
            dev("Intel UHD", DeviceKind::Integrated),
            dev("RTX", DeviceKind::Discrete),
        ];
        assert_eq!(choose_device(&list, None), Ok(2));
        assert_eq!(choose_device(&list[..2], None), Ok(1));
        assert_eq!(choose_device(&list[..1], None), Ok(0));
    }

    #[test]
    fn name_override_is_case_insensitive_and_skips_unusable() {
        let mut list = vec![
            dev("NVIDIA H100", DeviceKind::Discrete),
            dev("llvmpipe (LLVM 15)", DeviceKind::Cpu),
        ];
        assert_eq!(choose_device(&list, Some("LLVMPIPE")), Ok(1));
        list[1].unusable = Some("no Vulkan 1.3".into());
        let err = choose_device(&list, Some("llvmpipe")).unwrap_err();
        assert!(
            err.contains("no usable Vulkan device matches `llvmpipe`")
                && err.contains("no Vulkan 1.3"),
            "{err}"
        );
    }

    #[test]
    fn unusable_devices_are_never_chosen() {
        let mut list = vec![
            dev("RTX", DeviceKind::Discrete),
            dev("llvmpipe", DeviceKind::Cpu),
        ];
        list[0].unusable = Some("no dynamic rendering".into());
        assert_eq!(choose_device(&list, None), Ok(1));
        list[1].unusable = Some("x".into());
        assert!(choose_device(&list, None).is_err());
        assert!(choose_device(&[], None).unwrap_err().contains("lavapipe"));
    }
}
