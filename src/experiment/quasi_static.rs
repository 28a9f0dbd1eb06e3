//! Kind `quasi-static`: one point runs F frames of a scene whose dynamic objects move. Frame 0 is a
//! full photon trace; every later frame is recalculated incrementally
//! ([`crate::detp::quasi_static`]) and, every `dynamic.check_every` frames, against a full
//! recalculation of the same frame: `full_mismatch` counts the points whose sums differ (0 when
//! correct) and `full_frame_s` times it.
//!
//! Columns: the counts of frame 0 (`segments`, `points_static`, `points_dynamic`), the objects'
//! `ratio` r_D/r_0 and the engine each used; per-frame estimates over frames 1…F−1 (`_mean/_se/_n`;
//! consecutive frames are correlated, so the standard error is over batches of consecutive frames):
//! `retraced_rays` (segments meeting an object at its old or new pose) and `rays_meeting_object` (at
//! the new pose) beside f_R = n_R·Σ(r_D/r_0)² (`retraced_rays_theory`), photons and segments
//! re-traced, the search's tests, the static and dynamic points' tests, each phase's seconds,
//! `frame_s` and `full_frame_s`; the theory of Theorem 2 for the same n: the static points' costs
//! (2 vs 8.08·t·f_R·∛n_S) and the dynamic points' (sphere cache vs disc index). Side tables: `frames`
//! (one row per frame) and, with `detp.write_points`, `points` (the irradiance at one frame).

use crate::detp::fixed::Acc;
use crate::detp::order::Order;
use crate::detp::quasi_static::{
    mismatches, Engine, FrameStats, IndexKind, Params, QuasiStatic, Used,
};
use crate::detp::sphere_cache::{ListMode, SphereCacheParams};
use crate::lt::Scene;
use crate::spec::detp::{DynamicEngine, IndexChoice, ListModeChoice, OrderChoice, Points, Rays};
use crate::spec::quasi_static::{apply_ratio, QuasiStaticConfig};
use crate::stats::{ClusteredMean, Estimate};
use crate::theory::detp as th;

use super::metric::{Metric, Theory};
use super::{PointResult, Row};

/// The run's settings from a validated config (the scene comes loaded and scaled).
pub fn params(cfg: &QuasiStaticConfig, n_dynamic_points: f64) -> Params {
    let d = &cfg.detp;
    let Points::Surface(spacing) = d.points else {
        unreachable!("the spec check allows surface points only")
    };
    Params {
        photons: d.photons,
        // Common random numbers: every point of a sweep traces the same photon streams (keyed by the
        // seed alone), so engines and ratios are compared on identical photons; a point's
        // results still depend only on its own parameters, never on threads or shards.
        seed: crate::sample::rng::hash_key(&[d.seed, 0x7173]),
        frames: cfg.frames,
        disc_radius: d.disc_radius,
        spacing,
        engine: match cfg.engine {
            DynamicEngine::Hybrid => Engine::Hybrid,
            DynamicEngine::SphereCache => Engine::SphereCache,
            DynamicEngine::DiscIndex => Engine::DiscIndex,
            // Frame 0 runs by Theorem 2's rule; the predictor then picks (see `run_point`).
            DynamicEngine::Predicted => Engine::Hybrid,
        },
        crossover: cfg
            .crossover
            .unwrap_or_else(|| th::crossover_ratio(d.q, n_dynamic_points.max(1.0))),
        cache: SphereCacheParams {
            q: d.q,
            threshold: d.threshold as usize,
            list_mode: match d.list_mode {
                ListModeChoice::Exact => ListMode::Exact,
                ListModeChoice::Inherited => ListMode::Inherited,
            },
            chunk_points: d.chunk_points as usize,
            law_ball: None,
        },
        order: match d.order {
            OrderChoice::None => Order::None,
            OrderChoice::Morton => Order::Morton,
            OrderChoice::Hilbert => Order::Hilbert,
        },
        index: match d.index {
            IndexChoice::Grid => IndexKind::Grid(d.index_cell_width),
            IndexChoice::Octree => IndexKind::Octree(d.octree_leaf as usize),
        },
    }
}

/// The scene of a point, scaled to the spec's r_D/r_0.
pub fn scene(cfg: &QuasiStaticConfig) -> anyhow::Result<Scene> {
    let Rays::Scene(p) = &cfg.detp.rays else {
        anyhow::bail!("kind quasi-static needs a scene (the spec check refuses this)")
    };
    let mut s = Scene::load(p).map_err(|e| anyhow::anyhow!("{e}"))?;
    apply_ratio(&mut s, cfg.ratio);
    Ok(s)
}

/// Starts a run: the scene, frame 0 and its stats.
pub fn start(cfg: &QuasiStaticConfig) -> anyhow::Result<(QuasiStatic, FrameStats)> {
    let scene = scene(cfg)?;
    // n_D for Theorem 2's finite-n crossover: the dynamic points of the first object, estimated
    // from its area (the run counts them exactly afterwards).
    let Points::Surface(spacing) = cfg.detp.points else {
        unreachable!()
    };
    let n_d = scene
        .movers
        .first()
        .map(|m| {
            let area: f64 = m.posed(0.0).triangles.iter().map(|t| t.area()).sum::<f64>()
                + m.posed(0.0).balls.iter().map(|b| b.area()).sum::<f64>();
            area / (spacing * spacing)
        })
        .unwrap_or(1.0);
    let p = params(cfg, n_d);
    Ok(QuasiStatic::start(scene, p))
}

/// Frames per cluster of the per-frame estimates: 16 batches of consecutive frames (or one frame
/// each when there are fewer than 32).
fn batch(frames: u32) -> u32 {
    if frames <= 32 {
        1
    } else {
        (frames - 1).div_ceil(16)
    }
}

/// One quasi-static point.
pub fn run_point(
    cfg: &QuasiStaticConfig,
    _point: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> anyhow::Result<PointResult> {
    for w in &cfg.warnings {
        eprintln!("warning: point {_point}: {w}");
    }
    let (mut qs, f0) = start(cfg)?;
    progress(cfg.detp.photons);
    let predictions = cfg.predict.map(|fraction| {
        let rule: Vec<Used> = (0..qs.scene.movers.len())
            .map(|m| qs.rule_engine(m))
            .collect();
        let p = qs.predict_and_pick(fraction, cfg.engine == DynamicEngine::Predicted);
        (fraction, p, rule)
    });
    let (r_c, r0) = qs.root();
    let _ = r_c;
    let n_r = qs.live_segments() as f64;
    let ratios: Vec<f64> = qs.scene.movers.iter().map(|m| m.radius() / r0).collect();
    let f_r: f64 = ratios.iter().map(|&r| th::retraced_rays(n_r, r)).sum();
    let (n_s, n_dyn) = qs.point_counts();
    let n_d: usize = n_dyn.iter().sum();
    let b = batch(cfg.frames);
    let names = [
        "retraced_rays",
        "rays_meeting_object",
        "photons_retraced",
        "segments_retraced",
        "segments_changed",
        "search_tests",
        "search_cells",
        "static_tests",
        "dynamic_tests",
        "dynamic_sphere_tests",
        "search_s",
        "retrace_s",
        "static_s",
        "dynamic_s",
        "frame_s",
    ];
    let mut means: Vec<ClusteredMean> = vec![ClusteredMean::default(); names.len()];
    let mut full_s = ClusteredMean::default();
    let (mut full_mismatch, mut full_checked) = (0u64, 0u64);
    let mut frame_rows = vec![frame_row(&f0, None)];
    let points_frame = cfg.points_frame.unwrap_or(cfg.frames - 1);
    let mut points_at: Option<(Vec<Acc>, crate::detp::disc::Discs)> = None;
    if points_frame == 0 && cfg.detp.write_points {
        points_at = Some((qs.sums(), qs.discs()));
    }
    for f in 1..cfg.frames {
        let st = qs.step(f);
        progress(cfg.detp.photons);
        let values = [
            st.affected_segments as f64,
            st.meeting_new as f64,
            st.photons_retraced as f64,
            st.segments_retraced as f64,
            st.segments_added as f64,
            st.search.tested as f64,
            st.search.cells as f64,
            st.static_disc_tests as f64 + st.static_sphere_tests as f64,
            st.dynamic_disc_tests as f64,
            st.dynamic_sphere_tests as f64,
            st.search_s,
            st.retrace_s,
            st.static_s,
            st.dynamic_s,
            st.frame_s,
        ];
        for (m, v) in means.iter_mut().zip(values) {
            m.push(v);
        }
        let check =
            cfg.check_every > 0 && (u64::from(f) % cfg.check_every == 0 || f == cfg.frames - 1);
        let full = check.then(|| {
            let (sums, _, s) = qs.full_recalculation();
            let bad = mismatches(&qs.sums(), &sums);
            full_mismatch += bad;
            full_checked += 1;
            full_s.push(s);
            (s, bad)
        });
        if f % b == 0 || f == cfg.frames - 1 {
            means.iter_mut().for_each(ClusteredMean::end_batch);
            full_s.end_batch();
        }
        frame_rows.push(frame_row(&st, full));
        if f == points_frame && cfg.detp.write_points {
            points_at = Some((qs.sums(), qs.discs()));
        }
    }
    // Error of the last frame against a high-photon reference (relative RMSE over the points; the
    // reference's own noise is part of it, a floor of about 1/√(crossings per disc) of the reference).
    let reference = cfg.reference_photons.map(|n| {
        let mine = qs.irradiance();
        let t = std::time::Instant::now();
        let refr = qs.reference_irradiance(
            n,
            crate::sample::rng::hash_key(&[cfg.detp.seed, 0x7265_6665]),
        );
        let ref_s = t.elapsed().as_secs_f64();
        let mean_ref = refr.iter().sum::<f64>() / refr.len().max(1) as f64;
        let mse = mine
            .iter()
            .zip(&refr)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            / mine.len().max(1) as f64;
        (mse.sqrt() / mean_ref, ref_s, n)
    });
    let est: Vec<Estimate> = means.iter().map(ClusteredMean::estimate).collect();
    let get = |name: &str| est[names.iter().position(|n| *n == name).expect("a metric")];

    let mut row = Row::default();
    let used: Vec<&str> = f0.used.iter().map(|u| u.as_str()).collect();
    row.u("frames", u64::from(cfg.frames))
        .u("photons", cfg.detp.photons)
        .u("segments", n_r as u64)
        .u("points_static", n_s as u64)
        .u("points_dynamic", n_d as u64)
        .u("objects", ratios.len() as u64)
        .f("r0", r0)
        .f("ratio", ratios.iter().copied().fold(0.0, f64::max))
        .f("crossover", qs.params().crossover)
        .s("engine_used", used.join("+"))
        .u("warnings", cfg.warnings.len() as u64);
    let mut summary = Vec::new();
    Metric::new(
        "retraced_rays",
        get("retraced_rays"),
        Theory::Prediction(f_r),
    )
    .write(&mut row, &mut summary);
    Metric::new(
        "rays_meeting_object",
        get("rays_meeting_object"),
        Theory::Prediction(f_r),
    )
    .write(&mut row, &mut summary);
    // The rest of the per-frame estimates (the first two carry theory columns, above).
    for n in &names[2..] {
        row.estimate(n, &get(n));
    }
    let full = full_s.estimate();
    row.estimate("full_frame_s", &full)
        .f("frame0_s", f0.frame_s)
        .f("static_index_build_s", qs.static_index_build_s)
        .f("speedup", full.mean / get("frame_s").mean)
        .u("full_mismatch", full_mismatch)
        .u("full_checked", full_checked);
    if let Some((fraction, preds, rule)) = &predictions {
        // The first object's figures; picks are counted over all objects.
        let p = preds[0];
        let name = |u: Used| u.as_str();
        row.f("predict_fraction", *fraction)
            .f("predicted_sphere_cache_s", p.predicted[0])
            .f("predicted_disc_index_s", p.predicted[1])
            .f("measured_sphere_cache_s", p.measured[0])
            .f("measured_disc_index_s", p.measured[1])
            .f(
                "timed_prediction_error_sphere_cache",
                p.predicted[0] / p.measured[0] - 1.0,
            )
            .f(
                "timed_prediction_error_disc_index",
                p.predicted[1] / p.measured[1] - 1.0,
            )
            .s("timed_pick", name(p.pick))
            .s("timed_best_engine", name(p.best))
            .u(
                "timed_pick_right",
                preds.iter().filter(|p| p.pick == p.best).count() as u64,
            )
            .u(
                "timed_rule_pick_right",
                preds
                    .iter()
                    .zip(rule)
                    .filter(|(p, r)| p.best == **r)
                    .count() as u64,
            );
    }
    if let Some((rmse, ref_s, n)) = reference {
        row.f("irradiance_rmse", rmse)
            .u("reference_photons", n)
            .f("reference_s", ref_s);
    }
    // Theorem 2 for this run's n (costs in ray tests, t = u).
    let q = cfg.detp.q;
    let (sc_static, di_static) = th::static_points_cost(f_r, n_s as f64, q);
    let (sc_dyn, di_dyn) =
        th::dynamic_points_cost(n_r, ratios.first().copied().unwrap_or(0.0), n_d as f64, q);
    row.f("static_tests_theory_sphere_cache", sc_static)
        .f("static_tests_theory_disc_index", di_static)
        .f("dynamic_tests_theory_sphere_cache", sc_dyn)
        .f("dynamic_tests_theory_disc_index", di_dyn)
        .f(
            "crossover_theory",
            th::crossover_ratio(q, n_d.max(1) as f64),
        );
    summary.push((
        "full_mismatch".into(),
        Estimate {
            mean: full_mismatch as f64,
            se: 0.0,
            n: full_checked,
            clusters: full_checked,
        },
        "0 (incremental = full recalculation)".into(),
        if full_mismatch == 0 {
            "ok (exact)"
        } else {
            "FAIL"
        }
        .into(),
    ));
    summary.push((
        "speedup".into(),
        Estimate {
            mean: full.mean / get("frame_s").mean,
            se: f64::NAN,
            n: full_checked,
            clusters: 1,
        },
        "full_frame_s / frame_s".into(),
        format!("{:.1}× faster", full.mean / get("frame_s").mean),
    ));
    let point_rows = points_at
        .map(|(sums, discs)| points_table(&qs, &sums, &discs, points_frame, n_s))
        .unwrap_or_default();
    if full_mismatch != 0 {
        anyhow::bail!(
            "incremental ≠ full recalculation at {full_mismatch} point(s) over {full_checked} checked frame(s)"
        );
    }
    Ok(PointResult {
        row,
        tables: vec![("frames", frame_rows), ("points", point_rows)],
        summary,
        rays_per_s: get("segments_retraced").mean / get("frame_s").mean.max(1e-12),
    })
}

/// One row of the frames table.
fn frame_row(st: &FrameStats, full: Option<(f64, u64)>) -> Row {
    let mut r = Row::default();
    let used: Vec<&str> = st.used.iter().map(|u| u.as_str()).collect();
    r.u("frame", u64::from(st.frame))
        .u("retraced_rays", st.affected_segments)
        .u("rays_meeting_object", st.meeting_new)
        .u("photons_retraced", st.photons_retraced)
        .u("segments_removed", st.segments_removed)
        .u("segments_added", st.segments_added)
        .u("segments_retraced", st.segments_retraced)
        .u("search_cells", st.search.cells)
        .u("search_listings", st.search.listings)
        .u("search_tests", st.search.tested)
        .u("static_disc_tests", st.static_disc_tests)
        .u("static_sphere_tests", st.static_sphere_tests)
        .u("dynamic_disc_tests", st.dynamic_disc_tests)
        .u("dynamic_sphere_tests", st.dynamic_sphere_tests)
        .s("engine_used", used.join("+"))
        .f("search_s", st.search_s)
        .f("retrace_s", st.retrace_s)
        .f("static_s", st.static_s)
        .f("dynamic_s", st.dynamic_s)
        .f("frame_s", st.frame_s)
        .f("full_frame_s", full.map_or(f64::NAN, |f| f.0))
        .s(
            "full_mismatch",
            full.map_or(String::new(), |f| f.1.to_string()),
        );
    r
}

/// The irradiance at every sample point at one frame, with its Poisson standard error
/// (√(E·w̄/πd²), w̄ the mean segment power).
fn points_table(
    qs: &QuasiStatic,
    sums: &[Acc],
    discs: &crate::detp::disc::Discs,
    frame: u32,
    n_static: usize,
) -> Vec<Row> {
    let d = qs.params().disc_radius;
    let area = std::f64::consts::PI * d * d;
    let scale = qs.scale();
    let store = qs.live_store();
    let w = if store.is_empty() {
        0.0
    } else {
        store
            .segments
            .iter()
            .map(|s| scale.watts(Acc::from(s.power)))
            .sum::<f64>()
            / store.len() as f64
    };
    (0..discs.len())
        .map(|i| {
            let e = scale.watts(sums[i]) / area;
            let (c, n) = (discs.centers[i], discs.normals[i]);
            let mut r = Row::default();
            r.u("sample", i as u64)
                .u("frame", u64::from(frame))
                .u("dynamic", u64::from(i >= n_static))
                .f("x", c.x)
                .f("y", c.y)
                .f("z", c.z)
                .f("nx", n.x)
                .f("ny", n.y)
                .f("nz", n.z)
                .f("irradiance_mean", e)
                .f("irradiance_se", (e.max(0.0) * w / area).sqrt());
            r
        })
        .collect()
}

/// One line for `raycost check`.
pub fn describe(cfg: &QuasiStaticConfig) -> String {
    let warnings: String = cfg
        .warnings
        .iter()
        .map(|w| format!("\n      warning: {w}"))
        .collect();
    format!(
        "{}; {} frames, r_D/r_0 {}, engine {}, full check every {} frame(s){warnings}",
        super::detp::describe(&cfg.detp),
        cfg.frames,
        cfg.ratio
            .map_or("as in the scene".to_string(), |r| format!("{r}")),
        cfg.engine.as_str(),
        cfg.check_every
    )
}
