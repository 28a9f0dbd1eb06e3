//! The frames part of the analysis: F*, the frames of a quasi-static scene beyond which DETP (its
//! first frame in full, then incremental frames) costs less in all than per-point path tracing at
//! the same target error ([`frames_crossover`]), and the same for DETP recalculating every frame in
//! full (`full_frame_s`: it exists only if a full frame beats path tracing's frame).
//!
//! DETP's photons N_ε come from the fronts' error fit of the configuration the quasi-static layer
//! runs (direct = photons, edge = paper) at the frames table's d, or the nearest d of the fronts.
//! The frames table's seconds are measured at its own photon counts: among rows with the same
//! points, `a + b·N` is fitted (non-negative) when they hold ≥ 2 photon counts, else the seconds are
//! scaled in proportion to N. Path tracing costs n_P · ⌈(cv/ε)²⌉ · s per path per frame, with the
//! cv and seconds per path the frames run measured in the moving scene.

use super::fronts::DetpErrors;
use super::input::{keys, Csv};
use crate::error::OutputError;
use crate::experiment::quasi_static::columns::{
    FRAME0_S, FRAME_S, FULL_FRAME_S, PATH_TRACING_CV, PATH_TRACING_S_PER_PATH, POINTS_DYNAMIC,
    POINTS_STATIC,
};
use crate::output::column::POINT;
use crate::stats::fit::{CostModel, ErrorFit};
use crate::stats::time_to_target::{frames_crossover, Crossover, PathTracingCost};

/// One frames row, as read.
#[derive(Clone, Debug, PartialEq)]
pub struct FramesInput {
    /// Its sweep point.
    pub point: u64,
    /// n_P (static + dynamic).
    pub points: f64,
    /// Its detp.disc_radius (NaN if the table has none).
    pub disc_radius: f64,
    /// Its detp.photons.
    pub photons: f64,
    /// Frame 0's seconds.
    pub first_s: f64,
    /// An incremental frame's seconds.
    pub frame_s: f64,
    /// A full recalculation's seconds.
    pub full_s: f64,
    /// Path tracing's seconds per path.
    pub s_per_path: f64,
    /// Path tracing's cv.
    pub cv: f64,
}

/// Reads the frames table's rows (every column needed, or an error naming the missing one).
pub fn read_frames(main: &Csv) -> Result<Vec<FramesInput>, OutputError> {
    frames_columns(main).map_err(|mut e| {
        e.message.push_str(
            " (the frames analysis reads a run of kind quasi-static with engine path-tracing)",
        );
        e
    })
}

/// [`read_frames`] without the context its errors get.
fn frames_columns(main: &Csv) -> Result<Vec<FramesInput>, OutputError> {
    let (point, photons) = (main.value(&POINT)?, main.param(keys::PHOTONS)?);
    let (st, dy) = (main.value(&POINTS_STATIC)?, main.value(&POINTS_DYNAMIC)?);
    let (first, frame, full) = (
        main.value(&FRAME0_S)?,
        main.value(&FRAME_S)?,
        main.value(&FULL_FRAME_S)?,
    );
    let (spp, cv) = (
        main.value(&PATH_TRACING_S_PER_PATH)?,
        main.value(&PATH_TRACING_CV)?,
    );
    let d = if main.has_param(keys::DISC_RADIUS) {
        main.param(keys::DISC_RADIUS)?
    } else {
        vec![f64::NAN; point.len()]
    };
    Ok((0..point.len())
        .map(|i| FramesInput {
            point: point[i] as u64,
            points: st[i] + dy[i],
            disc_radius: d[i],
            photons: photons[i],
            first_s: first[i],
            frame_s: frame[i],
            full_s: full[i],
            s_per_path: spp[i],
            cv: cv[i],
        })
        .collect())
}

/// One row of `frames.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct FramesRow {
    /// Scene (of the fronts).
    pub scene: String,
    /// Target.
    pub target: f64,
    /// The frames table's sweep point.
    pub frames_point: u64,
    /// n_P.
    pub points: f64,
    /// The frames table's d.
    pub disc_radius: f64,
    /// The fronts' d whose error fit gave N_ε.
    pub fronts_disc_radius: f64,
    /// N_ε (NaN: unreachable).
    pub photons: f64,
    /// DETP's first frame at N_ε.
    pub first_s: f64,
    /// An incremental frame at N_ε.
    pub frame_s: f64,
    /// A full frame at N_ε.
    pub full_s: f64,
    /// Path tracing's paths per point.
    pub path_tracing_paths: f64,
    /// Path tracing's seconds per frame.
    pub path_tracing_frame_s: f64,
    /// F* (NaN: never).
    pub frames_star: f64,
    /// F* of full recalculation (NaN: never).
    pub frames_star_full: f64,
    /// Why something is NaN, and which d was used.
    pub reason: String,
}

/// The fronts' configuration the quasi-static layer runs (direct photons, edge paper, a fixed d)
/// nearest `d`.
fn nearest_paper(detp: &[DetpErrors], d: f64) -> Option<&DetpErrors> {
    let paper = detp.iter().filter(|e| {
        e.config.direct.as_deref() == Some("photons")
            && e.config.edge.as_deref() == Some("paper")
            && e.config.radius_rule.unwrap_or_default() == Default::default()
    });
    let gap = |e: &DetpErrors| {
        let x = e.config.disc_radius.unwrap_or(f64::NAN);
        if d.is_finite() {
            (x - d).abs()
        } else {
            x
        }
    };
    paper.min_by(|a, b| gap(a).total_cmp(&gap(b)))
}

/// `column`'s seconds at `n` photons among the rows with `row`'s points (see the module doc).
fn scaled(rows: &[FramesInput], row: &FramesInput, n: f64, column: fn(&FramesInput) -> f64) -> f64 {
    let same: Vec<(f64, f64, f64)> = rows
        .iter()
        .filter(|r| r.points == row.points && column(r).is_finite())
        .map(|r| (r.photons, 0.0, column(r)))
        .collect();
    let mut counts: Vec<f64> = same.iter().map(|s| s.0).collect();
    counts.sort_by(f64::total_cmp);
    counts.dedup();
    if counts.len() >= 2 {
        CostModel::fit(&same, 1.0).seconds(n, 0.0)
    } else {
        column(row) * n / row.photons
    }
}

/// Every row of `frames.csv`.
pub fn frames_rows(
    scene: &str,
    detp: &[DetpErrors],
    rows: &[FramesInput],
    targets: &[f64],
) -> Vec<FramesRow> {
    let mut out = Vec::new();
    for &target in targets {
        for row in rows {
            out.push(frames_row(scene, detp, rows, row, target));
        }
    }
    out
}

fn frames_row(
    scene: &str,
    detp: &[DetpErrors],
    rows: &[FramesInput],
    row: &FramesInput,
    target: f64,
) -> FramesRow {
    let pt = PathTracingCost {
        cv: row.cv,
        seconds_per_path: row.s_per_path,
    };
    let mut r = FramesRow {
        scene: scene.to_string(),
        target,
        frames_point: row.point,
        points: row.points,
        disc_radius: row.disc_radius,
        fronts_disc_radius: f64::NAN,
        photons: f64::NAN,
        first_s: f64::NAN,
        frame_s: f64::NAN,
        full_s: f64::NAN,
        path_tracing_paths: pt.paths_for(target) as f64,
        path_tracing_frame_s: pt.seconds(row.points, target),
        frames_star: f64::NAN,
        frames_star_full: f64::NAN,
        reason: String::new(),
    };
    let Some(e) = nearest_paper(detp, row.disc_radius) else {
        r.reason = "the fronts have no configuration with direct = photons, edge = paper".into();
        return r;
    };
    let fd = e.config.disc_radius.unwrap_or(f64::NAN);
    r.fronts_disc_radius = fd;
    let mut why = Vec::new();
    if !(fd == row.disc_radius) {
        why.push(format!(
            "errors at the fronts' nearest d = {fd} (frames d = {})",
            row.disc_radius
        ));
    }
    let reps = e.mse.len() as f64;
    let mean: Vec<f64> = (0..e.photons.len())
        .map(|j| e.mse.iter().map(|m| m[j]).sum::<f64>() / reps)
        .collect();
    let fit = ErrorFit::fit_relative(&e.photons, &mean);
    match fit.photons_for(target) {
        None => why.push(format!(
            "error floor √B = {:.4} ≥ target {target}",
            fit.floor()
        )),
        Some(n) => {
            r.photons = n;
            r.first_s = scaled(rows, row, n, |x| x.first_s);
            r.frame_s = scaled(rows, row, n, |x| x.frame_s);
            r.full_s = scaled(rows, row, n, |x| x.full_s);
            let pt_s = r.path_tracing_frame_s;
            match frames_crossover(r.first_s, r.frame_s, pt_s) {
                Crossover::At(f) => r.frames_star = f,
                Crossover::Never(_) => {
                    why.push("incremental frame not below path tracing's frame".into())
                }
            }
            match frames_crossover(r.full_s, r.full_s, pt_s) {
                Crossover::At(f) => r.frames_star_full = f,
                Crossover::Never(_) => why.push("full frame not below path tracing's frame".into()),
            }
        }
    }
    r.reason = why.join("; ");
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crossover::method::{Config, Method};

    /// A synthetic frames table (two photon counts at one n_P, seconds exactly linear in N) and a
    /// fronts fit with MSE exactly c/N: the seconds at N_ε are the line's, F* the closed form.
    #[test]
    fn frames_star_follows_from_the_scaled_seconds() {
        let csv_text = "point,detp.photons,detp.disc_radius,points_static,points_dynamic,frame0_s,frame_s_mean,full_frame_s_mean,path_tracing_s_per_path_mean,path_tracing_cv_mean\n\
                        0,1000,5,900,100,1.1,0.11,1.0,1e-6,3\n\
                        1,2000,5,900,100,2.1,0.21,2.0,1e-6,3\n";
        let main = Csv::from_text(csv_text);
        let rows = read_frames(&main).expect("frames");
        let photons = vec![1e3, 1e4, 1e5];
        let detp = vec![DetpErrors {
            config: Config {
                method: Method::named("sphere-cache").unwrap(),
                direct: Some("photons".into()),
                edge: Some("paper".into()),
                disc_radius: Some(10.0),
                radius_rule: Some(Default::default()),
            },
            mse: vec![photons.iter().map(|n| 10.0 / n).collect(); 2],
            photons,
        }];
        let out = frames_rows("s", &detp, &rows, &[0.1]);
        assert_eq!(out.len(), 2);
        let r = &out[0];
        let n = 10.0 / 0.01;
        assert!((r.photons / n - 1.0).abs() < 1e-6, "{}", r.photons);
        // first = 0.1 + 1e-3·N, frame = 0.01 + 1e-4·N, full = 1e-3·N.
        assert!((r.first_s - (0.1 + 1e-3 * n)).abs() < 1e-6, "{r:?}");
        assert!((r.frame_s - (0.01 + 1e-4 * n)).abs() < 1e-6);
        let pt = 1000.0 * 900.0 * 1e-6;
        assert!((r.path_tracing_frame_s - pt).abs() < 1e-12);
        let closed = (r.first_s - r.frame_s) / (pt - r.frame_s);
        assert!((r.frames_star - closed).abs() < 1e-9);
        // A full frame (1 s) is above path tracing's 0.9 s: never.
        assert!(r.frames_star_full.is_nan() && r.reason.contains("full frame"));
        assert!(r.reason.contains("nearest d = 10"), "{}", r.reason);
        // Missing columns are named.
        let mut bad = main.clone();
        bad.columns[9] = "other".into();
        let e = read_frames(&bad).expect_err("missing");
        assert!(e.message.contains("path_tracing_cv_mean"), "{e}");
    }
}
