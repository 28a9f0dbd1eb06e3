//! The evaluation of the pure-Rust `obvhs` crate (compressed-wide BVH built by PLOC) as the
//! traversal of light transport's exact queries, against our own core (`src/lt/bvh/`) and Embree.
//!
//! ```text
//! cargo run --release --features obvhs,embree --example obvhs_speed -- [SCENE] [RAYS] [ROUNDS] [ENGINE]
//! ```
//! SCENE: `cornell`, `kitchen`, `museum` (movers posed at τ = 0) or `all` (default); RAYS per round
//! (default 200 000); ROUNDS (default 7); ENGINE (`core`, `obvhs`, `embree`; all by default — one
//! engine alone is what callgrind should count).
//!
//! Rays: origins on the scene's triangles (a uniform triangle, a uniform point on it), directions
//! uniform on the sphere, the origin's triangle skipped — the photon tracer's rays. Queries: the
//! nearest hit, and the nearest with the next crossing beyond it (what DETP stores per segment).
//! - `core`: `Bvh::nearest` and `Bvh::two_nearest`.
//! - `obvhs`: its CWBVH over the triangles' boxes padded by m = 10⁻⁶·(B + max|o|) (B the scene's
//!   magnitude) and rounded outward to f32, rays rounded to f32 (which moves a ray by far less
//!   than m within the scene) started 10⁻³ behind the origin (obvhs culls every box the ray leaves
//!   before t = 10⁻⁴ whatever its tmin: without the shift it loses hits nearer than that), and our
//!   exact leaf test: every primitive obvhs reports is tested
//!   with `Triangle::intersect` in f64, the answer kept by (t, rank) as the core keeps it, and
//!   obvhs told the f32 rounded up of the best t (so it culls only what lies beyond it). The next
//!   crossing re-traces from the first with the core's same-crossing rule.
//! - `embree`: `rtcIntersect1` through the scene's `Caster` (`first_hit`, `first_two_hits`: the
//!   second crossing by a second ray), f32 throughout (not exact; shown for speed).
//!
//! Every obvhs answer is checked against the core's (same triangle, same f64 t): `mismatches`.
//! Times: one thread, engines alternating within each round, medians of per-round ratios to the
//! core's same query.

use std::time::Instant;

use glam::DVec3;
use obvhs::aabb::Aabb as OAabb;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray as ORay, RayHit};
use obvhs::BvhBuildParams;
use obvhs_glam::Vec3A;
use rand::Rng;
use raycost::bench::lt::{find, SCENES};
use raycost::lt::bvh::{Bvh, TwoNearest};
use raycost::lt::shapes::Triangle;
use raycost::lt::Scene;
use raycost::sample::lines::uniform_on_sphere;
use raycost::sample::rng::stream;

/// obvhs over padded triangle boxes, with our exact test at its leaves.
struct Obvhs<'a> {
    bvh: CwBvh,
    tris: &'a [Triangle],
    ranks: &'a [u32],
}

/// How far behind its origin the f32 ray given to obvhs starts (see [`Obvhs::best`]).
const BACK: f64 = 1e-3;

/// The f32 at or above `x`.
fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) >= x {
        f
    } else {
        f.next_up()
    }
}

/// The f32 at or below `x`.
fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) <= x {
        f
    } else {
        f.next_down()
    }
}

fn v3(p: DVec3) -> Vec3A {
    Vec3A::new(p.x as f32, p.y as f32, p.z as f32)
}

impl<'a> Obvhs<'a> {
    fn build(tris: &'a [Triangle], ranks: &'a [u32], origin_bound: f64) -> Self {
        let magnitude = tris
            .iter()
            .flat_map(|t| t.v)
            .map(|v| v.abs().max_element())
            .fold(1.0, f64::max);
        let m = 1e-6 * (magnitude + origin_bound + BACK);
        let boxes: Vec<OAabb> = tris
            .iter()
            .map(|t| {
                let (lo, hi) = t.bounds();
                let (lo, hi) = (lo - DVec3::splat(m), hi + DVec3::splat(m));
                OAabb {
                    min: Vec3A::new(f32_down(lo.x), f32_down(lo.y), f32_down(lo.z)),
                    max: Vec3A::new(f32_up(hi.x), f32_up(hi.y), f32_up(hi.z)),
                }
            })
            .collect();
        let mut build_time = std::time::Duration::default();
        let bvh = obvhs::cwbvh::builder::build_cwbvh(
            &boxes,
            BvhBuildParams::medium_build(),
            &mut build_time,
        );
        Self { bvh, tris, ranks }
    }

    /// The smallest (t, rank) hit with t > t_min accepted by `keep`, skipping `skip`.
    fn best(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        skip: u32,
        keep: impl Fn(f64) -> bool,
    ) -> (f64, u32) {
        // obvhs's box test clamps its entry to t ≥ 10⁻⁴ (`cwbvh::node::EPSILON`, whatever the
        // ray's tmin): a box the ray leaves before that is culled, and with it a hit nearer than
        // 10⁻⁴ (measured: 39 of 10⁵ kitchen rays). The f32 ray starts `BACK` behind the origin,
        // so obvhs's t is ours + BACK (d is a unit vector).
        let ray = ORay::new(v3(o - d * BACK), v3(d), 0.0, f32::INFINITY);
        let mut best = (f64::INFINITY, u32::MAX, u32::MAX);
        let mut hit = RayHit::none();
        self.bvh.ray_traverse(ray, &mut hit, |_, id| {
            let i = self.bvh.primitive_indices[id];
            if i == skip {
                return f32::INFINITY;
            }
            match self.tris[i as usize].intersect(o, d, t_min) {
                Some(t) if keep(t) => {
                    let r = self.ranks[i as usize];
                    if t < best.0 || (t == best.0 && r < best.2) {
                        best = (t, i, r);
                        // Strictly above the best f32 bound so far: obvhs keeps culling only
                        // beyond it, and an equal t of a lower rank still reaches us.
                        f32_up(t + BACK).next_up()
                    } else {
                        f32::INFINITY
                    }
                }
                _ => f32::INFINITY,
            }
        });
        (best.0, best.1)
    }

    fn nearest(&self, o: DVec3, d: DVec3, skip: u32) -> (f64, u32) {
        self.best(o, d, 0.0, skip, |_| true)
    }

    fn two_nearest(&self, o: DVec3, d: DVec3, skip: u32) -> TwoNearest {
        let first = self.nearest(o, d, skip);
        if !first.0.is_finite() {
            return TwoNearest::default();
        }
        let f = first.0;
        let second = self.best(o, d, f, skip, |t| t - f > 1e-12 * t.abs().max(1.0));
        TwoNearest { first, second }
    }
}

/// The rays of one round: (origin, direction, origin's triangle).
fn rays(tris: &[Triangle], n: usize, round: u64) -> Vec<(DVec3, DVec3, u32)> {
    let mut rng = stream(&[0x0b5, round]);
    (0..n)
        .map(|_| {
            let i = rng.gen_range(0..tris.len());
            let (mut a, mut b): (f64, f64) = (rng.gen(), rng.gen());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let v = tris[i].v;
            let o = v[0] + (v[1] - v[0]) * a + (v[2] - v[0]) * b;
            (o, uniform_on_sphere(&mut rng), i as u32)
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

type Run<'s> = Box<dyn Fn(&[(DVec3, DVec3, u32)]) -> u64 + 's>;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let which = args.first().map_or("all", String::as_str).to_string();
    let n: usize = args.get(1).map_or(Ok(200_000), |s| s.parse())?;
    let rounds: u64 = args.get(2).map_or(Ok(7), |s| s.parse())?;
    let only = args.get(3).cloned();
    println!(
        "cpu: {}; one thread; {} rays per round, {rounds} rounds",
        raycost::output::meta::cpu_model(),
        n
    );
    for (name, rel) in SCENES.iter().filter(|s| which == "all" || s.0 == which) {
        let path = find(rel).ok_or_else(|| anyhow::anyhow!("{rel} not found"))?;
        let mut scene = Scene::load(&path).map_err(|e| anyhow::anyhow!("{e}"))?;
        scene.set_tau(0.0);
        let tris = scene.triangles.clone();
        let core = Bvh::build(&tris);
        let origin_bound = tris
            .iter()
            .flat_map(|t| t.v)
            .map(|v| v.abs().max_element())
            .fold(0.0, f64::max);
        let t = Instant::now();
        let ob = Obvhs::build(&tris, core.ranks(), origin_bound);
        let ob_build = t.elapsed().as_secs_f64();
        // Exactness: every obvhs answer against the core's, on one round's rays.
        let check = rays(&tris, n.min(100_000), 999);
        let mut mismatches = [0usize; 2];
        for &(o, d, s) in &check {
            let (a, b) = (core.nearest(o, d, 0.0, s), ob.nearest(o, d, s));
            let (c, e) = (core.two_nearest(o, d, 0.0, s), ob.two_nearest(o, d, s));
            if a != b && mismatches[0] < 3 {
                println!("  nearest mismatch: o {o} d {d} skip {s}: core {a:?}, obvhs {b:?}");
            }
            if c != e && mismatches[1] < 3 {
                println!("  two mismatch: o {o} d {d} skip {s}: core {c:?}, obvhs {e:?}");
            }
            mismatches[0] += usize::from(a != b);
            mismatches[1] += usize::from(c != e);
        }
        println!(
            "{name}: {} triangles, obvhs build {ob_build:.3} s, mismatches of {} rays: \
             nearest {}, two {}",
            tris.len(),
            check.len(),
            mismatches[0],
            mismatches[1]
        );
        #[cfg(feature = "embree")]
        let embree = raycost::embree::triangles::EmbreeTriangles::build(&scene)?;
        let mut engines: Vec<(&str, Run)> = vec![
            (
                "core nearest",
                Box::new(|r| {
                    r.iter()
                        .map(|&(o, d, s)| core.nearest(o, d, 0.0, s).1 as u64)
                        .sum()
                }),
            ),
            (
                "obvhs nearest",
                Box::new(|r| {
                    r.iter()
                        .map(|&(o, d, s)| ob.nearest(o, d, s).1 as u64)
                        .sum()
                }),
            ),
            (
                "core two",
                Box::new(|r| {
                    r.iter()
                        .map(|&(o, d, s)| core.two_nearest(o, d, 0.0, s).second.1 as u64)
                        .sum()
                }),
            ),
            (
                "obvhs two",
                Box::new(|r| {
                    r.iter()
                        .map(|&(o, d, s)| ob.two_nearest(o, d, s).second.1 as u64)
                        .sum()
                }),
            ),
        ];
        #[cfg(feature = "embree")]
        {
            use raycost::lt::cast::Caster;
            use raycost::lt::Prim;
            let e = &embree;
            engines.push((
                "embree nearest",
                Box::new(move |r| {
                    r.iter()
                        .map(|&(o, d, s)| {
                            e.first_hit(o, d, 0.0, Some(Prim::Triangle(s)))
                                .map_or(0, |h| h.t as u64)
                        })
                        .sum()
                }),
            ));
            engines.push((
                "embree two",
                Box::new(move |r| {
                    r.iter()
                        .map(|&(o, d, s)| {
                            e.first_two_hits(o, d, 0.0, Some(Prim::Triangle(s))).1 as u64
                        })
                        .sum()
                }),
            ));
        }
        if let Some(e) = &only {
            engines.retain(|(name, _)| name.starts_with(e.as_str()));
        }
        let mut secs = vec![Vec::new(); engines.len()];
        for round in 0..rounds {
            let r = rays(&tris, n, round);
            for (k, (_, f)) in engines.iter().enumerate() {
                let t = Instant::now();
                std::hint::black_box(f(&r));
                secs[k].push(t.elapsed().as_secs_f64() / n as f64);
            }
        }
        for ((label, _), s) in engines.iter().zip(&secs) {
            // Paired with the core's same query in the same round (if it ran).
            let query = label.split(' ').nth(1).unwrap_or_default();
            let base = engines
                .iter()
                .position(|(l, _)| *l == format!("core {query}"));
            let ratio = base.map_or(String::new(), |b| {
                let r = median(s.iter().zip(&secs[b]).map(|(a, b)| a / b).collect());
                format!("  (÷ core {query}: {r:.2})")
            });
            println!(
                "  {label:<15} {:>7.1} ns/ray{ratio}",
                1e9 * median(s.clone())
            );
        }
    }
    Ok(())
}
