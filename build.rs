//! Records what the binary is built from, for result provenance: the git commit, whether the work
//! tree had uncommitted changes, and the compiler version ("unknown" where git or rustc is missing).
use std::process::Command;

fn output(cmd: &str, args: &[&str]) -> Option<String> {
    Command::new(cmd)
        .args(args)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
}

fn main() {
    let commit = output("git", &["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into());
    // Tracked files only: build outputs and results written by a run do not make a tree dirty.
    let dirty = match output("git", &["status", "--porcelain", "--untracked-files=no"]) {
        Some(s) => (!s.is_empty()).to_string(),
        None => "unknown".into(),
    };
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = output(&rustc, &["--version"]).unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=RAYCOST_GIT_COMMIT={commit}");
    println!("cargo:rustc-env=RAYCOST_GIT_DIRTY={dirty}");
    println!("cargo:rustc-env=RAYCOST_RUSTC={version}");
    // In a worktree `.git` is a file; ask git where HEAD and the index live.
    for what in ["HEAD", "index", "refs"] {
        if let Some(p) = output("git", &["rev-parse", "--git-path", what]) {
            if std::path::Path::new(&p).exists() {
                println!("cargo:rerun-if-changed={p}");
            }
        }
    }
}
