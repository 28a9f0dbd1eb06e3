//! Embree speed on the bench's reference scene (docs/bench.md): n = 10⁶ sphere centres uniform in a cube of side 100
//! (ρ = 1), r = 0.1, 10⁶ rays from the centre. Prints build seconds and rays/s on 1 and 2 threads.
//!
//! `CARGO_TARGET_DIR=/work/target-embree cargo run --release --features embree --example embree_speed [n] [rays]`

use std::time::Instant;

use glam::DVec3;
use raycost::embree::EmbreeScene;
use raycost::geom::{Ray, Sphere};
use raycost::sample::directions::{uniform_direction, uniform_unit_cube};
use raycost::sample::rng::stream;
use rayon::prelude::*;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<usize>());
    let n = args.next().transpose()?.unwrap_or(1_000_000);
    let n_rays = args.next().transpose()?.unwrap_or(1_000_000);
    let side = (n as f64).cbrt(); // ρ = 1
    let mut rng = stream(&[0x5eed, n as u64]);
    let spheres: Vec<Sphere> = (0..n as u64)
        .map(|id| Sphere {
            c: uniform_unit_cube(&mut rng) * side,
            r: 0.1,
            id,
        })
        .collect();
    let o = DVec3::splat(side / 2.0);
    let rays: Vec<Ray> = (0..n_rays)
        .map(|_| Ray::new(o, uniform_direction(&mut rng)))
        .collect();

    let t0 = Instant::now();
    let scene = EmbreeScene::build(&spheres)?;
    println!(
        "n = {n}, side = {side:.1}: build {:.3} s",
        t0.elapsed().as_secs_f64()
    );

    // Rays in chunks of 4096 per rayon task, as the grid engine batches them.
    let mut out = vec![None; n_rays];
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        let t0 = Instant::now();
        pool.install(|| {
            rays.par_chunks(4096)
                .zip(out.par_chunks_mut(4096))
                .for_each(|(r, o)| scene.first_hits(r, o))
        });
        let secs = t0.elapsed().as_secs_f64();
        let hits = out.iter().filter(|h| h.is_some()).count();
        println!(
            "{threads} thread(s): {:.3} M rays/s ({:.1} % hit)",
            n_rays as f64 / secs / 1e6,
            100.0 * hits as f64 / n_rays as f64
        );
    }
    Ok(())
}
