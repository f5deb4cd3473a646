//! The cache of baked results (fields, SSDFs). An entry is named by a key
//! that hashes every byte its result depends on: the inputs' text and every
//! file they read (a scene's equirect EXR; a glTF's buffers and images),
//! the knobs, the format and bake revisions and the program's version. An
//! edited input therefore misses the cache and is baked again; an entry
//! that fails to load is baked again and replaced; an entry is written to a
//! temporary file in the cache's directory and renamed into place, so an
//! interrupted write never leaves a partial entry under the entry's name.

use std::path::{Path, PathBuf};

use anyhow::Context as _;

/// Environment variable naming the directory baked results are cached in.
pub const CACHE_ENV: &str = "INLAY_CACHE_DIR";

/// The directory baked results are cached in, if one can be used:
/// `$INLAY_CACHE_DIR`, else `$XDG_CACHE_HOME/inlay`, else
/// `$HOME/.cache/inlay`.
pub fn cache_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os(CACHE_ENV) {
        return Some(PathBuf::from(d));
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME") {
        return Some(PathBuf::from(d).join("inlay"));
    }
    std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache").join("inlay"))
}

/// A content key: FNV-1a (64 bits) over labelled, length-prefixed byte
/// strings, so no two different sequences of inputs run together into the
/// same bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CacheKey(u64);

impl CacheKey {
    /// A key for results of kind `kind`, seeded with the program's version.
    pub fn new(kind: &str) -> Self {
        CacheKey(0xcbf29ce484222325)
            .bytes("kind", kind.as_bytes())
            .bytes("version", env!("CARGO_PKG_VERSION").as_bytes())
    }

    /// The key with `bytes` (labelled `label`) added.
    pub fn bytes(self, label: &str, bytes: &[u8]) -> Self {
        let mut h = self.0;
        for part in [label.as_bytes(), &(bytes.len() as u64).to_le_bytes(), bytes] {
            for b in part {
                h ^= *b as u64;
                h = h.wrapping_mul(0x100000001b3);
            }
        }
        CacheKey(h)
    }

    /// The key with `text` (labelled `label`) added.
    pub fn text(self, label: &str, text: &str) -> Self {
        self.bytes(label, text.as_bytes())
    }

    /// The key with every byte of the file at `path` added (its content,
    /// not its name: the same file reached by another path keys the same);
    /// an error names the file.
    pub fn file(self, path: &Path) -> anyhow::Result<Self> {
        let bytes =
            std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
        Ok(self.bytes("file", &bytes))
    }

    /// The key with every byte of each of `paths` added, in order.
    pub fn files<'p>(self, paths: impl IntoIterator<Item = &'p PathBuf>) -> anyhow::Result<Self> {
        paths.into_iter().try_fold(self, |k, p| k.file(p))
    }

    /// The key as 16 hex digits (the cache entry's name).
    pub fn hex(&self) -> String {
        format!("{:016x}", self.0)
    }
}

/// The cache entry for `stem` under `key`, with `extension`; `None` when
/// no cache directory can be used.
pub fn entry_path(stem: &str, key: CacheKey, extension: &str) -> Option<PathBuf> {
    cache_dir().map(|d| d.join(format!("{stem}-{}.{extension}", key.hex())))
}

/// The result cached at `entry` if it loads, else `make()`'s result, saved
/// there (as `encode` gives its bytes) for the next run. With no entry
/// (no cache, or caching turned off) it is `make()`. A failure to save is
/// logged, not returned: the result is good either way.
pub fn load_or_make<T>(
    entry: Option<&Path>,
    what: &str,
    load: impl FnOnce(&Path) -> anyhow::Result<T>,
    make: impl FnOnce() -> anyhow::Result<T>,
    encode: impl FnOnce(&T) -> Vec<u8>,
) -> anyhow::Result<T> {
    let Some(path) = entry else {
        return make();
    };
    if path.exists() {
        match load(path) {
            Ok(v) => {
                log::info!("loaded the {what} from {}", path.display());
                return Ok(v);
            }
            Err(e) => log::warn!("baking again over a bad cached {what}: {e:#}"),
        }
    }
    let value = make()?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let written = std::fs::create_dir_all(dir)
        .map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", dir.display()))
        .and_then(|_| {
            Ok(inlay_engine::output::write_atomically(
                path,
                &encode(&value),
            )?)
        });
    if let Err(e) = written {
        log::warn!("could not cache the {what}: {e:#}");
    }
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("inlay-cache-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn keys_separate_their_inputs() {
        let k = CacheKey::new("t");
        assert_ne!(k.text("a", "bc"), k.text("ab", "c"));
        assert_ne!(k.text("a", "b").text("c", ""), k.text("a", "bc"));
        assert_eq!(k.text("a", "b"), CacheKey::new("t").text("a", "b"));
        assert_ne!(CacheKey::new("field"), CacheKey::new("ssdf"));
    }

    #[test]
    fn a_file_edit_changes_the_key() {
        let d = temp_dir("edit");
        let f = d.join("input.bin");
        std::fs::write(&f, [1u8, 2, 3]).unwrap();
        let before = CacheKey::new("t").file(&f).unwrap();
        std::fs::write(&f, [1u8, 2, 4]).unwrap();
        let after = CacheKey::new("t").file(&f).unwrap();
        assert_ne!(before, after);
        let missing = CacheKey::new("t").file(&d.join("absent.bin"));
        assert!(format!("{:#}", missing.unwrap_err()).contains("absent.bin"));
    }

    #[test]
    fn a_bad_entry_is_made_again_and_replaced() {
        let d = temp_dir("bad");
        let entry = d.join("x-0.bin");
        std::fs::write(&entry, b"garbage").unwrap();
        let load = |p: &Path| -> anyhow::Result<u32> {
            let b = std::fs::read(p)?;
            anyhow::ensure!(b.len() == 4, "{} bytes", b.len());
            Ok(u32::from_le_bytes(b.try_into().unwrap()))
        };
        let mut made = 0;
        let v = load_or_make(
            Some(&entry),
            "test value",
            load,
            || {
                made += 1;
                Ok(7u32)
            },
            |v| v.to_le_bytes().to_vec(),
        )
        .unwrap();
        assert_eq!((v, made), (7, 1));
        let again = load_or_make(
            Some(&entry),
            "test value",
            load,
            || anyhow::bail!("must load from the cache"),
            |v: &u32| v.to_le_bytes().to_vec(),
        )
        .unwrap();
        assert_eq!(again, 7);
        let leftovers: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".partial"))
            .collect();
        assert!(leftovers.is_empty(), "temporary files left behind");
    }
}
