//! `raycost render`: a small picture of the dynamic Cornell box through the quasi-static engine.

use std::path::{Path, PathBuf};

use crate::common::{raycost, root, write_spec};

/// The tiny spec (20 000 photons, 3 frames).
fn tiny() -> PathBuf {
    root().join("tests/specs/render/cornell-tiny.toml")
}

/// (width, height, grey levels) of an 8-bit grey PNG.
fn read_grey_png(p: &Path) -> (u32, u32, Vec<u8>) {
    let dec = png::Decoder::new(std::fs::File::open(p).expect("the PNG exists"));
    let mut r = dec.read_info().expect("a PNG");
    let mut buf = vec![0; r.output_buffer_size()];
    let info = r.next_frame(&mut buf).expect("a frame");
    assert_eq!(info.color_type, png::ColorType::Grayscale);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

#[test]
fn renders_a_lit_strip_whose_incremental_frames_equal_full_recalculations() {
    let tmp = tempfile::tempdir().expect("temp");
    let (out, gif, diff) = (
        tmp.path().join("cornell.png"),
        tmp.path().join("cornell.gif"),
        tmp.path().join("cornell.diff.png"),
    );
    let o = raycost()
        .arg("render")
        .arg(tiny())
        .args(["--frames", "0,1,2", "--width", "48"])
        .arg("--out")
        .arg(&out)
        .arg("--gif")
        .arg(&gif)
        .arg("--diff")
        .arg(&diff)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    for f in 0..3 {
        assert!(
            stdout.contains(&format!(
                "render: frame {f}, 48×48 pixels, 0 pixel(s) differ (max |ΔE| = 0)"
            )),
            "{stdout}"
        );
    }
    assert!(
        stdout.contains("wrote ") && stdout.contains("times:"),
        "{stdout}"
    );
    let (w, h, px) = read_grey_png(&out);
    assert_eq!((w, h), (3 * 48, 48), "three 48×48 frames side by side");
    assert!(px.iter().any(|&v| v > 0), "not all black");
    // The floor (bottom rows, middle of each frame) is lit; the light (top middle) is white.
    for f in 0..3usize {
        let at = |x: usize, y: usize| px[y * 144 + f * 48 + x];
        let floor: Vec<u8> = (44..47)
            .flat_map(|y| (16..32).map(move |x| (x, y)))
            .map(|(x, y)| at(x, y))
            .collect();
        let mean = floor.iter().map(|&v| f64::from(v)).sum::<f64>() / floor.len() as f64;
        assert!(mean > 60.0, "frame {f}: floor mean grey {mean}");
        assert!(
            (0..12).any(|y| (16..32).any(|x| at(x, y) == 255)),
            "frame {f}: the light is white"
        );
    }
    assert!(std::fs::metadata(&gif).expect("the GIF exists").len() > 100);
    assert!(std::fs::read(&gif).expect("gif").starts_with(b"GIF89a"));
    assert!(diff.exists());
    // No temporary files are left beside the outputs.
    let names: Vec<String> = std::fs::read_dir(tmp.path())
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 3, "{names:?}");

    // A second run refuses to replace the picture (exit 2, file untouched), unless --force.
    let before = std::fs::read(&out).expect("png");
    let again = raycost()
        .arg("render")
        .arg(tiny())
        .args(["--frame", "1", "--width", "16"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(again.status.code(), Some(2));
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("--force"), "{err}");
    assert_eq!(std::fs::read(&out).expect("png"), before);
    raycost()
        .arg("render")
        .arg(tiny())
        .args(["--frame", "1", "--width", "16", "--force"])
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let (w, h, _) = read_grey_png(&out);
    assert_eq!((w, h), (16, 16));
}

#[test]
fn refuses_scenes_without_a_camera_frames_out_of_range_and_other_kinds() {
    let tmp = tempfile::tempdir().expect("temp");
    // The dynamic Cornell box without its [camera] table.
    let scene_text =
        std::fs::read_to_string(root().join("experiments/scenes/cornell-dynamic.toml"))
            .expect("scene");
    let cut = scene_text.find("[camera]").expect("a camera table");
    std::fs::write(tmp.path().join("no-camera.toml"), &scene_text[..cut]).expect("write");
    let spec_text = std::fs::read_to_string(tiny()).expect("spec").replace(
        "../../../experiments/scenes/cornell-dynamic.toml",
        "no-camera.toml",
    );
    let spec = write_spec(tmp.path(), "render-no-camera", &spec_text);
    let out = tmp.path().join("x.png");
    let o = raycost()
        .arg("render")
        .arg(&spec)
        .args(["--width", "8"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with("error: ") && err.contains("detp.scene") && err.contains("no camera"),
        "{err}"
    );
    assert!(!out.exists());

    let o = raycost()
        .arg("render")
        .arg(tiny())
        .args(["--frame", "3", "--width", "8"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("0…2"));
    assert!(!out.exists());

    let o = raycost()
        .arg("render")
        .arg(root().join("experiments/quickstart.toml"))
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("quasi-static"));
    assert!(!out.exists());
}

#[test]
fn a_detp_scene_spec_renders_frame_zero() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(
        tmp.path(),
        "render-detp",
        &format!(
            r#"
[experiment]
name = "render-detp"
kind = "detp"
seed = 2

[detp]
source = "scene"
scene = "{}"
photons = 5000
point_spacing = 60.0
disc_radius = 25.0
engines = ["disc-index"]
"#,
            root()
                .join("experiments/scenes/cornell.toml")
                .display()
                .to_string()
                .replace('\\', "/")
        ),
    );
    let out = tmp.path().join("d.png");
    raycost()
        .arg("render")
        .arg(&spec)
        .args(["--width", "20", "--colormap"])
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    assert!(out.exists());
    let o = raycost()
        .arg("render")
        .arg(&spec)
        .args(["--frame", "1", "--width", "20", "--force"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2), "kind detp has frame 0 only");
}

/// `--width 100000` once aborted allocating 640 GB; now it is refused before anything is
/// traced, naming the flag, and nothing is written.
#[test]
fn an_image_larger_than_memory_is_refused_before_tracing() {
    let tmp = tempfile::tempdir().expect("temp");
    let out = tmp.path().join("big.png");
    let o = raycost()
        .arg("render")
        .arg(tiny())
        .args(["--width", "100000"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--width") && err.contains("GiB"), "{err}");
    assert!(!out.exists());
}

/// `--compare-edge`: the paper's method, a remedy and their difference side by side on the lit
/// hard-case scene (a box on an open floor, a sheet over it): three panels, the remedy changes
/// pixels (the light the paper's rule lets through the box and sheet), and an unknown mode or more
/// than one frame is refused.
#[test]
fn compare_edge_renders_paper_remedy_and_difference() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(
        tmp.path(),
        "render-edge",
        &format!(
            r#"
[experiment]
name = "render-edge"
kind = "detp"
seed = 3

[detp]
source = "scene"
scene = "{}"
photons = 100000
point_spacing = 0.5
disc_radius = 0.05
engines = ["disc-index"]
"#,
            root()
                .join("experiments/scenes/hard/hard-cases-lit.toml")
                .display()
                .to_string()
                .replace('\\', "/")
        ),
    );
    let out = tmp.path().join("cmp.png");
    let o = raycost()
        .arg("render")
        .arg(&spec)
        .args(["--width", "48", "--compare-edge", "clamp-first-hit"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let (w, h, px) = read_grey_png(&out);
    assert_eq!(w, 3 * 48);
    let line = text
        .lines()
        .find(|l| l.contains("paper vs clamp-first-hit"))
        .unwrap_or_else(|| panic!("no comparison line in {text}"));
    let differ: usize = line
        .split(": ")
        .nth(2)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no count in {line}"));
    assert!(differ > 10, "{line}");
    // The difference panel is lit where pixels differ, the two renderings are not the same picture.
    let panel = |k: usize| -> Vec<u8> {
        (0..h as usize)
            .flat_map(|y| px[y * w as usize + k * 48..y * w as usize + (k + 1) * 48].to_vec())
            .collect()
    };
    assert!(panel(2).iter().filter(|&&v| v > 0).count() > 10);
    assert_ne!(panel(0), panel(1));
    for bad in [
        vec!["--compare-edge", "sideways"],
        vec!["--compare-edge", "first-hit", "--frames", "0,0"],
    ] {
        let o = raycost()
            .arg("render")
            .arg(&spec)
            .args(["--width", "8", "--force"])
            .args(&bad)
            .arg("--out")
            .arg(tmp.path().join("bad.png"))
            .output()
            .expect("runs");
        assert_eq!(o.status.code(), Some(2), "{bad:?}");
    }
}
