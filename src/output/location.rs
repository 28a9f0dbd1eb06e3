//! Where a file is, said the same whatever folder a command was started from: an input is named
//! by its place relative to the spec that names it (the spec's folder and the file both resolved
//! through the file system first, so `cornell.toml`, `sub/../cornell.toml` and `/abs/cornell.toml`
//! are one place), and an output folder is placed against the folders a command reads, so that a
//! command never writes its results inside one of its own inputs.

use std::path::{Component, Path, PathBuf};

use super::OutputError;

/// `path` with `.` dropped and each `name/..` folded away, without asking the file system (a
/// leading `..` that climbs above the start stays).
pub fn normalise(path: &Path) -> PathBuf {
    let mut out: Vec<Component> = Vec::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => match out.last() {
                Some(Component::Normal(_)) => {
                    out.pop();
                }
                Some(Component::RootDir | Component::Prefix(_)) => {}
                _ => out.push(c),
            },
            _ => out.push(c),
        }
    }
    out.iter().map(|c| c.as_os_str()).collect()
}

/// The way from folder `from` to `to`, both absolute and normalised: `..` for each of `from`'s
/// components `to` does not share, then the rest of `to`.
pub fn relative(from: &Path, to: &Path) -> PathBuf {
    let f: Vec<Component> = from.components().collect();
    let t: Vec<Component> = to.components().collect();
    let common = f.iter().zip(&t).take_while(|(a, b)| a == b).count();
    let mut out = PathBuf::new();
    for _ in common..f.len() {
        out.push("..");
    }
    for c in &t[common..] {
        out.push(c.as_os_str());
    }
    out
}

/// `path` resolved as far as it exists: its nearest existing ancestor canonicalised (symlinks and
/// `..` resolved by the file system), the part below it normalised and joined on. A path that does
/// not exist yet (an output) is thus placed where it will be created.
pub fn resolve(path: &Path) -> PathBuf {
    let absolute = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()
            .map(|d| d.join(path))
            .unwrap_or_else(|_| path.to_path_buf())
    };
    let absolute = normalise(&absolute);
    let mut existing = absolute.as_path();
    let mut rest: Vec<&std::ffi::OsStr> = Vec::new();
    loop {
        if let Ok(c) = existing.canonicalize() {
            let mut out = c;
            out.extend(rest.iter().rev());
            return out;
        }
        match (existing.parent(), existing.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name);
                existing = parent;
            }
            _ => return absolute,
        }
    }
}

/// A file's place relative to the folder `base` (the spec's folder), `/`-separated: the folder
/// holding the file and `base` are resolved through the file system ([`resolve`]); the file's own
/// name is kept as the spec spells it (a symlinked scene is named by its link).
pub fn relative_location(base: &Path, file: &Path) -> String {
    let name = file.file_name();
    let folder = resolve(file.parent().unwrap_or(Path::new("")));
    let place = match name {
        Some(n) => folder.join(n),
        None => folder,
    };
    slashed(&relative(&resolve(base), &place))
}

/// `path`'s components joined by `/` (the same text on every platform).
pub fn slashed(path: &Path) -> String {
    path.components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join("/")
}

/// Refuses an output `out` (named by `flag`) that is, or lies inside, one of the folders `reads` a
/// command reads, before anything is written: its results would become part of its own input
/// (a result folder holding two runs is refused as an input from then on). Paths are compared
/// resolved ([`resolve`]), so neither spelling nor a symlink hides the overlap.
pub fn refuse_inside(out: &Path, flag: &str, reads: &[&Path]) -> Result<(), OutputError> {
    let o = resolve(out);
    for r in reads {
        let r_res = resolve(r);
        if o.starts_with(&r_res) {
            let how = if o == r_res { "is" } else { "lies inside" };
            return Err(OutputError::new(
                out,
                format!(
                    "{flag}: {how} {}, a folder this command reads; give an output folder outside every input (nothing was written)",
                    r.display()
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalise_folds_dot_dot_lexically() {
        assert_eq!(normalise(Path::new("a/./b/../c")), PathBuf::from("a/c"));
        assert_eq!(
            normalise(Path::new("../a/../../b")),
            PathBuf::from("../../b")
        );
        assert_eq!(normalise(Path::new("/a/../../b")), PathBuf::from("/b"));
    }

    #[test]
    fn relative_climbs_out_of_what_is_not_shared() {
        assert_eq!(
            relative(Path::new("/x/spec"), Path::new("/x/spec/scenes/a.toml")),
            PathBuf::from("scenes/a.toml")
        );
        assert_eq!(
            relative(Path::new("/x/spec/sub"), Path::new("/x/scenes/a.toml")),
            PathBuf::from("../../scenes/a.toml")
        );
    }

    /// The same file named from different working folders and spellings has one location.
    #[test]
    fn every_spelling_of_a_file_has_one_location() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let root = tmp.path().canonicalize().expect("canon");
        std::fs::create_dir_all(root.join("spec/sub")).expect("mkdir");
        std::fs::write(root.join("spec/cornell.toml"), "x").expect("write");
        let base = root.join("spec");
        let want = "cornell.toml";
        assert_eq!(relative_location(&base, &base.join("cornell.toml")), want);
        assert_eq!(
            relative_location(&base.join("sub/.."), &base.join("sub/../cornell.toml")),
            want
        );
        assert_eq!(
            relative_location(&root.join("spec/./sub/.."), &root.join("spec/cornell.toml")),
            want
        );
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&base, root.join("link")).expect("symlink");
            assert_eq!(
                relative_location(&root.join("link"), &root.join("link/cornell.toml")),
                want
            );
        }
        assert_eq!(
            relative_location(&base.join("sub"), &base.join("cornell.toml")),
            "../cornell.toml"
        );
    }

    #[test]
    fn an_output_inside_an_input_is_refused_whatever_its_spelling() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let a = tmp.path().join("a");
        std::fs::create_dir_all(&a).expect("mkdir");
        let b = tmp.path().join("b");
        for out in [a.clone(), a.join("new/deeper"), tmp.path().join("b/../a/x")] {
            let e = refuse_inside(&out, "--out", &[&b, &a]).expect_err("inside");
            assert!(e.message.contains("a folder this command reads"), "{e}");
        }
        refuse_inside(&tmp.path().join("ab"), "--out", &[&a]).expect("a sibling is outside");
        refuse_inside(&b, "--out", &[&a]).expect("outside");
    }
}
