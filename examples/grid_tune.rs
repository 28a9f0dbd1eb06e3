//! Profiling aid for the query grid (how its tuned defaults were found): times configurations of
//! [`FastGrid`] against each other in alternating single-thread rounds, one process, so that the
//! machine's drift cancels out of their comparison.
//!
//! ```text
//! cargo run --release --example grid_tune -- N RAYS ROUNDS CONFIG...
//!   CONFIG = A[:AHEAD:RECORDS][:twice]
//! ```
//! `A` is the cell width; `AHEAD` and `RECORDS` the walk's lookahead (cells computed and prefetched
//! ahead, cells whose records are prefetched ahead; default 6:3); `twice` traces every ray twice in
//! a row, so that `twice − once` is the in-cache (compute-only) cost of a ray and `once` minus that
//! is what memory costs. Environment: `PORTABLE=1` uses the portable walk (as `WALK=portable`;
//! `WALK=avx2` or `WALK=avx512` force those walks where the CPU has them), `SORTED=1` traces the
//! rays in direction order (coherent), `ROUNDS_SHOWN=1` prints every round.
//!
//! Scene: N centres uniform in a cube at ρ = 1, r = 0.1, rays from its centre (the bench's).

use glam::DVec3;
use raycost::geom::{Aabb, Ray};
use raycost::grid::build::frame_around;
use raycost::grid::fast::{FastGrid, Walk};
use raycost::sample::{directions::uniform_direction, rng::stream};
use raycost::scene::finite::{FiniteScene, FiniteSize};
use raycost::scene::{RadiusClass, RadiusDist, RadiusDraw};

struct Config {
    grid: FastGrid,
    label: String,
    twice: bool,
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 4 {
        eprintln!("usage: grid_tune N RAYS ROUNDS A[:AHEAD:RECORDS][:twice]...");
        std::process::exit(2);
    }
    let num = |s: &str| {
        s.parse::<f64>()
            .unwrap_or_else(|_| panic!("not a number: {s}"))
    };
    let (n, n_rays, rounds) = (
        num(&args[0]) as u64,
        num(&args[1]) as usize,
        num(&args[2]) as usize,
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
    let mut configs: Vec<Config> = args[3..]
        .iter()
        .map(|c| {
            let parts: Vec<&str> = c.split(':').collect();
            let twice = parts.last() == Some(&"twice");
            let nums: Vec<f64> = parts
                .iter()
                .filter(|p| **p != "twice")
                .map(|p| num(p))
                .collect();
            let start = std::time::Instant::now();
            let mut grid = FastGrid::build(frame_around(bounds, nums[0], DVec3::ZERO), &spheres);
            if nums.len() >= 3 {
                grid.lookahead = (nums[1] as usize, nums[2] as usize);
            }
            if std::env::var_os("PORTABLE").is_some() {
                grid.set_walk(Walk::Portable);
            }
            match std::env::var("WALK").as_deref() {
                Ok("avx512") => grid.set_walk(Walk::Avx512),
                Ok("avx2") => grid.set_walk(Walk::Avx2),
                Ok("portable") => grid.set_walk(Walk::Portable),
                _ => {}
            }
            eprintln!(
                "{c}: built in {:.2} s, {:.0} MB",
                start.elapsed().as_secs_f64(),
                grid.bytes() as f64 / 1e6
            );
            Config {
                grid,
                label: c.clone(),
                twice,
            }
        })
        .collect();
    let mut rng = stream(&[2]);
    let mut rays: Vec<Ray> = (0..n_rays)
        .map(|_| Ray::new(DVec3::ZERO, uniform_direction(&mut rng)))
        .collect();
    if std::env::var_os("SORTED").is_some() {
        // Serpentine order over a fine (θ, φ) grid: neighbouring rays share cells.
        rays.sort_by_key(|r| {
            let th = (r.d.z.acos() * 2000.0) as i64;
            let ph = ((r.d.y.atan2(r.d.x) + 3.2) * 2000.0) as i64;
            (th, if th % 2 == 0 { ph } else { -ph })
        });
    }
    let mut secs = vec![Vec::new(); configs.len()];
    let mut counts = vec![(0u64, 0u64); configs.len()];
    for _ in 0..rounds {
        for (c, cfg) in configs.iter_mut().enumerate() {
            let start = std::time::Instant::now();
            let (mut cells, mut tests) = (0u64, 0u64);
            for r in &rays {
                if cfg.twice {
                    std::hint::black_box(cfg.grid.trace(std::hint::black_box(r)));
                }
                let q = cfg.grid.trace(r);
                cells += u64::from(q.n_s) + 1;
                tests += u64::from(q.n_i);
            }
            secs[c].push(start.elapsed().as_secs_f64());
            counts[c] = (cells, tests);
        }
    }
    for (c, cfg) in configs.iter().enumerate() {
        let mut v = secs[c].clone();
        if std::env::var_os("ROUNDS_SHOWN").is_some() {
            let r: Vec<String> = v
                .iter()
                .map(|s| format!("{:.0}", n_rays as f64 / s / 1e3))
                .collect();
            println!("{}: k rays/s by round: {}", cfg.label, r.join(" "));
        }
        v.sort_by(f64::total_cmp);
        let med = v[v.len() / 2];
        let (cells, tests) = counts[c];
        println!(
            "n={n} {}: median {:.3e} rays/s ({:.1} ns/cell, cells/ray {:.1}, N_I {:.1}), best {:.3e}",
            cfg.label,
            n_rays as f64 / med,
            med * 1e9 / cells as f64,
            cells as f64 / n_rays as f64,
            tests as f64 / n_rays as f64,
            n_rays as f64 / v[0]
        );
    }
}
