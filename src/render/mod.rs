//! `raycost render`: the DETP radiosity of a quasi-static run (B = albedo·E/π from the DETP irradiance
//! E), seen from the scene's camera. A picture with no lit pixel is written with a warning saying
//! why (no surface in view, every surface of albedo 0, or no light reaching them).
//!
//! For each frame asked for, the quasi-static engine is advanced incrementally (frame 0 is a full
//! trace; later frames are reached by [`QuasiStatic::step`], whose poses are pure functions of
//! time, so stepping straight to a frame is valid). One primary ray per pixel centre finds the
//! visible point; a tangent disc of the spec's `detp.disc_radius` there (normal facing the camera)
//! is the pixel's sample point, and its DETP sum is gathered from the live segment store through a
//! grid disc index. A pixel shows the radiosity B = albedo·E/π, one exposure for every frame of the
//! picture (99th percentile → 0.9, gamma 1/2.2); emitters are white, nothing seen is black.
//!
//! The spec's `detp.edge` applies (kind `detp`): clamped disc radii and/or segments cut at their
//! first impact, as in `raycost run`. `--compare-edge MODE` renders one frame three times side by
//! side: the paper's method, MODE, and |E_paper − E_MODE| (tone-mapped with its own exposure), and
//! prints how many pixels differ — the contact shadows under objects show in the middle panel and
//! the light that leaked through them in the right one.
//!
//! `--diff` gathers the same discs from a full recalculation of the frame and marks the pixels
//! whose integer sums differ (there should be none: incremental equals full bit for bit).
//!
//! Nothing here is on the path of `run`, `check` or `bench`.

pub mod camera;
pub mod encode;
pub mod gather;
pub mod tone;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::detp::disc::Discs;
use crate::detp::edge::{clamped_radii, clip_to_first_hit, EdgeMode};
use crate::detp::quasi_static::QuasiStatic;
use crate::detp::store::SegmentStore;
use crate::error::Error;
use crate::experiment::detp::{DetpKind, DynamicEngine, Points};
use crate::experiment::plan::Plan;
use crate::experiment::quasi_static::{self as eq, QuasiStaticConfig, QuasiStaticKind};
use crate::lt::Camera;
use crate::output::OutputError;
use crate::spec::{InputError, KeyError};

use camera::{Pixel, View};
use encode::Indexed;
use tone::{Palette, Radiosity};

/// What to render and where.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Frames, in the order they are reached and shown (left to right).
    pub frames: Vec<u32>,
    /// Sweep point (default 0).
    pub point: usize,
    /// The PNG (default `results/render/NAME.frame-F.png`).
    pub out: Option<PathBuf>,
    /// An animated GIF of the frames too.
    pub gif: Option<PathBuf>,
    /// The difference image incremental − full.
    pub diff: Option<PathBuf>,
    /// Image width (height keeps the camera's aspect ratio).
    pub width: Option<u32>,
    /// False colour instead of grey.
    pub colormap: bool,
    /// Replace existing files.
    pub force: bool,
    /// Camera override: eye.
    pub eye: Option<glam::DVec3>,
    /// Camera override: point looked at.
    pub look_at: Option<glam::DVec3>,
    /// Camera override: vertical field of view, degrees.
    pub fov: Option<f64>,
    /// Render the paper's method, this `detp.edge` mode and their difference side by side.
    pub compare_edge: Option<EdgeMode>,
}

/// One rendered frame.
struct Frame {
    b: Vec<Radiosity>,
    /// Per pixel: differs from the full recalculation, and |ΔE| (with `--diff`).
    diff: Option<(Vec<f64>, usize)>,
}

/// The spec's quasi-static config for the point (a `detp` scene spec becomes a one-frame run).
fn config(plan: &Plan, point: usize) -> anyhow::Result<(QuasiStaticConfig, Option<u64>)> {
    let n = plan.points.len();
    if point >= n {
        return Err(Error::Usage(format!(
            "--point: got {point}, the spec has points 0…{}",
            n.saturating_sub(1)
        ))
        .into());
    }
    if let Some(q) = plan.point::<QuasiStaticKind>(point) {
        return Ok((q.clone(), None));
    }
    match plan.point::<DetpKind>(point) {
        Some(d) if d.scene().is_some() => {
            let file = d.scene().expect("checked");
            Ok((
                QuasiStaticConfig {
                    detp: d.clone(),
                    scene: file.scene.clone(),
                    // The engine's own sample points are not shown; any spacing will do.
                    spacing: match d.points {
                        Points::Surface(s) => s.spacing,
                        _ => 4.0 * d.disc_radius,
                    },
                    frames: 1,
                    ratio: None,
                    crossover: None,
                    check_every: 0,
                    engine: DynamicEngine::default(),
                    points_frame: None,
                    reference_photons: None,
                    predict: None,
                    predictor: crate::detp::quasi_static::Predictor::default(),
                    warm_repeats: 0,
                    feed: crate::detp::quasi_static::Feed::default(),
                    warnings: Vec::new(),
                    lines: false,
                },
                // Replica 0's photons of a `detp` run.
                Some(crate::sample::rng::hash_key(&[
                    d.seed,
                    plan.spec.experiment.stream_point(point),
                    0,
                ])),
            ))
        }
        _ => Err(spec_error(
            plan,
            "experiment.kind",
            "raycost render needs kind \"quasi-static\", or kind \"detp\" with detp.source = \"scene\"",
        )
        .into()),
    }
}

/// A spec error at `key`, located in the spec file.
fn spec_error(plan: &Plan, key: &str, message: &str) -> InputError {
    plan.spec.locate(None, KeyError::new(key, message))
}

/// The radiosity of every pixel of `view` from sums `acc` over `discs` (the view's, or the same
/// discs with their own radii; watts per unit `w`).
fn radiosity(view: &View, discs: &Discs, acc: &[i64], watts_per_unit: f64) -> Vec<Radiosity> {
    view.pixels
        .iter()
        .map(|p| match *p {
            Pixel::Miss => f64::NAN,
            Pixel::Emitter => f64::INFINITY,
            Pixel::Disc { disc, albedo } => {
                let e = discs.irradiance(disc as usize, acc[disc as usize] as f64 * watts_per_unit);
                albedo * e / std::f64::consts::PI
            }
        })
        .collect()
}

/// Why a frame whose pixels `b` show no light at all is black, or `None` if some pixel is lit (an
/// emitter, or a surface with B > 0).
fn black(view: &View, b: &[Radiosity]) -> Option<String> {
    if b.iter().any(|&x| x > 0.0) {
        return None;
    }
    let albedos: Vec<f64> = view
        .pixels
        .iter()
        .filter_map(|p| match *p {
            Pixel::Disc { albedo, .. } => Some(albedo),
            _ => None,
        })
        .collect();
    Some(if albedos.is_empty() {
        "the camera sees no surface (every pixel misses the scene): check [camera] eye, look_at and fov_deg".into()
    } else if albedos.iter().all(|&a| a == 0.0) {
        "every surface in view has albedo 0, and a pixel shows radiosity B = albedo·E/π, which is 0 \
         whatever the irradiance E (give the surfaces an albedo > 0, or measure E with raycost run)"
            .into()
    } else {
        "no light reached the surfaces in view (E = 0 at every pixel): do the lights face them, \
         and are there enough detp.photons?"
            .into()
    })
}

fn default_out(plan: &Plan, frames: &[u32]) -> PathBuf {
    let f: Vec<String> = frames.iter().map(u32::to_string).collect();
    let which = if frames.len() == 1 {
        format!("frame-{}", f[0])
    } else {
        format!("frames-{}", f.join("-"))
    };
    Path::new("results/render").join(format!("{}.{which}.png", plan.spec.experiment.name))
}

/// Renders; returns what to print.
pub fn run(plan: &Plan, o: &RenderOptions) -> anyhow::Result<String> {
    let t_all = Instant::now();
    let (cfg, seed) = config(plan, o.point)?;
    let out = check_options(plan, o, &cfg)?;
    // The scene and its camera, before any tracing.
    let Some(cam) = cfg.scene.camera.clone() else {
        let path = cfg
            .detp
            .scene()
            .map_or(String::new(), |f| f.path.display().to_string());
        return Err(spec_error(
            plan,
            "detp.scene",
            &format!(
                "the scene {path} has no camera: add a [camera] table (TOML scene) or a `v` view (AFF) to render it"
            ),
        )
        .into());
    };
    let cam = aim(cam, o)?;
    let (w, h) = size(&cam, o.width)?;
    let mut log = String::new();

    // Frame 0: the full trace.
    let t = Instant::now();
    let (mut qs, _) = start(&cfg, seed)?;
    let mut times = Times {
        trace_s: t.elapsed().as_secs_f64(),
        ..Times::default()
    };
    writeln!(
        log,
        "render: {} point {}: frame 0 traced ({} photons, {} segments) in {:.3} s",
        plan.spec.path,
        o.point,
        cfg.detp.photons,
        qs.live_segments(),
        times.trace_s
    )?;
    let mut shown: Vec<Frame> = Vec::new();
    let mut black_frames: Vec<String> = Vec::new();
    for &f in &o.frames {
        if f != qs.frame {
            let t = Instant::now();
            let st = qs.step(f);
            times.step_s += t.elapsed().as_secs_f64();
            writeln!(
                log,
                "render: stepped to frame {f}: {} photons re-traced in {:.3} s",
                st.photons_retraced, st.frame_s
            )?;
        }
        let view = camera::view(&qs.scene, &cam, w, h, cfg.detp.disc_radius);
        match o.compare_edge.map(|m| with_spec_params(m, cfg.detp.edge)) {
            Some(mode) => {
                shown.extend(compare_frame(&qs, &view, mode, f, &mut times, &mut log)?);
            }
            None => shown.push(frame(&qs, &view, &cfg, o, f, &mut times, &mut log)?),
        }
        if let Some(why) = shown.last().and_then(|fr| black(&view, &fr.b)) {
            black_frames.push(why);
        }
    }
    // An all-black picture is almost always a scene or spec mistake: say why, once.
    if black_frames.len() == o.frames.len() {
        if let Some(why) = black_frames.first() {
            eprintln!("warning: every pixel of the picture is black: {why}");
        }
    }
    let t = Instant::now();
    encode_frames(&shown, o, &out, (w, h), &mut log)?;
    let encode_s = t.elapsed().as_secs_f64();
    writeln!(
        log,
        "render: times: frame 0 trace {:.3} s, stepping {:.3} s, gathering {:.3} s{}, encoding {encode_s:.3} s, total {:.3} s",
        times.trace_s,
        times.step_s,
        times.gather_s,
        if o.diff.is_some() {
            format!(", full recalculation + gather {:.3} s", times.full_s)
        } else {
            String::new()
        },
        t_all.elapsed().as_secs_f64()
    )?;
    Ok(log)
}

/// Seconds spent in each phase of a rendering.
#[derive(Default)]
struct Times {
    trace_s: f64,
    step_s: f64,
    gather_s: f64,
    full_s: f64,
}

/// The options against the spec: frames the spec has, `--compare-edge` with one frame, output
/// files named once and not replaced without `--force`. Returns the PNG's path.
fn check_options(
    plan: &Plan,
    o: &RenderOptions,
    cfg: &QuasiStaticConfig,
) -> anyhow::Result<PathBuf> {
    if o.frames.is_empty() {
        return Err(Error::Usage("--frames: give at least one frame".into()).into());
    }
    if o.compare_edge.is_some() && (o.frames.len() != 1 || o.diff.is_some() || o.gif.is_some()) {
        return Err(Error::Usage(
            "--compare-edge renders one frame as three panels: give one frame and no --diff or --gif".into(),
        )
        .into());
    }
    if let Some(&f) = o.frames.iter().find(|&&f| f >= cfg.frames) {
        let what = if cfg.frames == 1 {
            "the spec has only frame 0".to_string()
        } else {
            format!("the spec's frames are 0…{}", cfg.frames - 1)
        };
        return Err(Error::Usage(format!("--frame: got {f}, {what}")).into());
    }
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out(plan, &o.frames));
    let mut targets = vec![&out];
    targets.extend(o.gif.iter());
    targets.extend(o.diff.iter());
    for (i, t) in targets.iter().enumerate() {
        if targets[..i].contains(t) {
            return Err(Error::Usage(format!("{} is named twice", t.display())).into());
        }
        if t.exists() && !o.force {
            return Err(OutputError {
                path: t.display().to_string(),
                message: "exists; add --force to replace it".into(),
            }
            .into());
        }
    }
    Ok(out)
}

/// Frame `f` as the spec's `detp.edge` gathers it, with its difference from a full recalculation
/// when `--diff` asks.
fn frame(
    qs: &QuasiStatic,
    view: &View,
    cfg: &QuasiStaticConfig,
    o: &RenderOptions,
    f: u32,
    times: &mut Times,
    log: &mut String,
) -> anyhow::Result<Frame> {
    let t = Instant::now();
    let live = qs.live_store();
    let (discs, cut) = edge(&qs.scene, &view.discs, &live, cfg.detp.edge);
    let live_e = cut.as_ref().unwrap_or(&live);
    let acc = gather::gather(&discs, live_e);
    let b = radiosity(view, &discs, &acc, live.scale.watts_per_unit);
    times.gather_s += t.elapsed().as_secs_f64();
    if o.diff.is_none() {
        return Ok(Frame { b, diff: None });
    }
    let t = Instant::now();
    let (_, full, _) = qs.full_recalculation();
    let (_, cut_full) = edge(&qs.scene, &view.discs, &full, cfg.detp.edge);
    let acc_full = gather::gather(&discs, cut_full.as_ref().unwrap_or(&full));
    let e_inc = radiosity(view, &discs, &acc, live.scale.watts_per_unit);
    let e_full = radiosity(view, &discs, &acc_full, full.scale.watts_per_unit);
    let mut dif = vec![0.0; view.pixels.len()];
    let mut count = 0;
    for (k, p) in view.pixels.iter().enumerate() {
        if let Pixel::Disc { disc, albedo } = *p {
            let i = disc as usize;
            if acc[i] != acc_full[i] || live.scale != full.scale {
                count += 1;
                // Back from radiosity to irradiance.
                dif[k] = ((e_inc[k] - e_full[k]) * std::f64::consts::PI / albedo.max(1e-300))
                    .abs()
                    .max(f64::MIN_POSITIVE);
            }
        }
    }
    times.full_s += t.elapsed().as_secs_f64();
    let max = dif.iter().copied().fold(0.0, f64::max);
    let (w, h) = (view.width, view.height);
    writeln!(
        log,
        "render: frame {f}, {w}×{h} pixels, {count} pixel(s) differ (max |ΔE| = {max})"
    )?;
    Ok(Frame {
        b,
        diff: Some((dif, count)),
    })
}

/// Frame `f` three times: the paper's method, the remedy `mode`, and their difference.
fn compare_frame(
    qs: &QuasiStatic,
    view: &View,
    mode: EdgeMode,
    f: u32,
    times: &mut Times,
    log: &mut String,
) -> anyhow::Result<[Frame; 3]> {
    let t = Instant::now();
    let live = qs.live_store();
    let (pd, pc) = edge(&qs.scene, &view.discs, &live, EdgeMode::Paper);
    let a = gather::gather(&pd, pc.as_ref().unwrap_or(&live));
    let paper = radiosity(view, &pd, &a, live.scale.watts_per_unit);
    let (rd, rc) = edge(&qs.scene, &view.discs, &live, mode);
    let a = gather::gather(&rd, rc.as_ref().unwrap_or(&live));
    let remedy = radiosity(view, &rd, &a, live.scale.watts_per_unit);
    let (dif, count, max) = difference(view, &paper, &remedy);
    times.gather_s += t.elapsed().as_secs_f64();
    writeln!(
        log,
        "render: frame {f}, paper vs {}: {count} of {} pixel(s) differ (max |ΔE| = {max:.6e} W/m²)",
        edge_name(mode),
        view.discs.len()
    )?;
    Ok([
        Frame {
            b: paper,
            diff: None,
        },
        Frame {
            b: remedy,
            diff: None,
        },
        Frame { b: dif, diff: None },
    ])
}

/// Tone-maps the frames side by side into the PNG `out` (and the GIF and the difference image
/// when asked).
fn encode_frames(
    shown: &[Frame],
    o: &RenderOptions,
    out: &Path,
    (w, h): (u32, u32),
    log: &mut String,
) -> anyhow::Result<()> {
    let palette = if o.colormap {
        Palette::Colour
    } else {
        Palette::Grey
    };
    // With --compare-edge the two renderings share one exposure and the difference has its own.
    let exposure = tone::exposure(
        shown
            .iter()
            .take(if o.compare_edge.is_some() {
                2
            } else {
                usize::MAX
            })
            .map(|f| f.b.as_slice()),
    );
    let mut images: Vec<Vec<u8>> = shown
        .iter()
        .map(|f| tone::indices(&f.b, exposure, palette))
        .collect();
    if o.compare_edge.is_some() {
        let dif = &shown[2].b;
        images[2] = tone::indices(dif, tone::exposure([dif.as_slice()]), palette);
    }
    let (wu, hu) = (w as usize, h as usize);
    let k = images.len() as u32;
    let rgb = palette.rgb();
    let pal = o.colormap.then_some(rgb.as_slice());
    let data = tone::strip(&images, wu, hu);
    encode::write_png(
        out,
        &Indexed {
            width: w * k,
            height: h,
            data: &data,
            palette: pal,
        },
        o.force,
    )?;
    let frames_txt: Vec<String> = o.frames.iter().map(u32::to_string).collect();
    writeln!(
        log,
        "wrote {} ({}×{h}, frame(s) {}, exposure {exposure:.6e})",
        out.display(),
        w * k,
        frames_txt.join(", ")
    )?;
    if let Some(g) = &o.gif {
        encode::write_gif(g, w, h, &images, &rgb, 50, o.force)?;
        writeln!(log, "wrote {} ({w}×{h}, {k} frame(s))", g.display())?;
    }
    if let Some(dpath) = &o.diff {
        encode_diff(shown, dpath, (w, h), o.force, log)?;
    }
    Ok(())
}

/// The difference images |E_incremental − E_full| of the frames, side by side, in red.
fn encode_diff(
    shown: &[Frame],
    dpath: &Path,
    (w, h): (u32, u32),
    force: bool,
    log: &mut String,
) -> anyhow::Result<()> {
    let red: Vec<u8> = (0..=255u8).flat_map(|i| [i, 0, 0]).collect();
    let diffs: Vec<Vec<u8>> = shown
        .iter()
        .map(|f| {
            let (dif, _) = f.diff.as_ref().expect("diffs computed");
            let max = dif.iter().copied().fold(0.0, f64::max);
            dif.iter()
                .map(|&x| {
                    if x > 0.0 {
                        128 + (127.0 * x / max).round() as u8
                    } else {
                        0
                    }
                })
                .collect()
        })
        .collect();
    let total: usize = shown
        .iter()
        .map(|f| f.diff.as_ref().map_or(0, |d| d.1))
        .sum();
    let k = shown.len() as u32;
    let data = tone::strip(&diffs, w as usize, h as usize);
    encode::write_png(
        dpath,
        &Indexed {
            width: w * k,
            height: h,
            data: &data,
            palette: Some(&red),
        },
        force,
    )?;
    writeln!(
        log,
        "wrote {} (|E_incremental − E_full|: {total} pixel(s) differ over {k} frame(s))",
        dpath.display()
    )?;
    Ok(())
}

/// The view's discs and, if the mode cuts segments, a cut copy of `store`: `detp.edge` applied as
/// `raycost run` applies it.
fn edge(
    scene: &crate::lt::Scene,
    discs: &Discs,
    store: &SegmentStore,
    mode: EdgeMode,
) -> (Discs, Option<SegmentStore>) {
    let discs = match (mode.clamp_min(), mode.clamp_factor()) {
        (Some(min), Some(factor)) => {
            let r = clamped_radii(
                scene,
                &discs.centers,
                &discs.normals,
                discs.radius,
                min,
                factor,
            );
            discs.clone().with_radii(r).expect("radii in (0, d]")
        }
        _ => discs.clone(),
    };
    let cut = mode.first_hit_gap().map(|g| {
        let mut s = store.clone();
        clip_to_first_hit(&mut s, g * discs.radius);
        s
    });
    (discs, cut)
}

/// `--compare-edge MODE`: a remedy of `detp.edge`, with the default parameters (the spec's replace
/// them in [`run`] when it gives them).
pub fn edge_mode(name: &str) -> Result<EdgeMode, Error> {
    use crate::experiment::detp::{EDGE_GAP, EDGE_MIN_RADIUS, EDGE_RADIUS_FACTOR};
    let (min, gap, factor) = (EDGE_MIN_RADIUS, EDGE_GAP, EDGE_RADIUS_FACTOR);
    match name {
        "clamp-radius" => Ok(EdgeMode::ClampRadius { min, factor }),
        "first-hit" => Ok(EdgeMode::FirstHit { gap }),
        "clamp-first-hit" => Ok(EdgeMode::ClampFirstHit { min, factor, gap }),
        other => Err(Error::Usage(format!(
            "--compare-edge: got \"{other}\", expected a remedy of detp.edge: clamp-radius, first-hit or clamp-first-hit"
        ))),
    }
}

/// `mode` with the parameters the spec's own mode gives.
fn with_spec_params(mode: EdgeMode, spec: EdgeMode) -> EdgeMode {
    let min = spec.clamp_min();
    let factor = spec.clamp_factor();
    let gap = spec.first_hit_gap();
    match mode {
        EdgeMode::ClampRadius { min: m, factor: k } => EdgeMode::ClampRadius {
            min: min.unwrap_or(m),
            factor: factor.unwrap_or(k),
        },
        EdgeMode::FirstHit { gap: g } => EdgeMode::FirstHit {
            gap: gap.unwrap_or(g),
        },
        EdgeMode::ClampFirstHit {
            min: m,
            factor: k,
            gap: g,
        } => EdgeMode::ClampFirstHit {
            min: min.unwrap_or(m),
            factor: factor.unwrap_or(k),
            gap: gap.unwrap_or(g),
        },
        EdgeMode::Paper => EdgeMode::Paper,
    }
}

/// The `detp.edge` value of a mode.
fn edge_name(mode: EdgeMode) -> &'static str {
    match mode {
        EdgeMode::Paper => "paper",
        EdgeMode::ClampRadius { .. } => "clamp-radius",
        EdgeMode::FirstHit { .. } => "first-hit",
        EdgeMode::ClampFirstHit { .. } => "clamp-first-hit",
    }
}

/// Per pixel |E_a − E_b| (irradiance, from radiosity over albedo; 0 where neither is a disc), the
/// number of disc pixels that differ and the largest difference.
fn difference(view: &View, a: &[Radiosity], b: &[Radiosity]) -> (Vec<Radiosity>, usize, f64) {
    let mut out = vec![f64::NAN; view.pixels.len()];
    let (mut count, mut max) = (0, 0.0f64);
    for (k, p) in view.pixels.iter().enumerate() {
        match *p {
            Pixel::Disc { albedo, .. } => {
                let d = if a[k] == b[k] {
                    0.0
                } else {
                    count += 1;
                    (a[k] - b[k]).abs() * std::f64::consts::PI / albedo.max(1e-300)
                };
                max = max.max(d);
                out[k] = d;
            }
            Pixel::Emitter | Pixel::Miss => {}
        }
    }
    (out, count, max)
}

/// The scene's camera, moved and aimed as the options say.
fn aim(mut cam: Camera, o: &RenderOptions) -> anyhow::Result<Camera> {
    if let Some(e) = o.eye {
        cam.eye = e;
    }
    if let Some(l) = o.look_at {
        cam.look_at = l;
    }
    if let Some(f) = o.fov {
        if !(f.is_finite() && f > 0.0 && f < 180.0) {
            return Err(
                Error::Usage(format!("--fov: got {f}, expected degrees in (0, 180)")).into(),
            );
        }
        cam.fov_deg = f;
    }
    let fwd = cam.look_at - cam.eye;
    if fwd.length() == 0.0 || fwd.cross(cam.up).length() <= 1e-12 * fwd.length() * cam.up.length() {
        return Err(Error::Usage(
            "the camera looks at its own eye or along its up vector (set --eye/--look-at apart, not straight up or down)".into(),
        )
        .into());
    }
    Ok(cam)
}

/// The image size: the camera's, or `width` wide with the camera's aspect ratio.
fn size(cam: &Camera, width: Option<u32>) -> anyhow::Result<(u32, u32)> {
    let (w, h) = match width {
        None => (cam.width.max(1), cam.height.max(1)),
        Some(0) => {
            return Err(Error::Usage("--width: got 0, expected at least 1 pixel".into()).into())
        }
        Some(w) => {
            let h = (f64::from(w) * f64::from(cam.height) / f64::from(cam.width.max(1))).round();
            (w, (h.min(f64::from(u32::MAX)) as u32).max(1))
        }
    };
    // Per pixel: its disc (centre, normal), its sum, radiosity, the indexed image and a diff: about
    // PIXEL_BYTES. Refused before anything is traced when it does not fit.
    const PIXEL_BYTES: f64 = 160.0;
    let need = f64::from(w) * f64::from(h) * PIXEL_BYTES;
    let avail = crate::output::meta::available_memory().map_or(f64::INFINITY, |a| 0.5 * a as f64);
    if need > avail {
        let flag = if width.is_some() {
            "--width"
        } else {
            "the scene camera's resolution"
        };
        return Err(Error::Usage(format!(
            "{flag}: a {w}×{h} image needs about {:.1} GiB, over half the {:.1} GiB this machine has available; render smaller",
            need / f64::from(1u32 << 30),
            2.0 * avail / f64::from(1u32 << 30)
        ))
        .into());
    }
    Ok((w, h))
}

/// Frame 0 of the run (`seed`: overrides the quasi-static photon seed, for `detp` specs).
fn start(
    cfg: &QuasiStaticConfig,
    seed: Option<u64>,
) -> anyhow::Result<(QuasiStatic, crate::detp::quasi_static::FrameStats)> {
    match seed {
        None => Ok(eq::start(cfg, 0)),
        Some(s) => {
            let mut p = eq::params(cfg, 1.0, 0);
            p.seed = s;
            Ok(QuasiStatic::start(cfg.scene.clone(), p))
        }
    }
}
