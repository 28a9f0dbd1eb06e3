//! PNG and animated GIF files of palette images, written atomically (a temporary file beside the
//! target, renamed over it).

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::Context;

/// An image of palette indices.
pub struct Indexed<'a> {
    /// Pixels.
    pub width: u32,
    /// Pixels.
    pub height: u32,
    /// Row-major indices.
    pub data: &'a [u8],
    /// 256 RGB triples; `None`: the indices are grey levels (written as an 8-bit grey PNG).
    pub palette: Option<&'a [u8]>,
}

/// Writes `path` through a temporary file in the same folder and a rename.
fn atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<fs::File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let mut tmp: PathBuf = path.to_path_buf();
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    tmp.set_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let res = (|| {
        let f =
            fs::File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
        let mut w = BufWriter::new(f);
        write(&mut w)?;
        w.flush()?;
        w.get_ref().sync_all()?;
        drop(w);
        fs::rename(&tmp, path)
            .with_context(|| format!("cannot rename {} to {}", tmp.display(), path.display()))
    })();
    if res.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    res
}

/// A PNG: 8-bit grey, or indexed colour with the palette.
pub fn write_png(path: &Path, im: &Indexed) -> anyhow::Result<()> {
    atomic(path, |w| {
        let mut e = png::Encoder::new(w, im.width, im.height);
        e.set_depth(png::BitDepth::Eight);
        match im.palette {
            None => e.set_color(png::ColorType::Grayscale),
            Some(p) => {
                e.set_color(png::ColorType::Indexed);
                e.set_palette(p.to_vec());
            }
        }
        e.set_compression(png::Compression::Best);
        let mut pw = e.write_header()?;
        pw.write_image_data(im.data)?;
        pw.finish()?;
        Ok(())
    })
}

/// An animated GIF looping over `frames` (each `width × height` indices into `palette`),
/// `delay_cs` hundredths of a second apiece.
pub fn write_gif(
    path: &Path,
    width: u32,
    height: u32,
    frames: &[Vec<u8>],
    palette: &[u8],
    delay_cs: u16,
) -> anyhow::Result<()> {
    let (w, h) = (
        u16::try_from(width).context("GIF images are at most 65 535 pixels wide")?,
        u16::try_from(height).context("GIF images are at most 65 535 pixels high")?,
    );
    atomic(path, |out| {
        let mut e = gif::Encoder::new(out, w, h, palette)?;
        e.set_repeat(gif::Repeat::Infinite)?;
        for f in frames {
            let frame = gif::Frame {
                width: w,
                height: h,
                delay: delay_cs,
                buffer: std::borrow::Cow::Borrowed(f),
                ..Default::default()
            };
            e.write_frame(&frame)?;
        }
        Ok(())
    })
}
