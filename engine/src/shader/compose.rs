//! The include step: `#include "path"` lines are replaced by the named file
//! (each file at most once per shader), and knob values are prepended as WGSL
//! constants. A line map ties every composed line back to its file and line.

use std::collections::HashSet;

use super::{ShaderError, ShaderLibrary};

/// A compile-time constant prepended to a shader (a knob's value), emitted as
/// `const NAME: TYPE = VALUE;`.
#[derive(Debug, Clone, PartialEq)]
pub enum Define {
    /// An unsigned integer constant.
    U32(&'static str, u32),
    /// A signed integer constant.
    I32(&'static str, i32),
    /// A float constant.
    F32(&'static str, f32),
    /// A boolean constant.
    Bool(&'static str, bool),
}

impl Define {
    /// The constant's name.
    pub fn name(&self) -> &'static str {
        match self {
            Define::U32(n, _) | Define::I32(n, _) | Define::F32(n, _) | Define::Bool(n, _) => n,
        }
    }

    fn to_wgsl(&self) -> String {
        match self {
            Define::U32(n, v) => format!("const {n}: u32 = {v}u;"),
            Define::I32(n, v) => format!("const {n}: i32 = {v}i;"),
            Define::F32(n, v) => format!("const {n}: f32 = {v:?};"),
            Define::Bool(n, v) => format!("const {n}: bool = {v};"),
        }
    }
}

/// A composed shader: the text naga sees and, per line, where it came from.
#[derive(Debug, Clone)]
pub struct Composed {
    /// The full WGSL text.
    pub source: String,
    /// For each line of `source`: (file, 1-based line in that file).
    pub origins: Vec<(String, u32)>,
}

impl Composed {
    /// Maps a 1-based line of the composed text back to its file and line.
    pub fn origin(&self, line: u32) -> (String, u32) {
        self.origins
            .get(line.saturating_sub(1) as usize)
            .cloned()
            .unwrap_or_else(|| {
                (
                    self.origins.last().map(|o| o.0.clone()).unwrap_or_default(),
                    0,
                )
            })
    }
}

/// Composes `entry` from `library`: defines first (the library's own,
/// [`ShaderLibrary::with_defines`], then `defines`, which replace those of
/// the same names), then the file with its includes expanded depth-first,
/// each included file once.
pub fn compose(
    library: &ShaderLibrary,
    entry: &str,
    defines: &[Define],
) -> Result<Composed, ShaderError> {
    let mut out = Composed {
        source: String::new(),
        origins: Vec::new(),
    };
    for d in &library.merged_defines(defines) {
        out.source.push_str(&d.to_wgsl());
        out.source.push('\n');
        out.origins.push(("<knob defines>".into(), 0));
    }
    let source = library.get(entry).ok_or_else(|| ShaderError {
        file: entry.into(),
        line: 0,
        column: 0,
        message: "no such shader file in the library".into(),
    })?;
    let mut seen = HashSet::new();
    let mut stack = Vec::new();
    expand(library, entry, source, &mut seen, &mut stack, &mut out)?;
    Ok(out)
}

fn expand<'a>(
    library: &'a ShaderLibrary,
    file: &str,
    source: &'a str,
    seen: &mut HashSet<String>,
    stack: &mut Vec<String>,
    out: &mut Composed,
) -> Result<(), ShaderError> {
    seen.insert(file.to_owned());
    stack.push(file.to_owned());
    for (i, line) in source.lines().enumerate() {
        let line_no = i as u32 + 1;
        let trimmed = line.trim_start();
        if let Some(rest) = trimmed.strip_prefix("#include") {
            let err = |message: String| ShaderError {
                file: file.to_owned(),
                line: line_no,
                column: (line.len() - trimmed.len()) as u32 + 1,
                message,
            };
            let target = rest.trim();
            let target = target
                .strip_prefix('"')
                .and_then(|t| t.strip_suffix('"'))
                .ok_or_else(|| {
                    err(format!(
                        "malformed include `{}`: expected #include \"path\"",
                        line.trim()
                    ))
                })?;
            if stack.iter().any(|f| f == target) {
                return Err(err(format!(
                    "include cycle: {} -> {target}",
                    stack.join(" -> ")
                )));
            }
            if seen.contains(target) {
                out.source.push('\n');
                out.origins.push((file.to_owned(), line_no));
                continue;
            }
            let included = library.get(target).ok_or_else(|| {
                err(format!(
                    "included file `{target}` is not in the shader library"
                ))
            })?;
            expand(library, target, included, seen, stack, out)?;
        } else {
            out.source.push_str(line);
            out.source.push('\n');
            out.origins.push((file.to_owned(), line_no));
        }
    }
    stack.pop();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lib(files: &[(&str, &str)]) -> ShaderLibrary {
        ShaderLibrary::from_pairs(files.iter().copied())
    }

    /// A library's own defines come first; a shader's define of the same
    /// name replaces the library's, and a later `with_defines` replaces an
    /// earlier one.
    #[test]
    fn library_defines_are_merged_under_the_shader_s() {
        let l = lib(&[("a.wgsl", "fn a() {}")])
            .with_defines(&[Define::Bool("V", true), Define::U32("N", 1)])
            .with_defines(&[Define::Bool("V", false)]);
        assert_eq!(l.define("V"), Some(&Define::Bool("V", false)));
        let c = compose(&l, "a.wgsl", &[Define::U32("N", 4)]).unwrap();
        let lines: Vec<&str> = c.source.lines().collect();
        assert_eq!(
            &lines[..2],
            &["const V: bool = false;", "const N: u32 = 4u;"],
            "{}",
            c.source
        );
    }

    #[test]
    fn includes_expand_once_and_lines_map_back() {
        let l = lib(&[
            (
                "a.wgsl",
                "#include \"common/b.wgsl\"\n#include \"common/c.wgsl\"\nfn a() {}",
            ),
            ("common/b.wgsl", "#include \"common/c.wgsl\"\nfn b() {}"),
            ("common/c.wgsl", "fn c() {}"),
        ]);
        let c = compose(&l, "a.wgsl", &[Define::U32("N", 4)]).unwrap();
        assert_eq!(c.source.matches("fn c()").count(), 1, "{}", c.source);
        let lines: Vec<&str> = c.source.lines().collect();
        assert_eq!(lines[0], "const N: u32 = 4u;");
        let a_line = lines.iter().position(|l| *l == "fn a() {}").unwrap() as u32 + 1;
        assert_eq!(c.origin(a_line), ("a.wgsl".to_string(), 3));
        let b_line = lines.iter().position(|l| *l == "fn b() {}").unwrap() as u32 + 1;
        assert_eq!(c.origin(b_line), ("common/b.wgsl".to_string(), 2));
    }

    #[test]
    fn missing_include_names_the_including_file_and_line() {
        let l = lib(&[("a.wgsl", "fn a() {}\n  #include \"nope.wgsl\"")]);
        let e = compose(&l, "a.wgsl", &[]).unwrap_err();
        assert_eq!((e.file.as_str(), e.line, e.column), ("a.wgsl", 2, 3));
        assert!(e.message.contains("nope.wgsl"));
    }

    #[test]
    fn cycles_and_malformed_includes_are_errors() {
        let l = lib(&[
            ("a.wgsl", "#include \"b.wgsl\""),
            ("b.wgsl", "#include \"a.wgsl\""),
            ("m.wgsl", "#include <x>"),
        ]);
        assert!(compose(&l, "a.wgsl", &[])
            .unwrap_err()
            .message
            .contains("cycle"));
        assert!(compose(&l, "m.wgsl", &[])
            .unwrap_err()
            .message
            .contains("malformed"));
        assert!(compose(&l, "zzz.wgsl", &[]).is_err());
    }
}
