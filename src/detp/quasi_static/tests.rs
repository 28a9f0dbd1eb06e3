//! Incremental = full, bit for bit, frame after frame; the search finds every affected photon.

use super::*;
use crate::lt::Scene;

pub(super) fn scene() -> Scene {
    let p = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/experiments/scenes/cornell-dynamic.toml"
    );
    Scene::load(std::path::Path::new(p)).expect("the dynamic Cornell box loads")
}

pub(super) fn params(engine: Engine, photons: u64, frames: u32) -> Params {
    Params {
        photons,
        seed: 11,
        frames,
        disc_radius: 20.0,
        spacing: 40.0,
        engine,
        crossover: crate::theory::detp::crossover_ratio(2.0 / 3.0, f64::INFINITY),
        cache: SphereCacheParams {
            threshold: 16,
            chunk_points: 256,
            ..Default::default()
        },
        order: Order::Hilbert,
        index: if engine == Engine::DiscIndex {
            IndexKind::Octree(8)
        } else {
            IndexKind::Grid(40.0)
        },
        feed: Feed::Paper,
        time_traversal: false,
    }
}

/// Steps through `frames` frames and checks every one against a full recalculation: the sums, and
/// the live segments themselves (photon by photon, bit for bit).
fn check_frames(engine: Engine, photons: u64, frames: u32, every: u32) -> (u64, u64) {
    let (mut qs, first) = QuasiStatic::start(scene(), params(engine, photons, frames));
    assert_eq!(first.photons_retraced, photons);
    let (mut retraced, mut changed) = (0, 0);
    let mut before = qs.sums();
    for f in 1..frames {
        let st = qs.step(f);
        assert!(
            st.photons_retraced < photons,
            "frame {f}: the search re-traced everything"
        );
        retraced += st.photons_retraced;
        if f % every == 0 || f == frames - 1 {
            let (full, store, _) = qs.full_recalculation();
            let live = qs.live_store();
            assert_eq!(
                live.segments, store.segments,
                "frame {f}: live segments differ from a full trace"
            );
            assert_eq!(
                mismatches(&qs.sums(), &full),
                0,
                "frame {f}: incremental ≠ full"
            );
        }
        let now = qs.sums();
        changed += mismatches(
            &now[..qs.static_discs.len()],
            &before[..qs.static_discs.len()],
        );
        before = now;
    }
    (retraced, changed)
}

#[test]
fn incremental_equals_full_over_1000_frames() {
    let (retraced, changed) = check_frames(Engine::Hybrid, 1500, 1000, 1);
    // Not a vacuous check: photons were re-traced and static points did change.
    assert!(
        retraced > 1000,
        "only {retraced} photons re-traced in 1000 frames"
    );
    assert!(changed > 100, "static sums changed only {changed} times");
}

#[test]
fn every_engine_is_exact() {
    for engine in [Engine::SphereCache, Engine::DiscIndex, Engine::Hybrid] {
        check_frames(engine, 3000, 24, 1);
    }
}

#[test]
fn frames_can_be_visited_in_any_order() {
    // Poses are pure functions of τ: jumping around gives the same sums as a full trace.
    let (mut qs, _) = QuasiStatic::start(scene(), params(Engine::Hybrid, 2000, 50));
    for f in [37, 3, 49, 0, 12] {
        qs.step(f);
        let (full, ..) = qs.full_recalculation();
        assert_eq!(mismatches(&qs.sums(), &full), 0, "frame {f}");
    }
}

#[test]
fn hybrid_picks_by_ratio() {
    let mut s = scene();
    for m in &mut s.movers {
        m.scale = 0.9 * 0.35 * 900.0 / m.rest_radius; // below the crossover for r_0 ≈ 900
    }
    let (qs, st) = QuasiStatic::start(s, params(Engine::Hybrid, 500, 4));
    let r0 = qs.root().1;
    for (m, used) in qs.scene.movers.iter().zip(&st.used) {
        let ratio = m.radius() / r0;
        let want = if ratio < qs.params().crossover {
            Used::SphereCache
        } else {
            Used::DiscIndex
        };
        assert_eq!(*used, want, "ratio {ratio}");
    }
    assert!(st.used.contains(&Used::SphereCache) || st.used.contains(&Used::DiscIndex));
}

#[test]
fn the_predictor_picks_a_measured_engine_and_stays_exact() {
    let (mut qs, _) = QuasiStatic::start(scene(), params(Engine::Hybrid, 3000, 10));
    let preds = qs.predict_and_pick(0.25, Predictor::Subsample, true);
    assert_eq!(preds.len(), qs.scene.movers.len());
    for p in &preds {
        assert!(p
            .predicted
            .iter()
            .chain(&p.measured)
            .all(|&s| s > 0.0 && s.is_finite()));
        let faster = if p.measured[0] <= p.measured[1] {
            Used::SphereCache
        } else {
            Used::DiscIndex
        };
        assert_eq!(p.best, faster);
    }
    let st = qs.step(5);
    assert_eq!(st.used, preds.iter().map(|p| p.pick).collect::<Vec<_>>());
    let (full, ..) = qs.full_recalculation();
    assert_eq!(mismatches(&qs.sums(), &full), 0);
}

/// Every feed gives both engines the same sums (incremental = full, and sphere cache = disc index
/// on every point), and the feed changes what the disc index traverses: the segment index's answer
/// is a fraction of all segments.
#[test]
fn every_feed_gives_both_engines_the_same_sums() {
    let frames = 5;
    let mut traversal = Vec::new();
    for feed in [Feed::Paper, Feed::SegmentIndex, Feed::All] {
        let mut sums = Vec::new();
        for engine in [Engine::SphereCache, Engine::DiscIndex] {
            let p = Params {
                feed,
                ..params(engine, 3000, frames)
            };
            let (mut qs, _) = QuasiStatic::start(scene(), p);
            let (mut trav, mut fed) = (0, 0);
            for f in 1..frames {
                let st = qs.step(f);
                trav += st.dynamic_traversal;
                fed += st.dynamic_feed;
                if engine == Engine::DiscIndex {
                    assert!(st.dynamic_traversal > 0 && st.dynamic_sphere_tests == 0);
                } else {
                    assert!(st.dynamic_rays_copied > 0 && st.dynamic_traversal == 0);
                }
            }
            let (full, ..) = qs.full_recalculation();
            assert_eq!(mismatches(&qs.sums(), &full), 0, "{feed:?} {engine:?}");
            let fed_expected = !matches!(
                (feed, engine),
                (Feed::All, _) | (Feed::Paper, Engine::DiscIndex)
            );
            assert_eq!(fed > 0, fed_expected, "{feed:?} {engine:?}: feed {fed}");
            if engine == Engine::DiscIndex {
                traversal.push(trav);
            }
            sums.push(qs.sums());
        }
        assert_eq!(sums[0], sums[1], "{feed:?}: the engines disagree");
        assert!(sums[0].iter().any(|&a| a != 0));
    }
    // Paper and all: every segment traverses the index; segment-index: only those fed.
    assert_eq!(traversal[0], traversal[2]);
    assert!(traversal[1] * 2 < traversal[2], "traversal {traversal:?}");
}

/// `--photon-shard` at the core: three disjoint photon ranges, each run frame by frame on its own
/// (its own segment index, sized and compacted by its own segments), add up to the whole run —
/// every point's sum and every count that is not the segment index's work, at every frame, for
/// both feeds that give the disc index something different.
#[test]
fn photon_ranges_add_up_to_the_whole_run_frame_by_frame() {
    let (photons, frames) = (2400, 6);
    for feed in [Feed::Paper, Feed::SegmentIndex] {
        let p = Params {
            feed,
            ..params(Engine::DiscIndex, photons, frames)
        };
        let (mut whole, w0) = QuasiStatic::start(scene(), p.clone());
        let mut parts: Vec<(QuasiStatic, FrameStats)> = [0..700, 700..1650, 1650..photons]
            .into_iter()
            .map(|ids| QuasiStatic::start_photons(scene(), p.clone(), ids))
            .collect();
        let additive = |s: &FrameStats| {
            [
                s.affected_segments,
                s.meeting_new,
                s.photons_retraced,
                s.segments_removed,
                s.segments_added,
                s.segments_retraced,
                s.static_disc_tests,
                s.static_traversal,
                s.dynamic_disc_tests,
                s.dynamic_traversal,
            ]
        };
        let check =
            |f: u32, whole: &QuasiStatic, w: &FrameStats, parts: &[(QuasiStatic, FrameStats)]| {
                let mut sums = vec![0; whole.sums().len()];
                for (qs, _) in parts {
                    for (a, b) in sums.iter_mut().zip(qs.sums()) {
                        *a += b;
                    }
                }
                assert_eq!(sums, whole.sums(), "{feed:?} frame {f}: the ranges' sums");
                let total = parts[1..]
                    .iter()
                    .try_fold(parts[0].1.clone(), |a, (_, s)| a.add(s))
                    .expect("the same frame and engines");
                assert_eq!(additive(&total), additive(w), "{feed:?} frame {f}: counts");
                assert_eq!(total.used, w.used);
            };
        check(0, &whole, &w0, &parts);
        let mut retraced = 0;
        for f in 1..frames {
            let w = whole.step(f);
            retraced += w.photons_retraced;
            for (qs, st) in &mut parts {
                *st = qs.step(f);
            }
            check(f, &whole, &w, &parts);
        }
        assert!(
            retraced > 0,
            "no photon was re-traced: the check is vacuous"
        );
        // A range's full recalculation is its share of the whole run's.
        let mut full = vec![0; whole.sums().len()];
        for (qs, _) in &parts {
            let (sums, ..) = qs.full_recalculation();
            assert_eq!(mismatches(&qs.sums(), &sums), 0);
            for (a, b) in full.iter_mut().zip(sums) {
                *a += b;
            }
        }
        assert_eq!(full, whole.sums());
    }
}

/// The frame's stats without its seconds (every count, the engines used).
fn counts_only(s: &FrameStats) -> FrameStats {
    FrameStats {
        search_s: 0.0,
        retrace_s: 0.0,
        static_s: 0.0,
        dynamic_s: 0.0,
        dynamic_traversal_s: 0.0,
        frame_s: 0.0,
        ..s.clone()
    }
}

/// Timing the disc index's traversal alone (`Params::time_traversal`) is a second walk beside the
/// frame's: every sum and every count stay those of a run without it, frame by frame, for each
/// feed the disc index can get; its seconds are positive wherever the disc index gathers the
/// dynamic points (frame 0 included), 0 with the sphere cache, NaN when not timed.
#[test]
fn timing_the_traversal_alone_changes_no_sum_or_count() {
    let frames = 4;
    for (engine, feed) in [
        (Engine::DiscIndex, Feed::Paper),
        (Engine::DiscIndex, Feed::SegmentIndex),
        (Engine::SphereCache, Feed::Paper),
    ] {
        let run = |time_traversal: bool| {
            let p = Params {
                feed,
                time_traversal,
                ..params(engine, 2000, frames)
            };
            let (mut qs, f0) = QuasiStatic::start(scene(), p);
            let mut out = vec![(f0, qs.sums())];
            for f in 1..frames {
                let st = qs.step(f);
                out.push((st, qs.sums()));
            }
            out
        };
        let (plain, timed) = (run(false), run(true));
        for ((p, p_sums), (t, t_sums)) in plain.iter().zip(&timed) {
            let at = format!("{engine:?} {feed:?} frame {}", t.frame);
            assert_eq!(t_sums, p_sums, "{at}: sums");
            assert_eq!(counts_only(t), counts_only(p), "{at}: counts");
            assert!(p.dynamic_traversal_s.is_nan(), "{at}: not timed");
            if engine == Engine::DiscIndex {
                assert!(t.dynamic_traversal > 0, "{at}: the index was walked");
                assert!(
                    t.dynamic_traversal_s.is_finite() && t.dynamic_traversal_s > 0.0,
                    "{at}: {}",
                    t.dynamic_traversal_s
                );
            } else {
                assert_eq!(t.dynamic_traversal_s, 0.0, "{at}: no disc index");
            }
        }
    }
}
