//! What a results root holds: one folder per experiment (`RESULTS/NAME/`), listed with its files by
//! role — images to show (PNG, GIF), tables to link (CSV), everything else to link too (metadata,
//! logs). Folders are sorted by name and files by file name, so the page is the same for the same
//! results. Hidden folders and the report's own output folder are skipped.

use std::path::{Path, PathBuf};

use crate::error::InputError;

/// An image to show, with the pixel size its header declares.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// The file.
    pub path: PathBuf,
    /// Width and height in pixels; `None` when the header is not a PNG's or GIF's (the file is
    /// then linked, not shown, since a browser could not draw it).
    pub size: Option<(u32, u32)>,
}

/// One folder of the results root.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Folder {
    /// Folder name (the experiment name, `bench`, `render`, …).
    pub name: String,
    /// The folder (canonical).
    pub dir: PathBuf,
    /// `NAME.meta.toml`, if present.
    pub meta: Option<PathBuf>,
    /// `NAME.csv`, if present.
    pub main_table: Option<PathBuf>,
    /// Images (`.png`, `.gif`).
    pub images: Vec<Image>,
    /// Tables (`.csv`).
    pub tables: Vec<PathBuf>,
    /// Every other file.
    pub others: Vec<PathBuf>,
}

/// The folders of `results` (canonical), skipping hidden ones and `skip` (the output folder).
pub fn folders(results: &Path, skip: Option<&Path>) -> Result<Vec<Folder>, InputError> {
    let file = results.display().to_string();
    let read = |d: &Path| {
        std::fs::read_dir(d).map_err(|e| InputError::new(&file, format!("cannot list: {e}")))
    };
    let mut dirs: Vec<PathBuf> = Vec::new();
    for entry in read(results)? {
        let entry = entry.map_err(|e| InputError::new(&file, format!("cannot list: {e}")))?;
        let path = entry.path();
        let hidden = entry.file_name().to_string_lossy().starts_with('.');
        if hidden || !path.is_dir() {
            continue;
        }
        let canon = path.canonicalize().unwrap_or(path);
        if skip.is_some_and(|s| s == canon) || is_report(&canon) {
            continue;
        }
        dirs.push(canon);
    }
    dirs.sort();
    let mut out = Vec::with_capacity(dirs.len());
    for dir in dirs {
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut files: Vec<PathBuf> = Vec::new();
        for entry in read(&dir)? {
            let entry = entry.map_err(|e| InputError::new(&file, format!("cannot list: {e}")))?;
            let hidden = entry.file_name().to_string_lossy().starts_with('.');
            if !hidden && entry.path().is_file() {
                files.push(entry.path());
            }
        }
        files.sort();
        let mut folder = Folder {
            meta: Some(dir.join(format!("{name}.meta.toml"))).filter(|p| p.is_file()),
            main_table: Some(dir.join(format!("{name}.csv"))).filter(|p| p.is_file()),
            name,
            dir,
            images: Vec::new(),
            tables: Vec::new(),
            others: Vec::new(),
        };
        for f in files {
            let ext = f
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase())
                .unwrap_or_default();
            match ext.as_str() {
                "png" | "gif" => folder.images.push(Image {
                    size: image_size(&f),
                    path: f,
                }),
                "csv" => folder.tables.push(f),
                _ => folder.others.push(f),
            }
        }
        out.push(folder);
    }
    Ok(out)
}

/// Whether `dir` holds a page this command made (another report's output folder, such as a
/// committed `results/report/`): its `index.html` names raycost report as its generator.
fn is_report(dir: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 512];
    let n = std::fs::File::open(dir.join("index.html"))
        .and_then(|mut f| f.read(&mut head))
        .unwrap_or(0);
    String::from_utf8_lossy(&head[..n]).contains(super::page::GENERATOR)
}

/// Width and height from a PNG's IHDR or a GIF's logical screen descriptor.
fn image_size(path: &Path) -> Option<(u32, u32)> {
    use std::io::Read;
    let mut head = [0u8; 24];
    let mut f = std::fs::File::open(path).ok()?;
    f.read_exact(&mut head).ok()?;
    size_from_header(&head)
}

/// The size in the first 24 bytes of a PNG or GIF file.
fn size_from_header(h: &[u8; 24]) -> Option<(u32, u32)> {
    let be = |i: usize| u32::from_be_bytes([h[i], h[i + 1], h[i + 2], h[i + 3]]);
    let le = |i: usize| u32::from(u16::from_le_bytes([h[i], h[i + 1]]));
    let size = if h.starts_with(b"\x89PNG\r\n\x1a\n") && &h[12..16] == b"IHDR" {
        (be(16), be(20))
    } else if h.starts_with(b"GIF87a") || h.starts_with(b"GIF89a") {
        (le(6), le(8))
    } else {
        return None;
    };
    (size.0 > 0 && size.1 > 0).then_some(size)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_sizes_come_from_png_and_gif_headers() {
        let mut png = [0u8; 24];
        png[..8].copy_from_slice(b"\x89PNG\r\n\x1a\n");
        png[12..16].copy_from_slice(b"IHDR");
        png[16..20].copy_from_slice(&640u32.to_be_bytes());
        png[20..24].copy_from_slice(&480u32.to_be_bytes());
        assert_eq!(size_from_header(&png), Some((640, 480)));
        let mut gif = [0u8; 24];
        gif[..6].copy_from_slice(b"GIF89a");
        gif[6..8].copy_from_slice(&300u16.to_le_bytes());
        gif[8..10].copy_from_slice(&200u16.to_le_bytes());
        assert_eq!(size_from_header(&gif), Some((300, 200)));
        assert_eq!(size_from_header(&[b'x'; 24]), None);
    }

    #[test]
    fn folders_are_sorted_and_files_sorted_by_role() {
        let d = tempfile::tempdir().expect("tempdir");
        let r = d.path();
        for f in [
            "b/b.csv",
            "b/b.meta.toml",
            "b/b.hist.csv",
            "b/b.png",
            "b/b.log",
            "a/x.gif",
        ] {
            let p = r.join(f);
            std::fs::create_dir_all(p.parent().expect("parent")).expect("mkdir");
            std::fs::write(p, "x").expect("write");
        }
        std::fs::create_dir_all(r.join(".hidden")).expect("mkdir");
        std::fs::create_dir_all(r.join("report")).expect("mkdir");
        let skip = r.join("report").canonicalize().expect("canon");
        // An older report elsewhere in RESULTS is skipped too; a folder with another index.html is not.
        let page = format!("<!DOCTYPE html>{}", crate::report::page::GENERATOR);
        for (dir, text) in [("old-report", page.as_str()), ("site", "<html>")] {
            std::fs::create_dir_all(r.join(dir)).expect("mkdir");
            std::fs::write(r.join(dir).join("index.html"), text).expect("write");
        }
        let f = folders(r, Some(&skip)).expect("folders");
        let names: Vec<&str> = f.iter().map(|x| x.name.as_str()).collect();
        assert_eq!(names, ["a", "b", "site"]);
        let b = &f[1];
        assert!(b.meta.is_some() && b.main_table.is_some());
        assert_eq!(b.tables.len(), 2);
        assert_eq!(b.images.len(), 1);
        assert_eq!(b.images[0].size, None, "not a real PNG");
        assert_eq!(b.others.len(), 2);
        assert!(f[0].meta.is_none());
    }
}
