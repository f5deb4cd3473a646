//! Output files written so that no run leaves a partial file or a half-replaced
//! set of outputs behind.
//!
//! Every output first goes to a hidden temporary file in its own directory
//! (`.inlay-partial-<pid>-<n>-<name>`, keeping the name's extension so that
//! writers choosing a format by extension still work). An [`OutputBatch`]
//! renames all of its files into place only once every one of them has been
//! written; until then the previous outputs stay untouched, and a batch
//! dropped without [`OutputBatch::commit`] (an error, a panic) deletes its
//! temporaries. A run killed mid-write leaves at most a hidden temporary,
//! never a truncated output under the output's name.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{EngineError, Result};

/// Prefix of every temporary output file's name.
pub const PARTIAL_PREFIX: &str = ".inlay-partial-";

static NEXT_TEMP: AtomicU64 = AtomicU64::new(0);

fn file_error(path: &Path, message: impl Into<String>) -> EngineError {
    EngineError::File {
        path: path.display().to_string(),
        message: message.into(),
    }
}

/// The directory `path` would be written into (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The directory `path` would be written into, if it exists.
fn existing_dir(path: &Path) -> Result<&Path> {
    let dir = parent_dir(path);
    if dir.is_dir() {
        Ok(dir)
    } else {
        Err(file_error(
            path,
            format!("its directory {} does not exist", dir.display()),
        ))
    }
}

/// A fresh temporary path next to `path`, keeping its extension.
fn temp_path_for(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let n = NEXT_TEMP.fetch_add(1, Ordering::Relaxed);
    parent_dir(path).join(format!("{PARTIAL_PREFIX}{}-{n}-{name}", std::process::id()))
}

/// The writer's message about `temp`, told about `path` instead.
fn writer_error(temp: &Path, path: &Path, message: String) -> EngineError {
    let message = message.replace(&temp.display().to_string(), &path.display().to_string());
    let named = format!("{}: ", path.display());
    match message.strip_prefix(&named) {
        Some(rest) => file_error(path, rest),
        None => file_error(path, message),
    }
}

/// Whether `path` exists and is neither a regular file nor a directory (a
/// device such as `/dev/null`, a pipe): written straight through, never
/// replaced by a rename.
fn is_special(path: &Path) -> bool {
    path.metadata()
        .map(|m| !m.is_file() && !m.is_dir())
        .unwrap_or(false)
}

/// Checks, before any long work, that `path` can take an output: its
/// extension is one of `extensions` (compared without case; empty accepts
/// any), it is not a directory, and its directory exists and takes a new
/// file (tried by creating and removing a temporary one). Nothing under
/// `path` itself is touched. A device or pipe (`/dev/null`) is accepted
/// as it is.
pub fn check_output_path(path: &Path, extensions: &[&str]) -> Result<()> {
    if path.as_os_str().is_empty() || path.file_name().is_none() {
        return Err(file_error(path, "not a file name"));
    }
    if is_special(path) {
        return Ok(());
    }
    if !extensions.is_empty() {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if !ext.as_deref().is_some_and(|e| extensions.contains(&e)) {
            let list: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
            return Err(file_error(
                path,
                format!(
                    "unknown output format: use a {} file name",
                    list.join(" or ")
                ),
            ));
        }
    }
    if path.is_dir() {
        return Err(file_error(path, "is a directory, not a file"));
    }
    let dir = existing_dir(path)?;
    let probe = temp_path_for(path);
    std::fs::File::create(&probe)
        .map_err(|e| file_error(path, format!("cannot write in {}: {e}", dir.display())))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// A set of output files replaced together: each is written to a temporary
/// file beside it, and [`commit`](Self::commit) renames them all into place.
/// Dropped uncommitted, it deletes the temporaries and leaves every previous
/// output as it was.
#[derive(Debug, Default)]
pub struct OutputBatch {
    staged: Vec<(PathBuf, PathBuf)>,
}

impl OutputBatch {
    /// An empty batch.
    pub fn new() -> Self {
        Self::default()
    }

    /// Stages `path` by calling `write` with the temporary path to fill (it
    /// has `path`'s extension). A failure names `path`; the temporary is
    /// removed. A device or pipe (`/dev/null`) is written at once instead.
    pub fn write_with<E: std::fmt::Display>(
        &mut self,
        path: &Path,
        write: impl FnOnce(&Path) -> std::result::Result<(), E>,
    ) -> Result<()> {
        if is_special(path) {
            return write(path).map_err(|e| file_error(path, e.to_string()));
        }
        existing_dir(path)?;
        let temp = temp_path_for(path);
        // Registered first so that a panic inside `write` still cleans up.
        self.staged.push((temp.clone(), path.to_owned()));
        match write(&temp) {
            Ok(()) if temp.is_file() => Ok(()),
            Ok(()) => Err(file_error(path, "the writer produced no file")),
            Err(e) => Err(writer_error(&temp, path, e.to_string())),
        }
        .inspect_err(|_| {
            self.staged.pop();
            let _ = std::fs::remove_file(&temp);
        })
    }

    /// Stages `bytes` as the content of `path`.
    pub fn write_bytes(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        self.write_with(path, |temp| std::fs::write(temp, bytes))
    }

    /// The outputs staged so far, in order.
    pub fn paths(&self) -> impl Iterator<Item = &Path> {
        self.staged.iter().map(|(_, p)| p.as_path())
    }

    /// Renames every staged file into place, in order, and returns their
    /// paths. Renames within one directory are atomic, so each output is
    /// either its previous or its complete new content.
    pub fn commit(mut self) -> Result<Vec<PathBuf>> {
        let staged = std::mem::take(&mut self.staged);
        let mut done = Vec::with_capacity(staged.len());
        let mut rest = staged.into_iter();
        for (temp, path) in rest.by_ref() {
            if let Err(e) = std::fs::rename(&temp, &path) {
                let _ = std::fs::remove_file(&temp);
                for (t, _) in rest {
                    let _ = std::fs::remove_file(&t);
                }
                return Err(file_error(&path, format!("cannot put in place: {e}")));
            }
            done.push(path);
        }
        Ok(done)
    }
}

impl Drop for OutputBatch {
    fn drop(&mut self) {
        for (temp, _) in self.staged.drain(..) {
            let _ = std::fs::remove_file(&temp);
        }
    }
}

/// Writes one output through a temporary file renamed into place once
/// `write` has filled it.
pub fn write_atomically_with<E: std::fmt::Display>(
    path: &Path,
    write: impl FnOnce(&Path) -> std::result::Result<(), E>,
) -> Result<()> {
    let mut batch = OutputBatch::new();
    batch.write_with(path, write)?;
    batch.commit().map(|_| ())
}

/// Writes `bytes` to `path` through a temporary file renamed into place.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomically_with(path, |temp| std::fs::write(temp, bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("inlay-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn leftovers(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(PARTIAL_PREFIX))
            .collect()
    }

    #[test]
    fn a_batch_replaces_all_or_nothing() {
        let d = temp_dir("batch");
        let (a, b) = (d.join("a.txt"), d.join("b.txt"));
        std::fs::write(&a, "old a").unwrap();
        std::fs::write(&b, "old b").unwrap();
        // The second output fails: neither is replaced.
        let mut batch = OutputBatch::new();
        batch.write_bytes(&a, b"new a").unwrap();
        let e = batch
            .write_with(&b, |_| Err::<(), _>("disk full"))
            .unwrap_err();
        assert!(e.to_string().contains("b.txt") && e.to_string().contains("disk full"));
        drop(batch);
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "old b");
        assert!(leftovers(&d).is_empty(), "{:?}", leftovers(&d));
        // Both succeed: both are replaced on commit, not before.
        let mut batch = OutputBatch::new();
        batch.write_bytes(&a, b"new a").unwrap();
        batch.write_bytes(&b, b"new b").unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a");
        assert_eq!(batch.commit().unwrap(), vec![a.clone(), b.clone()]);
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new a");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "new b");
        assert!(leftovers(&d).is_empty());
    }

    #[test]
    fn a_writer_interrupted_mid_file_leaves_the_previous_output() {
        let d = temp_dir("interrupted");
        let a = d.join("image.exr");
        std::fs::write(&a, "previous").unwrap();
        // A panic half-way through the write (an interruption inside the
        // process) unwinds through the batch, which removes the partial file.
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut batch = OutputBatch::new();
            let _ = batch.write_with(&a, |temp| -> std::io::Result<()> {
                assert!(temp.extension().is_some_and(|e| e == "exr"));
                std::fs::write(temp, b"half")?;
                panic!("interrupted");
            });
        }));
        assert!(result.is_err());
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "previous");
        assert!(leftovers(&d).is_empty(), "{:?}", leftovers(&d));
    }

    #[test]
    fn output_paths_are_checked_without_touching_them() {
        let d = temp_dir("check");
        let ok = d.join("x.PNG");
        check_output_path(&ok, &["exr", "png"]).unwrap();
        assert!(!ok.exists());
        let e = check_output_path(&d.join("x.jpg"), &["exr", "png"]).unwrap_err();
        assert!(e.to_string().contains("x.jpg") && e.to_string().contains(".exr or .png"));
        let e = check_output_path(&d.join("missing/x.exr"), &["exr"]).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        std::fs::create_dir_all(d.join("dir.exr")).unwrap();
        let e = check_output_path(&d.join("dir.exr"), &["exr"]).unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        check_output_path(Path::new("relative-name.json"), &[]).unwrap();
        // A device is written through, whatever its name.
        let null = Path::new("/dev/null");
        if is_special(null) {
            check_output_path(null, &["json"]).unwrap();
            write_atomically(null, b"discarded").unwrap();
            assert!(is_special(null));
        }
        assert!(leftovers(&d).is_empty());
        assert!(leftovers(Path::new(".")).is_empty());
    }
}
