//! Quick single-point speed probe of the query grid: `cargo run --release --example fast_speed -- N A RAYS`.
use glam::DVec3;
use raycost::geom::{Aabb, Ray};
use raycost::grid::{build::frame_around, fast::FastGrid};
use raycost::sample::{directions::uniform_direction, rng::stream};
use raycost::scene::finite::{FiniteScene, FiniteSize};
use raycost::scene::{RadiusClass, RadiusDist, RadiusDraw};
use rayon::prelude::*;

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("number"))
        .collect();
    let (n, a, rays) = (args[0] as u64, args[1], args[2] as usize);
    let classes = vec![RadiusClass {
        fraction: 1.0,
        radius: RadiusDist::Constant(0.1),
    }];
    let scene = FiniteScene {
        intensity: 1.0,
        classes,
        draw: RadiusDraw::PerSphere,
        size: FiniteSize::Count(n),
        center: DVec3::ZERO,
    };
    let spheres = scene.generate(&[1]);
    let b = scene.centre_box();
    let t = std::time::Instant::now();
    let grid = FastGrid::build(
        frame_around(Aabb::new(b.lo - 0.1, b.hi + 0.1), a, DVec3::ZERO),
        &spheres,
    );
    let build = t.elapsed().as_secs_f64();
    let mut rng = stream(&[2]);
    let rs: Vec<Ray> = (0..rays)
        .map(|_| Ray::new(DVec3::ZERO, uniform_direction(&mut rng)))
        .collect();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let t = std::time::Instant::now();
        let (ni, ns): (u64, u64) = pool.install(|| {
            rs.par_chunks(1024)
                .map(|c| {
                    c.iter().map(|r| grid.trace(r)).fold((0u64, 0u64), |s, q| {
                        (s.0 + u64::from(q.n_i), s.1 + u64::from(q.n_s))
                    })
                })
                .reduce(|| (0, 0), |x, y| (x.0 + y.0, x.1 + y.1))
        });
        let s = t.elapsed().as_secs_f64();
        println!("n={n} a={a} threads={threads}: {:.3e} rays/s, N_I {:.1}, N_S {:.1}, build {build:.2}s, {:.0} MB", rays as f64 / s, ni as f64 / rays as f64, ns as f64 / rays as f64, grid.bytes() as f64 / 1e6);
    }
}
