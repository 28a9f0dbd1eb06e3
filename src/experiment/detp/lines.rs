//! The DETP paper's validation rays (§4.2): μ-random lines through the unit ball, and the exact
//! irradiance they give a disc.

use std::ops::Range;
use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::config::DetpConfig;
use super::{RaySet, BATCH};
use crate::detp::fixed::PowerScale;
use crate::detp::store::{Segment, SegmentStore};
use crate::sample::lines::uniform_line;
use crate::sample::rng::{domain, stream};

/// μ-random lines through the unit ball (Alg. 4.1/4.2), each a segment with 1 W of power that starts
/// 1 unit before its entry point and ends 1 unit past its exit, so every disc near the ball (d ≤ 1)
/// sees the whole chord.
///
/// Only the lines `ids` are kept (`--photon-shard`; all of them otherwise): a line's stream is its
/// batch's, so the batches that `ids` cuts are drawn whole and the others' lines dropped, and every
/// kept line is bit-identical to the same line of the whole set.
pub(super) fn lines(cfg: &DetpConfig, point: u64, replica: u64, ids: Range<u64>) -> RaySet {
    let start = Instant::now();
    let scale = PowerScale::for_max_power(1.0);
    let units = scale.units(1.0);
    let n = cfg.photons;
    let batches = (ids.start / BATCH)..n.min(ids.end).div_ceil(BATCH);
    let segments: Vec<Segment> = batches
        .into_par_iter()
        .flat_map_iter(|b| {
            let mut rng = stream(&[domain::LINES, cfg.seed, point, replica, b]);
            let lo = b * BATCH;
            let hi = (lo + BATCH).min(n);
            let ids = ids.clone();
            (lo..hi).filter_map(move |id| {
                let (p, d) = uniform_line(&mut rng);
                // The chord from p along d has length −2 p·d (p on the unit sphere).
                let chord = -2.0 * p.dot(d);
                ids.contains(&id)
                    .then(|| Segment::new(p - d, d, 1.0 + chord, 2.0 + chord, units, id as u32))
            })
        })
        .collect();
    let n = segments.len() as u64;
    RaySet {
        store: SegmentStore::new(segments, scale),
        // The root holds every disc (points lie in the unit ball, discs reach d beyond it), so no disc
        // falls back to all segments; the lines stay μ-random in the unit ball, the law's sphere.
        root: (DVec3::ZERO, 1.0 + cfg.disc_radius),
        law_radius: 1.0,
        law_ball: Some((DVec3::ZERO, 1.0)),
        rays_in_root: n,
        trace_s: start.elapsed().as_secs_f64(),
        edge_s: 0.0,
        segments_direct: 0,
        direct: None,
    }
}

/// Expected irradiance of μ-random lines of 1 W on a disc inside the unit ball: a flat disc's
/// "surface area" is 2πd², so a line meets it with probability 2πd²/4π = d²/2 (Crofton), half of
/// those cross from the front, and E = n_R·(d²/4)/(πd²) = n_R/(4π) whatever d and the normal.
pub(super) fn exact(n_r: u64, c: DVec3, d: f64) -> f64 {
    if c.length() + d <= 1.0 {
        n_r as f64 / (4.0 * std::f64::consts::PI)
    } else {
        f64::NAN
    }
}
