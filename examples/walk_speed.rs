//! Rays per second of each walk of the query grid this CPU has (AVX-512, AVX2, portable), side by
//! side in one process: interleaved rounds (the order of the walks rotates every round, so that
//! drift and turbo state cancel out), on 1 and on 2 threads, medians printed with the CPU model.
//! Every walk's answers are checked against the portable walk's (hit and counts, bit for bit).
//!
//! ```text
//! cargo run --release --example walk_speed -- [N] [RAYS] [ROUNDS] [A]
//! ```
//! Defaults: N = 10⁶ spheres (ρ = 1, r = 0.1, the bench's scene), RAYS = 200 000 from the centre,
//! ROUNDS = 7, cell width A = 2.36 (what `raycost bench`'s cost model picks at ρ = 1, r = 0.1).

use glam::DVec3;
use raycost::geom::{Aabb, Ray};
use raycost::grid::build::frame_around;
use raycost::grid::fast::{FastGrid, FastTrace, Walk};
use raycost::sample::{directions::uniform_direction, rng::stream};
use raycost::scene::finite::{FiniteScene, FiniteSize};
use raycost::scene::{RadiusClass, RadiusDist, RadiusDraw};
use rayon::prelude::*;

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("numbers: N RAYS ROUNDS A"))
        .collect();
    let arg = |i: usize, default: f64| args.get(i).copied().unwrap_or(default);
    let (n, n_rays, rounds, a) = (
        arg(0, 1e6) as u64,
        arg(1, 2e5) as usize,
        arg(2, 7.0) as usize,
        arg(3, 2.36),
    );
    let scene = FiniteScene {
        intensity: 1.0,
        classes: vec![RadiusClass {
            fraction: 1.0,
            radius: RadiusDist::Constant(0.1),
        }],
        draw: RadiusDraw::PerSphere,
        size: FiniteSize::Count(n),
        center: DVec3::ZERO,
    };
    let spheres = scene.generate(&[1]);
    let b = scene.centre_box();
    let bounds = Aabb::new(b.lo - 0.1, b.hi + 0.1);
    let mut grid = FastGrid::build(frame_around(bounds, a, DVec3::ZERO), &spheres);
    drop(spheres);
    let mut rng = stream(&[2]);
    let rays: Vec<Ray> = (0..n_rays)
        .map(|_| Ray::new(DVec3::ZERO, uniform_direction(&mut rng)))
        .collect();
    let walks = Walk::all_available();
    let threads = [1usize, 2];
    let pools: Vec<rayon::ThreadPool> = threads
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
        })
        .collect();
    println!(
        "cpu: {}\nn = {n}, a = {a}, {n_rays} rays per round, {rounds} rounds, grid {:.0} MB, default walk {:?}",
        cpu_model(),
        grid.bytes() as f64 / 1e6,
        Walk::detect()
    );
    // Reference answers (portable walk), and a warm-up of the grid's pages.
    grid.set_walk(Walk::Portable);
    let reference: Vec<FastTrace> =
        pools[1].install(|| rays.par_iter().map(|r| grid.trace(r)).collect());
    let mut out = vec![FastTrace::default(); n_rays];
    // secs[walk][thread count] over rounds.
    let mut secs = vec![vec![Vec::new(); threads.len()]; walks.len()];
    for round in 0..rounds {
        for j in 0..walks.len() {
            let w = (round + j) % walks.len();
            grid.set_walk(walks[w]);
            for (p, pool) in pools.iter().enumerate() {
                let start = std::time::Instant::now();
                pool.install(|| {
                    out.par_chunks_mut(1024)
                        .zip(rays.par_chunks(1024))
                        .for_each(|(o, r)| {
                            o.iter_mut().zip(r).for_each(|(o, r)| *o = grid.trace(r))
                        })
                });
                secs[w][p].push(start.elapsed().as_secs_f64());
                let bad = out.iter().zip(&reference).filter(|(x, y)| x != y).count();
                assert_eq!(
                    bad, 0,
                    "{:?} walk disagrees with the portable walk",
                    walks[w]
                );
            }
        }
    }
    let cells = reference.iter().map(|q| f64::from(q.n_s + 1)).sum::<f64>() / n_rays as f64;
    let tests = reference.iter().map(|q| f64::from(q.n_i)).sum::<f64>() / n_rays as f64;
    println!(
        "per ray: {cells:.2} cells, {tests:.2} listings filtered; all walks agree bit for bit"
    );
    for (p, &t) in threads.iter().enumerate() {
        for (w, walk) in walks.iter().enumerate() {
            let rps: Vec<f64> = secs[w][p].iter().map(|s| n_rays as f64 / s).collect();
            let shown: Vec<String> = rps.iter().map(|r| format!("{:.3}", r / 1e6)).collect();
            println!(
                "{t} thread(s) {:>8}: median {:.3} M rays/s (rounds: {})",
                format!("{walk:?}"),
                median(rps.clone()) / 1e6,
                shown.join(", ")
            );
        }
        // Paired ratios per round (same round, adjacent in time).
        if let (Some(a5), Some(a2)) = (
            walks.iter().position(|&w| w == Walk::Avx512),
            walks.iter().position(|&w| w == Walk::Avx2),
        ) {
            let ratio: Vec<f64> = secs[a2][p]
                .iter()
                .zip(&secs[a5][p])
                .map(|(s2, s5)| s2 / s5)
                .collect();
            println!(
                "{t} thread(s) AVX-512 / AVX2 rays/s, median of paired rounds: {:.3}",
                median(ratio)
            );
        }
    }
}
