//! The grid query the paper analyses, and the brute-force oracle it must agree with.
//!
//! Walk the cells a ray pierces in order; in each, test every listed sphere; stop in the first cell
//! whose exit distance is at least the nearest hit found so far (a hit counts only once the walk has
//! reached the cell that holds it: the paper's nearest-hit rule, since lists are unordered). Spheres
//! that contain the eye are tested (they are listed) but never hit. Ties in `t` go to the smaller id,
//! in both the grid and the brute force, so the two agree exactly whenever the grid tests the winner.

use super::{mailbox::Mailbox, CellLists, Dda};
use crate::geom::{Ray, Sphere};

/// The first sphere a ray enters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The sphere's id.
    pub id: u64,
    /// Distance along the (unit-direction) ray.
    pub t: f64,
}

impl Hit {
    /// Is `(t, id)` nearer than `best` (ties to the smaller id)?
    #[inline]
    pub(crate) fn beats(t: f64, id: u64, best: &Option<Hit>) -> bool {
        match best {
            None => true,
            Some(b) => t < b.t || (t == b.t && id < b.id),
        }
    }
}

/// What one ray's query cost and found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TraceCounts {
    /// N_I: ray–sphere tests, a sphere listed in several visited cells counted each time.
    pub n_i: u32,
    /// Distinct spheres tested (the N_I of a mailboxed grid).
    pub n_i_mb: u32,
    /// N_S: cell steps (cells visited − 1).
    pub n_s: u32,
    /// The first hit, if any.
    pub hit: Option<Hit>,
    /// True if the walk was cut off by `max_steps` before finding a hit or leaving the grid.
    pub truncated: bool,
}

/// Traces `ray` through `lists`. With `skip_repeats` (mailboxing) a sphere already tested by this ray
/// is not tested again; the counts of both variants are reported either way, so the flag only changes
/// the time taken. `max_steps` bounds the walk in an unbounded grid.
#[inline]
pub fn trace<L: CellLists + ?Sized>(
    lists: &mut L,
    ray: &Ray,
    mailbox: &mut Mailbox,
    skip_repeats: bool,
    max_steps: u32,
) -> TraceCounts {
    let frame = *lists.frame();
    let mut counts = TraceCounts::default();
    let mut best: Option<Hit> = None;
    mailbox.clear();
    let mut walk = WalkState::default();
    for (cell, _t_enter, t_exit) in Dda::new(&frame, ray) {
        walk.enter(t_exit);
        let magnitude = lists.pad_magnitude(cell);
        let list = lists.list(cell);
        // Most cells of a fine grid list nothing: their box is never needed.
        let cb = if list.is_empty() {
            crate::geom::Aabb::new(frame.origin, frame.origin)
        } else {
            frame.cell_box(cell)
        };
        for s in list {
            counts.n_i += 1;
            // A sphere whose padded box lies strictly inside this cell is listed here only, so it
            // cannot come again: count it as distinct without touching the mailbox.
            let reach = s.r + frame.pad(magnitude, s.r);
            let alone = (s.c - reach).cmpgt(cb.lo).all() && (s.c + reach).cmplt(cb.hi).all();
            if alone || mailbox.insert(s.id) {
                counts.n_i_mb += 1;
            } else if skip_repeats {
                continue;
            }
            if let Some(t) = s.intersect(ray) {
                if Hit::beats(t, s.id, &best) {
                    best = Some(Hit { id: s.id, t });
                }
            }
        }
        if walk.stops(&best, t_exit, max_steps, &mut counts) {
            break;
        }
    }
    walk.finish(best, &mut counts);
    counts
}

/// A walk's bookkeeping and stopping rule, the same in every tracer.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct WalkState {
    visited: u32,
    last_exit: f64,
    stopped: bool,
}

impl WalkState {
    /// Records a visited cell, left at `t_exit`.
    #[inline(always)]
    pub(crate) fn enter(&mut self, t_exit: f64) {
        self.visited += 1;
        self.last_exit = t_exit;
    }

    /// Whether the walk stops after the cell left at `t_exit`: the nearest hit found lies within
    /// it (no later cell can hold a nearer one), or `max_steps` cells were visited (truncated if
    /// nothing was found).
    #[inline(always)]
    pub(crate) fn stops(
        &mut self,
        best: &Option<Hit>,
        t_exit: f64,
        max_steps: u32,
        counts: &mut TraceCounts,
    ) -> bool {
        if matches!(best, Some(b) if b.t <= t_exit) {
            self.stopped = true;
        } else if self.visited > max_steps {
            counts.truncated = best.is_none();
            self.stopped = true;
        }
        self.stopped
    }

    /// Completes `counts` with N_S and the hit.
    #[inline(always)]
    pub(crate) fn finish(&self, best: Option<Hit>, counts: &mut TraceCounts) {
        counts.n_s = self.visited.saturating_sub(1);
        // The ray left a finite grid: a sphere entered beyond the last cell (listed because it
        // pokes into the grid) is outside the indexed region, so it is not this grid's hit.
        counts.hit = if self.stopped {
            best
        } else {
            best.filter(|b| b.t <= self.last_exit)
        };
    }
}

/// The distance at which `ray` leaves the finite grid of `frame` (as the DDA computes it), or ∞.
pub fn exit_distance(frame: &crate::grid::GridFrame, ray: &Ray) -> f64 {
    Dda::new(frame, ray)
        .last()
        .map_or(f64::INFINITY, |(_, _, t)| t)
}

/// The first sphere `ray` enters among all of `spheres` (the oracle), with the same tie rule.
pub fn brute_force(spheres: &[Sphere], ray: &Ray) -> Option<Hit> {
    let mut best = None;
    for s in spheres {
        if let Some(t) = s.intersect(ray) {
            if Hit::beats(t, s.id, &best) {
                best = Some(Hit { id: s.id, t });
            }
        }
    }
    best
}
