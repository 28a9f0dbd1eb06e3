//! The crossover's cost figures, measured at library level before the experiment kinds are wired: per
//! scene, per-point path tracing (seconds per path, rays per path by kind, seconds per ray, the
//! per-path cv), direct light by NEE (seconds per point), photon tracing (seconds per photon and per
//! segment, the share of indirect segments), and DETP's seconds over photons × points (disc index
//! and sphere cache) with the photon map beside them, then the cost model
//! `seconds = fixed + a·N + b·N·n_P^γ + c·n_P` fitted to them (γ = 1, and the best γ on a grid) and
//! its worst misfit.
//! Prints Markdown; `docs/plans/crossover-wiring.md` quotes it. Timings depend on the load: the first
//! and last lines give `uptime`'s load and the CPU.
//!
//! `cargo run --release --example crossover_costs [-- SCENE…]` (names: cornell, kitchen, hard,
//! museum, robots; default all). `RAYCOST_QUICK=1` halves every size.

use std::path::Path;
use std::time::Instant;

use glam::DVec3;
use raycost::detp::disc::Discs;
use raycost::detp::disc_index::{DiscIndex, Octree};
use raycost::detp::indirect::{indirect_store, is_indirect};
use raycost::detp::order::{permutation, Order};
use raycost::detp::photon::trace_photons;
use raycost::detp::photon_map::{estimate, Filter};
use raycost::detp::sphere_cache::{self, root_sphere, SphereCacheParams};
use raycost::detp::surface_points::{open_surface_points, read_points_csv};
use raycost::geom::Aabb;
use raycost::lt::direct::direct_irradiance;
use raycost::lt::pathtrace::{path_trace, powers_of_two};
use raycost::lt::Scene;
use raycost::stats::fit::CostModel;
use raycost::stats::time_to_target::PathTracingCost;

/// One scene of the study: its file, points for the path tracer (a points file or a lattice
/// spacing), the disc radius d and the point counts of the DETP sweep.
struct Case {
    name: &'static str,
    file: &'static str,
    points_file: Option<&'static str>,
    spacing: f64,
    d: f64,
    point_targets: &'static [f64],
}

const CASES: &[Case] = &[
    Case {
        name: "cornell",
        file: "experiments/scenes/cornell.toml",
        points_file: None,
        spacing: 40.0,
        d: 10.0,
        point_targets: &[1e3, 1e4, 1e5, 1e6],
    },
    Case {
        name: "kitchen",
        file: "experiments/scenes/bart/kitchen/kitchen.aff",
        points_file: Some("experiments/scenes/bart/kitchen-points.csv"),
        spacing: 0.1,
        d: 0.05,
        point_targets: &[1e3, 1e4, 1e5, 1e6],
    },
    Case {
        name: "hard",
        file: "experiments/scenes/hard/hard-cases-lit.toml",
        points_file: Some("experiments/scenes/hard/hard-cases.points.csv"),
        spacing: 0.1,
        d: 0.05,
        point_targets: &[1e3, 1e4, 1e5],
    },
    Case {
        name: "museum",
        file: "experiments/scenes/bart/museum/museum5.aff",
        points_file: None,
        spacing: 0.5,
        d: 0.1,
        point_targets: &[1e3, 1e4, 1e5],
    },
    Case {
        name: "robots",
        file: "experiments/scenes/bart/robot/Robot.aff",
        points_file: None,
        spacing: 2.0,
        d: 0.5,
        point_targets: &[1e3, 1e4, 1e5],
    },
];

fn main() {
    let quick = std::env::var_os("RAYCOST_QUICK").is_some();
    let args: Vec<String> = std::env::args().skip(1).collect();
    println!("{}", machine());
    for case in CASES {
        if !args.is_empty() && !args.iter().any(|a| a == case.name) {
            continue;
        }
        run_case(case, quick);
    }
    println!("{}", machine());
}

/// `uptime`'s load, the CPU and the thread count.
fn machine() -> String {
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .unwrap_or_default()
        .lines()
        .find(|l| l.starts_with("model name"))
        .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        .unwrap_or_default();
    format!(
        "machine: {cpu}, {} threads, load {}",
        rayon::current_num_threads(),
        load.split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" ")
    )
}

/// Seconds of `f`, with its value.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let v = f();
    (v, t.elapsed().as_secs_f64())
}

/// Area of the non-emitting static surfaces (where surface points go).
fn point_area(scene: &Scene) -> f64 {
    let (tris, balls) = scene.static_geometry();
    let emits = |s: u32| scene.surfaces[s as usize].emission > 0.0;
    tris.iter()
        .filter(|t| !emits(t.surface))
        .map(|t| t.area())
        .sum::<f64>()
        + balls
            .iter()
            .filter(|b| !emits(b.surface))
            .map(|b| b.area())
            .sum::<f64>()
}

fn run_case(case: &Case, quick: bool) {
    let mut scene = Scene::load(Path::new(case.file)).expect("scene");
    if !scene.movers.is_empty() {
        scene.set_tau(0.0);
    }
    let scale = if quick { 0.5 } else { 1.0 };
    let area = point_area(&scene);
    println!(
        "\n## {} ({} triangles, {} spheres, {} lights, point area {area:.4e}, d = {})\n",
        case.name,
        scene.triangles.len(),
        scene.balls.len(),
        scene.lights.len(),
        case.d
    );
    let (pts, nrm) = match case.points_file {
        Some(f) => read_points_csv(Path::new(f)).expect("points"),
        None => {
            let (p, n, _) = open_surface_points(&scene, case.spacing);
            (p, n)
        }
    };
    path_tracing_costs(&scene, &pts, &nrm, scale);
    let photons_ref = (200_000.0 * scale) as u64;
    let (store, s) = timed(|| trace_photons(&scene, photons_ref, 1));
    let indirect = store.segments.iter().filter(|s| is_indirect(s)).count();
    println!(
        "photons: {photons_ref} in {s:.3} s: {:.3} µs/photon, {:.2} segments/photon, {:.3} µs/segment, {:.1} % of segments indirect (bounce ≥ 1)\n",
        1e6 * s / photons_ref as f64,
        store.len() as f64 / photons_ref as f64,
        1e6 * s / store.len() as f64,
        100.0 * indirect as f64 / store.len() as f64
    );
    detp_costs(&scene, case, area, scale);
}

/// Path tracing on up to 256 of the points with K = 256 paths, and NEE direct light on them.
fn path_tracing_costs(scene: &Scene, pts: &[DVec3], nrm: &[DVec3], scale: f64) {
    let step = (pts.len() / 256).max(1);
    let p: Vec<DVec3> = pts.iter().step_by(step).take(256).copied().collect();
    let n: Vec<DVec3> = nrm.iter().step_by(step).take(256).copied().collect();
    let k = (256.0 * scale) as u64;
    let run = path_trace(scene, &p, &n, &powers_of_two(k), 1, 0);
    let last = run.checkpoints.len() - 1;
    let paths = (p.len() as u64 * k) as f64;
    let rays = run.rays[last];
    let means = run.means_at(last);
    let cv = PathTracingCost::cv_from(&run.variance, &means);
    println!(
        "path tracing: {} points × {k} paths in {:.3} s: {:.3} µs/path, {:.2} continuation + {:.2} shadow rays/path, {:.3} µs/ray, cv {cv:.3} (paths for 5 %: {})",
        p.len(),
        run.wall_s,
        1e6 * run.seconds_per_path(),
        rays.path as f64 / paths,
        rays.shadow as f64 / paths,
        1e6 * run.wall_s / rays.total() as f64,
        PathTracingCost {
            cv,
            seconds_per_path: run.seconds_per_path()
        }
        .paths_for(0.05)
    );
    let ((_, tally), s) = timed(|| direct_irradiance(scene, &p, &n, 16, 1, 0));
    println!(
        "NEE direct (16 area samples): {:.3} µs/point, {:.1} shadow rays/point\n",
        1e6 * s / p.len() as f64,
        tally.shadow as f64 / p.len() as f64
    );
}

/// DETP's seconds over photons × points: disc index (octree), sphere cache, photon map (k = 64).
fn detp_costs(scene: &Scene, case: &Case, area: f64, scale: f64) {
    println!("| N | n_P | trace s | octree build s | octree query s | octree query s, indirect store | sphere cache s | photon map s |");
    println!("|---|---|---|---|---|---|---|---|");
    let mut samples = Vec::new();
    // One fine lattice (≥ the largest count: a mesh gets a point per triangle at least, so coarser
    // lattices cannot go below the triangle count), subsampled evenly to each count.
    let most = case.point_targets.iter().fold(0.0f64, |a, &b| a.max(b)) * scale;
    let (fine_c, fine_n, _) = open_surface_points(scene, (area / most).sqrt() / 1.2);
    for photons in [(50_000.0 * scale) as u64, (200_000.0 * scale) as u64] {
        let (store, trace_s) = timed(|| trace_photons(scene, photons, 2));
        let indirect = indirect_store(&store);
        for &target in case.point_targets {
            let step = ((fine_c.len() as f64 / (target * scale)).round() as usize).max(1);
            let c: Vec<DVec3> = fine_c.iter().step_by(step).copied().collect();
            let n: Vec<DVec3> = fine_n.iter().step_by(step).copied().collect();
            let discs = Discs::new(c, n, case.d).expect("discs");
            let np = discs.len();
            let mut acc = vec![0; np];
            let (ix, build_s) = timed(|| Octree::build(&discs, 8, case.d));
            let (_, query_s) = timed(|| ix.accumulate(&store, None, 1, &mut acc));
            let mut acc_ind = vec![0; np];
            let (_, indirect_s) = timed(|| ix.accumulate(&indirect, None, 1, &mut acc_ind));
            let perm = permutation(&discs.centers, Order::Hilbert, 10);
            let (b, db) = (scene.bounds(), discs.bounds_all());
            let root = root_sphere(&Aabb::new(b.lo.min(db.lo), b.hi.max(db.hi)));
            let params = SphereCacheParams {
                chunk_points: 16_384,
                ..SphereCacheParams::default()
            };
            let mut acc2 = vec![0; np];
            let (_, cache_s) =
                timed(|| sphere_cache::run(&store, &discs, &perm, root, &params, &mut acc2));
            assert_eq!(acc, acc2, "engines agree");
            let (_, map_s) =
                timed(|| estimate(&store, &discs.centers, &discs.normals, 64, Filter::Cone));
            println!(
                "| {photons} | {np} | {trace_s:.3} | {build_s:.4} | {query_s:.3} | {indirect_s:.3} | {cache_s:.3} | {map_s:.3} |"
            );
            samples.push((photons as f64, np as f64, trace_s + build_s + query_s));
        }
    }
    let grid: Vec<f64> = (0..=20).map(|k| f64::from(k) / 20.0).collect();
    for (what, fit) in [
        ("γ = 1", CostModel::fit(&samples, 1.0)),
        ("best γ", CostModel::fit_best_gamma(&samples, &grid)),
    ] {
        println!(
            "\nDETP (trace + octree) model, {what}: fixed {:.3e} s + {:.3e} s/photon + {:.3e} s/(photon·point^{:.2}) + {:.3e} s/point; worst misfit {:.1} %",
            fit.fixed,
            fit.per_photon,
            fit.per_photon_point,
            fit.gamma,
            fit.per_point,
            100.0 * fit.worst_relative_misfit(&samples)
        );
    }
}
