//! Host mirrors of WGSL structs, checked against the shader: a type made
//! with [`gpu_struct!`](crate::gpu_struct) is `#[repr(C)]` and
//! `bytemuck::Pod` (its bytes go to the GPU as they are: push constants,
//! uniform blocks, storage records) and names the WGSL file and struct it
//! mirrors; [`check_layout`] compares its size and every member's offset
//! with what naga lays out for that struct, so a member added, moved or
//! retyped on one side only is caught by a test instead of read as
//! garbage by the GPU.

use super::{compose, Define, ShaderError, ShaderLibrary};

/// A struct's memory layout: its size and each member's offset, in bytes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StructLayout {
    /// The struct's name.
    pub name: String,
    /// Its size (WGSL: rounded up to its alignment).
    pub size: u32,
    /// Each member's name and offset, in declaration order.
    pub members: Vec<(String, u32)>,
}

/// A host type that mirrors a WGSL struct, byte for byte.
pub trait GpuStruct: bytemuck::Pod {
    /// The WGSL file, relative to the shader library's root, that declares
    /// the struct (directly or through an `#include`).
    const WGSL_FILE: &'static str;
    /// The struct's name in WGSL.
    const WGSL_STRUCT: &'static str;
    /// The host layout: `size_of`, and `offset_of` for each field (fields
    /// whose names start with `_` are padding the WGSL side leaves
    /// implicit).
    fn layout() -> StructLayout;
}

/// Declares a `#[repr(C)]`, `Pod` struct that mirrors the WGSL struct
/// `$wgsl` of shader file `$file`, and implements
/// [`GpuStruct`](crate::shader::GpuStruct) for it. Field names must match
/// the WGSL members'; padding fields start with `_`. The crate using it
/// depends on `bytemuck` (with `derive`).
///
/// ```ignore
/// inlay_engine::gpu_struct! {
///     /// The edge pass's push constants.
///     pub struct EdgeAaPush = "edge_aa/edge_aa.wgsl" : "EdgeAaPush" {
///         pub width: u32,
///         pub height: u32,
///         pub subpixel: f32,
///     }
/// }
/// ```
#[macro_export]
macro_rules! gpu_struct {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident = $file:literal : $wgsl:literal {
            $( $(#[$fmeta:meta])* $fvis:vis $field:ident : $ty:ty ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        $vis struct $name {
            $( $(#[$fmeta])* $fvis $field : $ty ),*
        }

        impl $crate::shader::GpuStruct for $name {
            const WGSL_FILE: &'static str = $file;
            const WGSL_STRUCT: &'static str = $wgsl;
            fn layout() -> $crate::shader::StructLayout {
                $crate::shader::StructLayout {
                    name: stringify!($name).into(),
                    size: ::core::mem::size_of::<Self>() as u32,
                    members: vec![
                        $( (stringify!($field).into(), ::core::mem::offset_of!($name, $field) as u32) ),*
                    ],
                }
            }
        }
    };
}

/// Every named struct of `file` (composed with `defines`) as naga lays it
/// out.
pub fn struct_layouts(
    library: &ShaderLibrary,
    file: &str,
    defines: &[Define],
) -> Result<Vec<StructLayout>, ShaderError> {
    let composed = compose(library, file, defines)?;
    let module = naga::front::wgsl::parse_str(&composed.source).map_err(|e| ShaderError {
        file: file.into(),
        line: 0,
        column: 0,
        message: e.message().to_owned(),
    })?;
    Ok(module
        .types
        .iter()
        .filter_map(|(_, t)| match (&t.name, &t.inner) {
            (Some(name), naga::TypeInner::Struct { members, span }) => Some(StructLayout {
                name: name.clone(),
                size: *span,
                members: members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                    .collect(),
            }),
            _ => None,
        })
        .collect())
}

/// Compares `host` with the layout of struct `name` in `file`: the same
/// size, every WGSL member present on the host at the same offset, and no
/// host member (other than `_` padding) missing from WGSL. The error says
/// what differs.
pub fn compare_layout(
    library: &ShaderLibrary,
    file: &str,
    name: &str,
    defines: &[Define],
    host: &StructLayout,
) -> Result<(), String> {
    let layouts = struct_layouts(library, file, defines).map_err(|e| e.to_string())?;
    let wgsl = layouts
        .iter()
        .find(|l| l.name == name)
        .ok_or_else(|| format!("{file} declares no struct `{name}`"))?;
    let mut problems = Vec::new();
    if wgsl.size != host.size {
        problems.push(format!(
            "size: WGSL {} bytes, host {}",
            wgsl.size, host.size
        ));
    }
    for (member, offset) in &wgsl.members {
        match host.members.iter().find(|(n, _)| n == member) {
            None => problems.push(format!(
                "`{member}` (WGSL offset {offset}) is missing on the host"
            )),
            Some((_, o)) if o != offset => {
                problems.push(format!("`{member}`: WGSL offset {offset}, host {o}"))
            }
            Some(_) => {}
        }
    }
    for (member, _) in &host.members {
        if !member.starts_with('_') && !wgsl.members.iter().any(|(n, _)| n == member) {
            problems.push(format!("host member `{member}` is not in the WGSL struct"));
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} against {file} `{name}`: {}",
            host.name,
            problems.join("; ")
        ))
    }
}

/// [`compare_layout`] for a [`GpuStruct`].
pub fn check_layout<T: GpuStruct>(
    library: &ShaderLibrary,
    defines: &[Define],
) -> Result<(), String> {
    compare_layout(library, T::WGSL_FILE, T::WGSL_STRUCT, defines, &T::layout())
}

#[cfg(test)]
mod tests {
    use super::*;

    const SOURCE: &str = "struct P {\n  origin: vec3<f32>,\n  step: f32,\n  count: u32,\n}\n";

    fn lib() -> ShaderLibrary {
        ShaderLibrary::from_pairs([("p.wgsl", SOURCE)])
    }

    fn host(members: &[(&str, u32)], size: u32) -> StructLayout {
        StructLayout {
            name: "Host".into(),
            size,
            members: members.iter().map(|(n, o)| (n.to_string(), *o)).collect(),
        }
    }

    #[test]
    fn naga_lays_out_wgsl_structs() {
        let l = struct_layouts(&lib(), "p.wgsl", &[]).unwrap();
        assert_eq!(l.len(), 1);
        assert_eq!(l[0].size, 32, "vec3 aligns the struct to 16");
        assert_eq!(
            l[0].members,
            vec![
                ("origin".into(), 0),
                ("step".into(), 12),
                ("count".into(), 16)
            ]
        );
    }

    #[test]
    fn a_matching_host_passes_and_each_difference_is_named() {
        let good = host(
            &[("origin", 0), ("step", 12), ("count", 16), ("_pad", 20)],
            32,
        );
        assert_eq!(compare_layout(&lib(), "p.wgsl", "P", &[], &good), Ok(()));
        let short = host(&[("origin", 0), ("step", 12), ("count", 16)], 20);
        let e = compare_layout(&lib(), "p.wgsl", "P", &[], &short).unwrap_err();
        assert!(e.contains("size: WGSL 32 bytes, host 20"), "{e}");
        let moved = host(
            &[("origin", 0), ("count", 12), ("step", 16), ("_p", 20)],
            32,
        );
        let e = compare_layout(&lib(), "p.wgsl", "P", &[], &moved).unwrap_err();
        assert!(e.contains("`step`: WGSL offset 12, host 16"), "{e}");
        let extra = host(
            &[("origin", 0), ("step", 12), ("count", 16), ("more", 20)],
            32,
        );
        let e = compare_layout(&lib(), "p.wgsl", "P", &[], &extra).unwrap_err();
        assert!(e.contains("`more` is not in the WGSL struct"), "{e}");
        assert!(compare_layout(&lib(), "p.wgsl", "Q", &[], &good).is_err());
    }

    crate::gpu_struct! {
        /// The macro's own output, against the same struct.
        struct Mirrored = "p.wgsl" : "P" {
            origin: [f32; 3],
            step: f32,
            count: u32,
            _pad: [u32; 3],
        }
    }

    #[test]
    fn the_macro_reports_rust_offsets() {
        assert_eq!(check_layout::<Mirrored>(&lib(), &[]), Ok(()));
        let m = Mirrored::layout();
        assert_eq!(m.size, 32);
        assert_eq!(m.members[2], ("count".into(), 16));
        let bytes = bytemuck::bytes_of(&Mirrored {
            origin: [1.0, 2.0, 3.0],
            step: 0.5,
            count: 7,
            _pad: [0; 3],
        });
        assert_eq!(&bytes[16..20], &7u32.to_le_bytes());
    }
}
