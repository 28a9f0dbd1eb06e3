//! One DETP engine on `raycost bench`'s DETP scene (the paper's §4.2: μ-random lines through the
//! unit sphere, points uniform in the ball with uniform normals, d = half the mean spacing), timed
//! alone: made to run under `valgrind --tool=callgrind` (instruction counts are repeatable on a
//! busy machine) and to be timed in alternating rounds against another build of the same example.
//!
//! ```text
//! cargo run --release --example detp_speed -- ENGINE [LOG2_RAYS] [POINTS] [REPEATS]
//! ```
//! ENGINE: `grid` (cells of width 2d; `gridK`: width K·d), `octree` (leaves ≤ 32 discs, sides ≥ 2d: the bench's),
//! `octree8` (leaves ≤ 8: the quasi-static specs'), `cache` (sphere cache, Q = 2/3, threshold 100),
//! `cache-q9` (Q = 0.9); an index engine with `-walk` appended (`grid-walk`, …) runs
//! [`DiscIndex::traversal_only`]: the same walk, no disc tested. Defaults: 2¹⁶ lines, 10⁴ points, 1 repeat. Prints the counters (they must
//! not change between builds), the seconds of the accumulation and the checksum of the sums.

use std::time::Instant;

use glam::DVec3;
use rand::Rng;
use raycost::detp::disc::Discs;
use raycost::detp::disc_index::{DiscIndex, GridIndex, Octree};
use raycost::detp::fixed::PowerScale;
use raycost::detp::order::{permutation, Order};
use raycost::detp::sphere_cache::{self, SphereCacheParams};
use raycost::detp::store::{Segment, SegmentStore};
use raycost::sample::lines::uniform_line;
use raycost::sample::rng::stream;

fn scene(rays: u32, points: usize) -> (SegmentStore, Discs) {
    let mut rng = stream(&[0x6465_7470, 0]);
    let segs = (0..rays)
        .map(|k| {
            let (p, d) = uniform_line(&mut rng);
            Segment::new(p, d, 0.0, f64::INFINITY, rng.gen_range(1..1 << 20), k)
        })
        .collect();
    let d = (4.0 * std::f64::consts::PI / 3.0 / points as f64).cbrt() / 2.0;
    (
        SegmentStore::new(segs, PowerScale::for_max_power(1.0)),
        Discs::in_ball(&mut rng, points, DVec3::ZERO, 1.0, d),
    )
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg0 = args.first().map_or("grid", String::as_str);
    let (engine, walk_only) = match arg0.strip_suffix("-walk") {
        Some(e) => (e.to_string(), true),
        None => (arg0.to_string(), false),
    };
    let num = |i: usize, default: usize| {
        args.get(i)
            .map_or(default, |s| s.parse().expect("a number"))
    };
    let (log2_rays, points, repeats) = (num(1, 16), num(2, 10_000), num(3, 1));
    let (store, discs) = scene(1 << log2_rays, points);
    let d = discs.radius;
    let t = Instant::now();
    let index: Option<Box<dyn DiscIndex>> = match engine.as_str() {
        "grid" => Some(Box::new(GridIndex::build(&discs, 2.0 * d))),
        // `gridK`: cells of width K·d (the bench's grid is `grid2`).
        e if e.starts_with("grid") => {
            let k: f64 = e[4..].parse().expect("gridK with K a number");
            Some(Box::new(GridIndex::build(&discs, k * d)))
        }
        "octree" => Some(Box::new(Octree::build(&discs, 32, 2.0 * d))),
        "octree8" => Some(Box::new(Octree::build(&discs, 8, 2.0 * d))),
        "cache" | "cache-q9" => None,
        e => panic!("unknown engine {e}"),
    };
    let build_s = t.elapsed().as_secs_f64();
    let perm = permutation(&discs.centers, Order::Hilbert, 10);
    for _ in 0..repeats {
        let mut acc = vec![0; discs.len()];
        let t = Instant::now();
        let counters = match &index {
            Some(ix) if walk_only => format!("{:?}", ix.traversal_only(&store, None)),
            Some(ix) => format!("{:?}", ix.accumulate(&store, None, 1, &mut acc)),
            None => {
                let params = SphereCacheParams {
                    q: if engine == "cache" { 2.0 / 3.0 } else { 0.9 },
                    ..Default::default()
                };
                let root = (DVec3::ZERO, 1.0 + d * (1.0 + 1e-9));
                let s = sphere_cache::run(&store, &discs, &perm, root, &params, &mut acc);
                format!(
                    "sphere tests {} disc tests {} copied {}",
                    s.ray_sphere_tests,
                    s.ray_disc_tests,
                    s.rays_copied()
                )
            }
        };
        let s = t.elapsed().as_secs_f64();
        let sum = acc.iter().fold(0u64, |h, &v| h.rotate_left(5) ^ v as u64);
        println!("{arg0} build {build_s:.3} s run {s:.4} s {counters} checksum {sum:x}");
    }
}
