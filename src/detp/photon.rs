//! Photon tracing into the ray store. Each photon draws from its own stream keyed by
//! (PHOTON, seed, photon id), so any photon can be traced again alone — after a dynamic object
//! moved, say — and gives bit-identical segments ([`retrace`]).
//!
//! A photon starts at a light picked in proportion to power and carries Φ_total / N (so every
//! segment has the same power). Every flight is a stored segment: origin, direction, first impact
//! t_hit (+∞ if it leaves the scene) and t_end, the next intersection of the same line beyond the
//! impact (+∞ if none), which is how far DETP counts crossings (concave surfaces). At an impact the
//! photon survives with probability equal to the albedo (Russian roulette: power unchanged) and
//! leaves in a cosine-distributed direction about the normal on the side it arrived from.

use std::f64::consts::TAU;

use glam::DVec3;
use rand::Rng;
use rayon::prelude::*;

use super::fixed::{PowerScale, Units};
use super::store::{Segment, SegmentStore};
use crate::lt::cast::Caster;
use crate::lt::{Light, Prim, Scene};
use crate::sample::directions::{cosine_about, uniform_direction};
use crate::sample::rng::{domain, stream};

/// Paths longer than this are cut (and counted): albedos below 1 make them vanishingly rare.
pub const MAX_BOUNCES: u16 = crate::lt::MAX_BOUNCES;

/// Photons per parallel work item (each keeps its own streams: the result does not depend on it).
const BATCH: u64 = 1024;

/// Traces `photons` photons (their ids are 0..photons) into a store, in photon order.
pub fn trace_photons(scene: &Scene, photons: u64, seed: u64) -> SegmentStore {
    trace_photons_with(scene, scene, photons, seed)
}

/// The photons `ids` of a run of `photons` photons (`--photon-shard`): each bit-identical to the
/// one [`trace_photons`] traces, because a photon's stream and power depend on its id and the
/// run's photon count only. `photon_start` still spans every id (empty outside `ids`).
pub fn trace_photon_range(
    scene: &Scene,
    ids: std::ops::Range<u64>,
    photons: u64,
    seed: u64,
) -> SegmentStore {
    trace_range_with(scene, scene, ids, photons, seed)
}

/// [`trace_photons`] with the rays cast by `caster` (the scene's own core, or Embree in
/// `raycost bench`).
pub fn trace_photons_with<C: Caster>(
    scene: &Scene,
    caster: &C,
    photons: u64,
    seed: u64,
) -> SegmentStore {
    trace_range_with(scene, caster, 0..photons, photons, seed)
}

/// The photons `ids` of `photons`, cast by `caster`.
fn trace_range_with<C: Caster>(
    scene: &Scene,
    caster: &C,
    ids: std::ops::Range<u64>,
    photons: u64,
    seed: u64,
) -> SegmentStore {
    assert!(
        photons > 0 && photons <= u64::from(u32::MAX) && ids.end <= photons,
        "photon count out of range"
    );
    let (scale, units) = photon_units(scene, photons);
    let lo = ids.start;
    let paths: Vec<Vec<Segment>> = (0..(ids.end - lo).div_ceil(BATCH))
        .into_par_iter()
        .map(|b| {
            let hi = (lo + (b + 1) * BATCH).min(ids.end);
            (lo + b * BATCH..hi)
                .flat_map(|p| trace_one(scene, caster, seed, p as u32, units))
                .collect()
        })
        .collect();
    let mut segments = Vec::with_capacity(paths.iter().map(Vec::len).sum());
    let mut photon_start = Vec::with_capacity(photons as usize + 1);
    for batch in paths {
        segments.extend(batch);
    }
    // Offsets: segments are in photon order, each photon's contiguous.
    let mut p = 0u32;
    for (i, s) in segments.iter().enumerate() {
        while p <= s.photon {
            photon_start.push(i as u32);
            p += 1;
        }
    }
    while (p as u64) <= photons {
        photon_start.push(segments.len() as u32);
        p += 1;
    }
    let mut store = SegmentStore::new(segments, scale);
    store.photon_start = photon_start;
    store
}

/// The segments of photon `photon` alone, bit-identical to those [`trace_photons`] stored for it
/// (same scene, seed and photon count).
pub fn retrace(scene: &Scene, seed: u64, photons: u64, photon: u32) -> Vec<Segment> {
    trace_one(scene, scene, seed, photon, photon_units(scene, photons).1)
}

/// Every photon carries Φ_total / N: the scale maps that to 2³¹ units.
fn photon_units(scene: &Scene, photons: u64) -> (PowerScale, Units) {
    let watts = scene.total_power() / photons as f64;
    let scale = PowerScale::for_max_power(watts);
    (scale, scale.units(watts))
}

/// Picks a light in proportion to power.
fn pick_light(scene: &Scene, u: f64) -> &Light {
    let total = scene.total_power();
    let mut acc = 0.0;
    for l in &scene.lights {
        acc += l.power();
        if u * total < acc {
            return l;
        }
    }
    scene.lights.last().expect("a scene has a light")
}

/// Where a photon leaves its light: (origin, direction, the primitive it leaves).
fn emit<R: Rng>(scene: &Scene, rng: &mut R) -> (DVec3, DVec3, Option<Prim>) {
    match pick_light(scene, rng.gen()) {
        Light::Point { position, .. } => (*position, uniform_direction(rng), None),
        Light::Spot {
            position,
            axis,
            cos_cone,
            ..
        } => {
            // Uniform in the cone's solid angle: cos θ uniform in [cos_cone, 1].
            let c = 1.0 - rng.gen::<f64>() * (1.0 - cos_cone);
            let s = (1.0 - c * c).max(0.0).sqrt();
            let phi = TAU * rng.gen::<f64>();
            let (a, b) = axis.any_orthonormal_pair();
            (
                *position,
                (a * (s * phi.cos()) + b * (s * phi.sin()) + *axis * c).normalize(),
                None,
            )
        }
        Light::Area {
            triangles, ball, ..
        } => {
            if let Some(b) = ball {
                let s = scene.balls[*b as usize];
                let p = s.center + uniform_direction(rng) * s.radius;
                let n = s.normal_at(p);
                (p, cosine_about(rng, n), Some(Prim::Ball(*b)))
            } else {
                // A triangle in proportion to area, a uniform point on it.
                let total: f64 = triangles
                    .iter()
                    .map(|&t| scene.triangles[t as usize].area())
                    .sum();
                let mut u = rng.gen::<f64>() * total;
                let mut pick = triangles[0];
                for &t in triangles {
                    pick = t;
                    u -= scene.triangles[t as usize].area();
                    if u < 0.0 {
                        break;
                    }
                }
                let tri = scene.triangles[pick as usize];
                let (mut a, mut b): (f64, f64) = (rng.gen(), rng.gen());
                if a + b > 1.0 {
                    (a, b) = (1.0 - a, 1.0 - b);
                }
                let p = tri.v[0] + (tri.v[1] - tri.v[0]) * a + (tri.v[2] - tri.v[0]) * b;
                (
                    p,
                    cosine_about(rng, tri.normal()),
                    Some(Prim::Triangle(pick)),
                )
            }
        }
    }
}

/// One photon's path.
fn trace_one<C: Caster>(
    scene: &Scene,
    caster: &C,
    seed: u64,
    photon: u32,
    units: Units,
) -> Vec<Segment> {
    let mut rng = stream(&[domain::PHOTON, seed, u64::from(photon)]);
    let eps = scene.precision().offset();
    let (mut o, mut d, mut leaving) = emit(scene, &mut rng);
    let mut path = Vec::new();
    for bounce in 0..=MAX_BOUNCES {
        let (hit, t_end) = caster.first_two_hits(o, d, eps, leaving);
        let t_hit = hit.map_or(f64::INFINITY, |h| h.t);
        let mut s = Segment::new(o, d, t_hit, t_end, units, photon);
        s.bounce = bounce;
        path.push(s);
        let Some(h) = hit else { break };
        if bounce == MAX_BOUNCES || rng.gen::<f64>() >= scene.surfaces[h.surface as usize].albedo {
            break;
        }
        let p = o + d * h.t;
        let mut n = scene.normal(h.prim, p);
        if n.dot(d) > 0.0 {
            n = -n; // leave on the side the photon came from
        }
        o = p;
        d = cosine_about(&mut rng, n);
        leaving = Some(h.prim);
    }
    path
}
