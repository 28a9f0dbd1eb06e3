//! The query grid's two engines on one thread, for instruction counts under
//! `valgrind --tool=callgrind`: the finite grid on the bench's scene (n centres uniform in a cube
//! at ρ = 1, r = 0.1, rays from the centre) or the lazily generated infinite scene (eyes uniform in
//! a cell, one realisation per ray, mailboxing) as `raycost bench` traces them.
//!
//! ```text
//! cargo run --release --example grid_instr -- finite N A RAYS
//! cargo run --release --example grid_instr -- infinite A RAYS
//! cargo run --release --example grid_instr -- infinite-per-slab A RAYS
//! ```
//! `infinite` is the engine (the gap to the next occupied slab); `infinite-per-slab` the engine
//! before it (a Poisson count per slab), the same process on another random stream.
//! Prints the rays, cells visited (Σ (N_S + 1)) and listings (N_I). Run it at RAYS and 2·RAYS: the
//! difference of the two instruction totals over RAYS is the cost of a ray without the set-up.

use glam::DVec3;
use raycost::geom::{Aabb, Ray};
use raycost::grid::build::frame_around;
use raycost::grid::fast::FastGrid;
use raycost::sample::directions::{uniform_direction, uniform_unit_cube};
use raycost::sample::rng::stream;
use raycost::scene::finite::{FiniteScene, FiniteSize};
use raycost::scene::infinite::{InfiniteCaches, InfiniteScene, Walk};
use raycost::scene::tube::SlabDraw;
use raycost::scene::{RadiusClass, RadiusDist, RadiusDraw};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize| -> f64 { args[i].parse().expect("a number") };
    let classes = vec![RadiusClass {
        fraction: 1.0,
        radius: RadiusDist::Constant(0.1),
    }];
    let mut rng = stream(&[0x9e1d]);
    let (rays, cells, listings) = match args.first().map(String::as_str) {
        Some("finite") => {
            let (n, a, n_rays) = (num(1) as u64, num(2), num(3) as usize);
            let scene = FiniteScene {
                intensity: 1.0,
                classes,
                draw: RadiusDraw::PerSphere,
                size: FiniteSize::Count(n),
                center: DVec3::ZERO,
            };
            let spheres = scene.generate(&[1]);
            let b = scene.centre_box();
            let grid = FastGrid::build(
                frame_around(Aabb::new(b.lo - 0.1, b.hi + 0.1), a, DVec3::ZERO),
                &spheres,
            );
            drop(spheres);
            let (mut cells, mut listings) = (0u64, 0u64);
            for _ in 0..n_rays {
                let t = grid.trace(&Ray::new(DVec3::ZERO, uniform_direction(&mut rng)));
                cells += u64::from(t.n_s) + 1;
                listings += u64::from(t.n_i);
            }
            (n_rays, cells, listings)
        }
        Some(engine @ ("infinite" | "infinite-per-slab")) => {
            let (a, n_rays) = (num(1), num(2) as usize);
            let slabs = if engine == "infinite" {
                SlabDraw::Gaps
            } else {
                SlabDraw::PerSlab
            };
            let scene = InfiniteScene {
                intensity: 1.0,
                classes: &classes,
                draw: RadiusDraw::PerSphere,
            };
            let walk = Walk {
                cell_width: a,
                eye_magnitude: 2.0 * a,
                rays_per_scene: 1,
                mailbox: true,
                max_steps: 10_000_000,
                slabs,
            };
            let mut caches = InfiniteCaches::default();
            let (mut cells, mut listings) = (0u64, 0u64);
            for (b, chunk) in (0..n_rays).collect::<Vec<_>>().chunks(256).enumerate() {
                let rays: Vec<Ray> = chunk
                    .iter()
                    .map(|_| {
                        let d = uniform_direction(&mut rng);
                        Ray::new(uniform_unit_cube(&mut rng) * a, d)
                    })
                    .collect();
                let mut out = Vec::with_capacity(rays.len());
                scene.trace_batch(&walk, &[7, b as u64], &rays, &mut caches, &mut out);
                cells += out.iter().map(|c| u64::from(c.n_s) + 1).sum::<u64>();
                listings += out.iter().map(|c| u64::from(c.n_i)).sum::<u64>();
            }
            (n_rays, cells, listings)
        }
        _ => panic!("finite N A RAYS | infinite A RAYS | infinite-per-slab A RAYS"),
    };
    println!("rays {rays} cells {cells} listings {listings}");
}
