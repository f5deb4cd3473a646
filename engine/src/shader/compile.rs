//! naga: composed WGSL → validated module → SPIR-V for one entry point, plus
//! the descriptor bindings and push-constant size that entry point uses.

use naga::valid::{Capabilities, ValidationFlags, Validator};

use super::{compose, Composed, Define, ShaderError, ShaderLibrary};

/// Which pipeline stage an entry point runs in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ShaderStage {
    /// Vertex shader.
    Vertex,
    /// Fragment shader.
    Fragment,
    /// Compute shader.
    Compute,
}

impl ShaderStage {
    fn naga(self) -> naga::ShaderStage {
        match self {
            ShaderStage::Vertex => naga::ShaderStage::Vertex,
            ShaderStage::Fragment => naga::ShaderStage::Fragment,
            ShaderStage::Compute => naga::ShaderStage::Compute,
        }
    }
}

/// The kind of descriptor a shader binding needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DescriptorKind {
    /// `var<uniform>`.
    UniformBuffer,
    /// `var<storage, read>` or `var<storage, read_write>`.
    StorageBuffer,
    /// `texture_2d<f32>` and friends.
    SampledImage,
    /// `texture_storage_2d<…>`.
    StorageImage,
    /// `sampler`.
    Sampler,
}

/// One descriptor binding an entry point uses.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct ReflectedBinding {
    /// `@group`.
    pub set: u32,
    /// `@binding`.
    pub binding: u32,
    /// Descriptor type.
    pub kind: DescriptorKind,
    /// The WGSL variable name, for error messages.
    pub name: String,
}

/// SPIR-V for one entry point and what it binds.
#[derive(Debug, Clone)]
pub struct CompiledShader {
    /// The source file it was compiled from.
    pub file: String,
    /// The entry point's name.
    pub entry: String,
    /// Its stage.
    pub stage: ShaderStage,
    /// SPIR-V words.
    pub spirv: Vec<u32>,
    /// Descriptor bindings the entry point uses, sorted by (set, binding).
    pub bindings: Vec<ReflectedBinding>,
    /// Size of its `var<immediate>` (push-constant) block in bytes, 0 if none.
    pub push_constant_size: u32,
    /// Compute workgroup size (zeros for other stages).
    pub workgroup_size: [u32; 3],
}

/// Composes `file`, parses and validates it with naga, and writes SPIR-V for
/// `entry`. Errors point at the original file and line.
pub fn compile(
    library: &ShaderLibrary,
    file: &str,
    entry: &str,
    stage: ShaderStage,
    defines: &[Define],
) -> Result<CompiledShader, ShaderError> {
    let composed = compose(library, file, defines)?;
    let module = naga::front::wgsl::parse_str(&composed.source).map_err(|e| {
        let loc = e.location(&composed.source);
        located(&composed, loc, e.message().to_owned())
    })?;
    // `SHADER_FLOAT16_IN_FLOAT32` allows `unpack2x16float` (f16 storage
    // read into f32): SPIR-V's GLSL.std.450 UnpackHalf2x16, core Vulkan,
    // no device feature needed.
    let mut validator = Validator::new(
        ValidationFlags::all(),
        Capabilities::IMMEDIATES
            | Capabilities::SHADER_FLOAT32_ATOMIC
            | Capabilities::SHADER_FLOAT16_IN_FLOAT32,
    );
    let info = validator.validate(&module).map_err(|e| {
        let loc = e.location(&composed.source);
        located(&composed, loc, error_chain(e.as_inner()))
    })?;
    let index = module
        .entry_points
        .iter()
        .position(|ep| ep.name == entry && ep.stage == stage.naga())
        .ok_or_else(|| ShaderError {
            file: file.into(),
            line: 0,
            column: 0,
            message: format!("no {stage:?} entry point named `{entry}`"),
        })?;
    let ep = &module.entry_points[index];
    let options = naga::back::spv::Options {
        lang_version: (1, 3),
        use_storage_input_output_16: false,
        ..Default::default()
    };
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: stage.naga(),
        entry_point: entry.into(),
    };
    let spirv =
        naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline)).map_err(|e| {
            ShaderError {
                file: file.into(),
                line: 0,
                column: 0,
                message: format!("SPIR-V generation failed: {e}"),
            }
        })?;
    let uses = info.get_entry_point(index);
    let mut bindings = Vec::new();
    let mut push_constant_size = 0;
    for (handle, var) in module.global_variables.iter() {
        if uses[handle].is_empty() {
            continue;
        }
        if var.space == naga::AddressSpace::Immediate {
            push_constant_size = module.types[var.ty].inner.size(module.to_ctx());
            continue;
        }
        let Some(rb) = &var.binding else { continue };
        let kind = match (&var.space, &module.types[var.ty].inner) {
            (naga::AddressSpace::Uniform, _) => DescriptorKind::UniformBuffer,
            (naga::AddressSpace::Storage { .. }, _) => DescriptorKind::StorageBuffer,
            (naga::AddressSpace::Handle, naga::TypeInner::Sampler { .. }) => {
                DescriptorKind::Sampler
            }
            (
                naga::AddressSpace::Handle,
                naga::TypeInner::Image {
                    class: naga::ImageClass::Storage { .. },
                    ..
                },
            ) => DescriptorKind::StorageImage,
            (naga::AddressSpace::Handle, naga::TypeInner::Image { .. }) => {
                DescriptorKind::SampledImage
            }
            _ => {
                return Err(ShaderError {
                    file: file.into(),
                    line: 0,
                    column: 0,
                    message: format!(
                        "binding `{}` has a type the engine cannot bind",
                        var.name.as_deref().unwrap_or("?")
                    ),
                })
            }
        };
        bindings.push(ReflectedBinding {
            set: rb.group,
            binding: rb.binding,
            kind,
            name: var.name.clone().unwrap_or_default(),
        });
    }
    bindings.sort_by_key(|b| (b.set, b.binding));
    Ok(CompiledShader {
        file: file.into(),
        entry: entry.into(),
        stage,
        spirv,
        bindings,
        push_constant_size,
        workgroup_size: ep.workgroup_size,
    })
}

fn located(composed: &Composed, loc: Option<naga::SourceLocation>, message: String) -> ShaderError {
    match loc {
        Some(l) => {
            let (file, line) = composed.origin(l.line_number);
            ShaderError {
                file,
                line,
                column: l.line_position,
                message,
            }
        }
        None => ShaderError {
            file: composed.origin(1).0,
            line: 0,
            column: 0,
            message,
        },
    }
}

fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lib(files: &[(&str, &str)]) -> ShaderLibrary {
        ShaderLibrary::from_pairs(files.iter().copied())
    }

    const SHARED: &str = "fn twice(x: f32) -> f32 {\n  return 2.0 * x;\n}\n";

    #[test]
    fn compiles_and_reflects_bindings_and_push_constants() {
        let l = lib(&[
            ("common/m.wgsl", SHARED),
            (
                "k.wgsl",
                "#include \"common/m.wgsl\"\nstruct P { n: u32, s: f32 }\nvar<immediate> pc: P;\n@group(0) @binding(1) var<storage, read_write> out: array<f32>;\n@group(0) @binding(0) var img: texture_storage_2d<rgba16float, write>;\n@group(0) @binding(2) var unused: texture_2d<f32>;\n@compute @workgroup_size(8, 8, 1)\nfn main(@builtin(global_invocation_id) id: vec3<u32>) {\n  out[id.x] = twice(pc.s) * f32(N);\n  textureStore(img, vec2<i32>(id.xy), vec4<f32>(1.0));\n}\n",
            ),
        ]);
        let s = compile(
            &l,
            "k.wgsl",
            "main",
            ShaderStage::Compute,
            &[Define::U32("N", 3)],
        )
        .unwrap();
        assert_eq!(s.spirv[0], 0x0723_0203, "SPIR-V magic");
        assert_eq!(s.push_constant_size, 8);
        assert_eq!(s.workgroup_size, [8, 8, 1]);
        let kinds: Vec<_> = s.bindings.iter().map(|b| (b.binding, b.kind)).collect();
        assert_eq!(
            kinds,
            vec![
                (0, DescriptorKind::StorageImage),
                (1, DescriptorKind::StorageBuffer)
            ],
            "the unused texture is not reflected"
        );
    }

    #[test]
    fn parse_error_in_an_included_file_names_that_file_and_line() {
        let l = lib(&[
            (
                "common/bad.wgsl",
                "fn ok() {}\nfn broken( -> f32 { return 1.0; }\n",
            ),
            (
                "top.wgsl",
                "#include \"common/bad.wgsl\"\n@compute @workgroup_size(1)\nfn main() {}\n",
            ),
        ]);
        let e = compile(&l, "top.wgsl", "main", ShaderStage::Compute, &[]).unwrap_err();
        assert_eq!((e.file.as_str(), e.line), ("common/bad.wgsl", 2), "{e}");
        assert!(e.to_string().starts_with("common/bad.wgsl:2:"), "{e}");
    }

    #[test]
    fn validation_error_names_file_and_line() {
        let l = lib(&[(
            "v.wgsl",
            "@compute @workgroup_size(1)\nfn main() {\n  let a: f32 = 1.0;\n  let b: u32 = a;\n}\n",
        )]);
        let e = compile(&l, "v.wgsl", "main", ShaderStage::Compute, &[]).unwrap_err();
        assert_eq!(e.file, "v.wgsl");
        assert_eq!(e.line, 4, "{e}");
    }

    #[test]
    fn missing_entry_point_is_an_error() {
        let l = lib(&[("c.wgsl", "@compute @workgroup_size(1)\nfn main() {}\n")]);
        let e = compile(&l, "c.wgsl", "other", ShaderStage::Compute, &[]).unwrap_err();
        assert!(e.message.contains("`other`"));
    }
}
