//! The project explains itself from its own tree: every relative link in
//! the README, the scene format and `docs/` names a file of the
//! repository, and no source, shader or document points outside it (the
//! design notes the project started from are not part of it).

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The targets of `[text](target)` links in `markdown`, without anchors;
/// web links left out.
fn relative_links(markdown: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = markdown;
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        let end = rest.find(')').unwrap_or(rest.len());
        let target = rest[..end].split('#').next().unwrap_or("").trim();
        if !target.is_empty() && !target.contains("://") && !target.starts_with("mailto:") {
            out.push(target.to_string());
        }
    }
    out
}

fn documents() -> Vec<PathBuf> {
    let mut docs = vec![root().join("README.md"), root().join("scenes/README.md")];
    for e in std::fs::read_dir(root().join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            docs.push(p);
        }
    }
    docs
}

#[test]
fn links_name_files_of_the_repository() {
    let root = root().canonicalize().unwrap();
    let mut checked = 0;
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap();
        for link in relative_links(&text) {
            let target = doc.parent().unwrap().join(&link);
            let resolved = target
                .canonicalize()
                .unwrap_or_else(|_| panic!("{}: link `{link}` names no file", doc.display()));
            assert!(
                resolved.starts_with(&root),
                "{}: link `{link}` leads outside the repository",
                doc.display()
            );
            checked += 1;
        }
    }
    assert!(
        checked >= 5,
        "only {checked} links found: the scan is broken"
    );
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            walk(&p, out);
        } else if p.extension().is_some_and(|x| {
            ["rs", "wgsl", "md", "toml", "sh", "py"].contains(&x.to_str().unwrap_or(""))
        }) {
            out.push(p);
        }
    }
}

#[test]
fn nothing_points_outside_the_tree() {
    let mut files = Vec::new();
    for dir in [
        "engine", "passes", "tools", "shaders", "tests", "docs", "scenes",
    ] {
        walk(&root().join(dir), &mut files);
    }
    files.push(root().join("README.md"));
    assert!(files.len() > 50, "only {} files found", files.len());
    // Spelled in two halves so that this file does not match itself.
    let outside = ["../", "shared/"].concat();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap_or_default();
        assert!(
            !text.contains(&outside),
            "{} refers to `{outside}`",
            f.display()
        );
    }
}

#[test]
fn the_link_scan_finds_links() {
    let md = "see [the method](docs/METHOD.md#eq) and [web](https://x.y/z), [a](b.md)";
    assert_eq!(relative_links(md), vec!["docs/METHOD.md", "b.md"]);
}
