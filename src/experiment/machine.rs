//! T_I and T_S of the cost model t = N_I·T_I + N_S·T_S, measured on the running machine.
//!
//! T_S: the DDA alone walking an unbounded grid (no cell access), time per step. T_I: one ray tested
//! against a block of spheres that fits in L1, time per test. Both are lower bounds of what the grid
//! pays (cell lists add memory traffic), which is why `grid-cost-model` also reports the time
//! predicted from the *measured* counts and the timed query, side by side.

use std::time::Instant;

use glam::DVec3;

use crate::geom::{Ray, Sphere};
use crate::grid::{Dda, GridFrame};
use crate::sample::{directions::uniform_direction, rng::stream};

/// Measured machine constants, seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MachineCosts {
    /// One ray–sphere test.
    pub t_i: f64,
    /// One cell step.
    pub t_s: f64,
}

/// Measures T_I and T_S (about 0.2 s). Takes the best of three repetitions to shed interference.
pub fn measure() -> MachineCosts {
    let mut rng = stream(&[0x6d61_6368]);
    let rays: Vec<Ray> = (0..4096)
        .map(|_| Ray::new(DVec3::splat(0.3), uniform_direction(&mut rng)))
        .collect();
    let spheres: Vec<Sphere> = (0..256)
        .map(|i| Sphere {
            c: DVec3::new(
                rand::Rng::gen_range(&mut rng, -9.0..9.0),
                rand::Rng::gen_range(&mut rng, -9.0..9.0),
                rand::Rng::gen_range(&mut rng, -9.0..9.0),
            ),
            r: 0.1,
            id: i,
        })
        .collect();
    let frame = GridFrame {
        origin: DVec3::ZERO,
        width: 1.0,
        dims: None,
    };
    let mut best = MachineCosts {
        t_i: f64::INFINITY,
        t_s: f64::INFINITY,
    };
    for _ in 0..3 {
        let start = Instant::now();
        let mut sink = 0.0;
        for ray in &rays {
            for s in &spheres {
                if let Some(t) = s.intersect(ray) {
                    sink += t;
                }
            }
        }
        std::hint::black_box(sink);
        best.t_i = best
            .t_i
            .min(start.elapsed().as_secs_f64() / (rays.len() * spheres.len()) as f64);

        let start = Instant::now();
        let mut steps = 0u64;
        for ray in &rays {
            for (c, _, t) in Dda::new(&frame, ray).take(200) {
                steps += 1;
                std::hint::black_box((c, t));
            }
        }
        best.t_s = best.t_s.min(start.elapsed().as_secs_f64() / steps as f64);
    }
    best
}
