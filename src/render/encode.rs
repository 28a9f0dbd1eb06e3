//! PNG and animated GIF files of palette images, written through the result-folder protocol
//! ([`crate::output::folder`]: the target's lock, a new temporary file beside it, fsync, rename).

use std::fs;
use std::io::BufWriter;
use std::path::Path;

use anyhow::Context;

use crate::output::folder::{self, Lock};
use crate::output::OutputError;

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

/// Writes `path` through the result-folder protocol: its lock (`PATH.lock`) held, the refusal to
/// replace it without `force` checked under the lock, a new temporary file, fsync, rename.
fn atomic(
    path: &Path,
    force: bool,
    write: impl FnOnce(&mut BufWriter<fs::File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let _lock = Lock::acquire(dir, &name)?;
    folder::remove_stale_temporaries(&[path.to_path_buf()])?;
    if path.exists() && !force {
        return Err(OutputError::new(path, "exists; add --force to replace it").into());
    }
    folder::write_atomic_with(path, write)
}

/// A PNG: 8-bit grey, or indexed colour with the palette.
pub fn write_png(path: &Path, im: &Indexed, force: bool) -> anyhow::Result<()> {
    atomic(path, force, |w| {
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
    force: bool,
) -> anyhow::Result<()> {
    let (w, h) = (
        u16::try_from(width).context("GIF images are at most 65 535 pixels wide")?,
        u16::try_from(height).context("GIF images are at most 65 535 pixels high")?,
    );
    atomic(path, force, |out| {
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
