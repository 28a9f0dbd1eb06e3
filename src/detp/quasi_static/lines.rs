//! μ-random lines as the rays of a quasi-static run (kind `quasi-static` with
//! `detp.source = "lines"`: eq. 11's own assumption, the control of f_R = n_R·(r_D/r_0)²).
//!
//! Line `id` is drawn from its own stream `[LINES, seed, id]` (two points uniform on the unit
//! sphere: a μ-random chord, the law of kind `detp`'s lines), so it can be drawn again alone. It
//! is one segment of 1 W that starts 1 unit before its entry into the unit ball and, unless a
//! mover stops it, ends 1 unit past its exit (as kind `detp` stores a line); a mover is opaque and
//! absorbing: the segment's first impact is the mover's surface and its counted part ends where the
//! line leaves the mover. "Re-tracing" a line is intersecting it with the movers at the new pose,
//! a pure function of (seed, id, pose), so incremental equals full bit for bit as for photons.

use std::ops::Range;

use glam::DVec3;
use rayon::prelude::*;

use super::super::fixed::{PowerScale, Units};
use super::super::store::{Segment, SegmentStore};
use crate::lt::Scene;
use crate::sample::lines::uniform_line;
use crate::sample::rng::{domain, stream};

/// Lines per parallel work item (each line keeps its own stream: the result does not depend on it).
const BATCH: u64 = 1024;

/// The power scale and units of one line: 1 W each.
pub fn line_units() -> (PowerScale, Units) {
    let scale = PowerScale::for_max_power(1.0);
    (scale, scale.units(1.0))
}

/// The segment of line `id` against the scene's movers at their current pose.
pub fn trace_line(scene: &Scene, seed: u64, id: u32) -> Segment {
    let mut rng = stream(&[domain::LINES, seed, u64::from(id)]);
    let (p, d) = uniform_line(&mut rng);
    // The chord from p along d has length −2 p·d (p on the unit sphere).
    let chord = -2.0 * p.dot(d);
    let (exit, end) = (1.0 + chord, 2.0 + chord);
    let origin = p - d;
    let eps = scene.precision().offset();
    let (hit, t_next) = scene.first_two_hits(origin, d, eps, None);
    let (t_hit, t_end) = match hit {
        Some(h) if h.t < end => (h.t, t_next.min(end)),
        _ => (exit, end),
    };
    Segment::new(origin, d, t_hit, t_end, line_units().1, id)
}

/// The lines `ids` of a run of `lines` lines, one segment each, in id order, with the photon index
/// spanning every id (empty outside `ids`), as [`crate::detp::photon::trace_photon_range`] stores
/// photons.
pub fn trace_lines(scene: &Scene, ids: Range<u64>, lines: u64, seed: u64) -> SegmentStore {
    assert!(
        lines > 0 && lines <= u64::from(u32::MAX) && ids.end <= lines,
        "line count out of range"
    );
    let lo = ids.start;
    let segments: Vec<Segment> = (0..(ids.end - lo).div_ceil(BATCH))
        .into_par_iter()
        .flat_map_iter(|b| {
            let hi = (lo + (b + 1) * BATCH).min(ids.end);
            (lo + b * BATCH..hi).map(|id| trace_line(scene, seed, id as u32))
        })
        .collect();
    let mut photon_start = Vec::with_capacity(lines as usize + 1);
    photon_start.extend(std::iter::repeat_n(0, lo as usize));
    photon_start.extend((0..segments.len() as u32).take((ids.end - lo) as usize));
    let n = segments.len() as u32;
    photon_start.extend(std::iter::repeat_n(n, (lines - ids.end) as usize + 1));
    let mut store = SegmentStore::new(segments, line_units().0);
    store.photon_start = photon_start;
    store
}

/// The box every line's segment lies in: 1 unit beyond the unit ball on each side.
pub fn lines_bounds() -> crate::geom::Aabb {
    crate::geom::Aabb::new(DVec3::splat(-2.0), DVec3::splat(2.0))
}

/// The scene of a lines run: no static geometry, one absorbing sphere of radius `ratio` (r_0 = 1)
/// whose centre circles the ball's centre once over the frames on a circle of radius
/// (1 − ratio)/2 in the z = 0 plane (so it stays inside the ball, halfway between the centre and
/// the rim); a point light at the centre and a small static square at z = 10 that no line reaches
/// (every segment stays within 2 of the centre) are there because a scene needs a light and a
/// static surface: no line uses either, and the run's static points are its own.
pub fn lines_scene(ratio: f64) -> Scene {
    let orbit = (1.0 - ratio) / 2.0;
    let text = format!(
        r#"
[[surface]]
name = "moving sphere"
kind = "sphere"
center = [{orbit:?}, 0.0, 0.0]
radius = {ratio:?}
albedo = 0.0
dynamic = "sphere"

[[dynamic]]
name = "sphere"
path = "circle"
center = [0.0, 0.0, 0.0]
radius = {orbit:?}
axis = [0.0, 0.0, 1.0]
turns = 1.0

[[surface]]
name = "unreached static square"
kind = "quad"
vertices = [[-0.1, -0.1, 10.0], [0.1, -0.1, 10.0], [0.1, 0.1, 10.0], [-0.1, 0.1, 10.0]]
albedo = 0.0

[[light]]
kind = "point"
position = [0.0, 0.0, 0.0]
power = 1.0
"#
    );
    Scene::parse(
        &text,
        std::path::Path::new("(lines: a sphere circling in the unit ball)"),
    )
    .expect("the lines' scene is well formed for every ratio in (0, 1)")
}
