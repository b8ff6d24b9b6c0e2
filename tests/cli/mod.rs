//! End-to-end tests of the `caustica` binary: rendering a bundled scene to EXR and PNG, the
//! metadata written, and the exit codes and messages of bad input. One file per kind of
//! use; this one holds how the binary is run.

mod failures;
mod render;
mod subcommands;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn caustica<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caustica"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caustica-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `render`, which must succeed.
fn render_ok(scene: &str, out: &Path, flags: &str) -> Output {
    let o = render(scene, out, flags);
    assert!(o.status.success(), "{}", stderr(&o));
    o
}

/// The binary run with a command line given as one string, split at whitespace (no argument
/// here contains any: the temporary directories are named without).
fn run(line: &str) -> Output {
    caustica(&line.split_whitespace().collect::<Vec<_>>())
}

/// `caustica render SCENE -o OUT FLAGS...`, the flags as one string.
fn render(scene: &str, out: &Path, flags: &str) -> Output {
    run(&format!("render {scene} -o {} {flags}", out.display()))
}
