//! The documents point at what exists: every path the code map in `app/docs/contributing.md`
//! names, and every relative link in the project's Markdown documents.

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The paths the code map's first column names. An entry starts at column 0 (from the
/// repository's root) or column 2 (inside the last column-0 entry that is a folder); deeper
/// lines continue an entry's description.
fn code_map_paths(doc: &str) -> Vec<PathBuf> {
    let section = doc
        .split("## Code map")
        .nth(1)
        .expect("contributing.md has a code map");
    let block = section
        .split("```text")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("the code map is a text block");
    let mut paths = Vec::new();
    let mut folder = PathBuf::new();
    for line in block.lines() {
        let indent = line.len() - line.trim_start().len();
        let Some(first) = line.split_whitespace().next() else {
            continue;
        };
        match indent {
            0 => {
                let path = PathBuf::from(first);
                if first.ends_with('/') {
                    folder = path.clone();
                }
                paths.push(path);
            }
            2 => paths.push(folder.join(first)),
            _ => {}
        }
    }
    paths
}

#[test]
fn code_map_paths_exist() {
    let doc = std::fs::read_to_string(root().join("app/docs/contributing.md")).unwrap();
    let paths = code_map_paths(&doc);
    assert!(paths.len() > 40, "only {} paths read", paths.len());
    let missing: Vec<_> = paths.iter().filter(|p| !root().join(p).exists()).collect();
    assert!(
        missing.is_empty(),
        "the code map names missing paths: {missing:?}"
    );
}

/// The Markdown files of the repository, outside build output.
fn markdown_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy();
        if name.starts_with('.') || name == "target" {
            continue;
        }
        if path.is_dir() {
            markdown_files(&path, out);
        } else if name.ends_with(".md") {
            out.push(path);
        }
    }
}

/// The targets of `[text](target)` links that are neither web addresses nor anchors.
fn relative_links(text: &str) -> Vec<String> {
    text.split("](")
        .skip(1)
        .filter_map(|rest| rest.split(')').next())
        .map(|target| target.split('#').next().unwrap_or("").to_string())
        .filter(|t| !t.is_empty() && !t.contains("://") && !t.starts_with("mailto:"))
        .collect()
}

#[test]
fn relative_links_in_documents_resolve() {
    let mut files = Vec::new();
    markdown_files(&root(), &mut files);
    assert!(
        files.iter().any(|f| f.ends_with("README.md")),
        "no documents found"
    );
    let mut broken = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for link in relative_links(&text) {
            if !file.parent().unwrap().join(&link).exists() {
                broken.push(format!("{}: {link}", file.display()));
            }
        }
    }
    assert!(broken.is_empty(), "broken links: {broken:#?}");
}

#[test]
fn the_code_map_reader_reads_nested_entries() {
    let doc = "## Code map\n\n```text\nCargo.toml   the workspace\nrenderer/    the library\n  src/lib.rs  its root\n              continued\n```\n";
    assert_eq!(
        code_map_paths(doc),
        [
            PathBuf::from("Cargo.toml"),
            PathBuf::from("renderer/"),
            PathBuf::from("renderer/src/lib.rs")
        ]
    );
}
