//! Puts the report's files in place so that no reader ever sees a half-written one: each file goes
//! through the result-folder protocol ([`crate::output::folder::write_atomic`]: a new hidden
//! temporary file in its final folder, fsync, rename over its name). The images go first and `index.html` last, so a page on disk only ever refers to
//! images that are there. Nothing else in DIR is touched (an image of a folder since removed from
//! RESULTS stays in `DIR/img/` until deleted by hand).

use std::fs;
use std::path::Path;

use anyhow::Context;

use crate::output::folder::write_atomic;

use super::Copy;

/// Writes `html` as `out/index.html` after copying every image of `copies` under `out`.
pub fn write(out: &Path, html: &str, copies: &[Copy]) -> anyhow::Result<()> {
    for (src, rel) in copies {
        let bytes = fs::read(src).with_context(|| format!("cannot read {}", src.display()))?;
        atomic(&out.join(rel), &bytes)?;
    }
    atomic(&out.join("index.html"), html.as_bytes())
}

/// Writes `bytes` to `path` whole (the result-folder protocol: a new temporary file, fsync, rename).
fn atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let dir = path.parent().context("a file path has a folder")?;
    fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    write_atomic(path, bytes).with_context(|| format!("cannot write {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_land_whole_and_no_temporary_is_left() {
        let d = tempfile::tempdir().expect("tempdir");
        let src = d.path().join("a.png");
        fs::write(&src, b"png bytes").expect("write");
        let out = d.path().join("out");
        let copies = vec![(src.clone(), Path::new("img/a/a.png").to_path_buf())];
        write(&out, "<p>1</p>", &copies).expect("write");
        write(&out, "<p>2</p>", &copies).expect("replace");
        assert_eq!(
            fs::read(out.join("img/a/a.png")).expect("copy"),
            b"png bytes"
        );
        assert_eq!(
            fs::read_to_string(out.join("index.html")).expect("page"),
            "<p>2</p>"
        );
        let names: Vec<String> = fs::read_dir(&out)
            .expect("list")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.iter().all(|n| !n.contains(".tmp")), "{names:?}");
    }
}
