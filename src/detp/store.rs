//! The ray store: every photon segment that DETP reads, compactly, with the photon it belongs to.
//!
//! A segment starts at `origin` and runs along `dir` for t ∈ (0, `t_end`]. `t_hit` is its first impact
//! with the scene (where the photon bounced or died); `t_end` is the *second* intersection of its line
//! with the scene, or +∞ if there is none — the DETP paper counts crossings up to the second
//! intersection so that discs on concave surfaces, whose tangent plane lies behind the surface, are
//! not shadowed by the surface they approximate.
//!
//! Layout (56 bytes, checked at compile time): the origin stays f64 (a scene can sit far from the
//! origin); the direction is rounded to f32 once, and every test widens it back to f64 exactly, so all
//! engines see the very same line; `t_hit`/`t_end` are f32 (7 significant digits along a segment is
//! far below any disc radius in use); power is an integer ([`crate::detp::fixed`]). What is stored is
//! the truth every engine uses: a segment is never re-derived from the tracer's f64 values.

use glam::DVec3;

use super::fixed::{PowerScale, Units};

/// One stored segment.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Segment {
    /// Start point.
    pub origin: [f64; 3],
    /// Direction (unit length before rounding to f32; tests do not assume unit length).
    pub dir: [f32; 3],
    /// First impact with the scene, in units of `dir` (f32::INFINITY if it left the scene).
    pub t_hit: f32,
    /// End of the counted part: the second intersection (f32::INFINITY if none). t_end ≥ t_hit.
    pub t_end: f32,
    /// Power in units of the store's [`PowerScale`].
    pub power: Units,
    /// The photon this segment belongs to (its index: the key of its random stream).
    pub photon: u32,
    /// Bounce number along the photon's path (0: leaving the light).
    pub bounce: u16,
    /// Free bits for engines and the quasi-static layer (e.g. "met a dynamic object").
    pub flags: u16,
}

const _: () = assert!(std::mem::size_of::<Segment>() == 56);

impl Segment {
    /// Origin as a vector.
    #[inline]
    pub fn o(&self) -> DVec3 {
        DVec3::from_array(self.origin)
    }

    /// Direction widened to f64 (exact).
    #[inline]
    pub fn d(&self) -> DVec3 {
        DVec3::new(
            f64::from(self.dir[0]),
            f64::from(self.dir[1]),
            f64::from(self.dir[2]),
        )
    }

    /// End of the counted part, widened to f64 (+∞ stays +∞).
    #[inline]
    pub fn t_end(&self) -> f64 {
        f64::from(self.t_end)
    }

    /// A segment from f64 values: the direction is normalised in f64 and then rounded to f32.
    pub fn new(
        origin: DVec3,
        dir: DVec3,
        t_hit: f64,
        t_end: f64,
        power: Units,
        photon: u32,
    ) -> Self {
        let d = dir.normalize();
        assert!(
            d.is_finite(),
            "segment direction must be non-zero and finite"
        );
        Self {
            origin: origin.to_array(),
            dir: [d.x as f32, d.y as f32, d.z as f32],
            t_hit: t_hit as f32,
            t_end: t_end as f32,
            power,
            photon,
            bounce: 0,
            flags: 0,
        }
    }
}

/// All segments of a run, in photon order, with the power scale that gives their units meaning.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentStore {
    /// The segments; those of photon p are `segments[photon_start[p]..photon_start[p + 1]]` when
    /// `photon_start` is filled (photon tracing), else in any order (e.g. uniform lines).
    pub segments: Vec<Segment>,
    /// Offsets of each photon's segments (len = photons + 1), or empty.
    pub photon_start: Vec<u32>,
    /// Watts per power unit.
    pub scale: PowerScale,
}

impl SegmentStore {
    /// A store of `segments` (any order, no photon index).
    pub fn new(segments: Vec<Segment>, scale: PowerScale) -> Self {
        assert!(
            segments.len() < u32::MAX as usize,
            "a store holds fewer than 2³² segments, so no accumulator can overflow"
        );
        Self {
            segments,
            photon_start: Vec::new(),
            scale,
        }
    }

    /// Number of segments.
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    /// Is it empty?
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// Bytes held (segments and photon offsets).
    pub fn bytes(&self) -> usize {
        self.segments.len() * std::mem::size_of::<Segment>() + self.photon_start.len() * 4
    }

    /// `n` μ-random lines through the unit ball as segments from their first point on the sphere
    /// (t_end = +∞ for even k, the chord for odd k), powers 1..1000 from `rng`: the unit tests'
    /// store. The draws per line: the line, then the power.
    #[cfg(test)]
    pub fn test_lines<R: rand::Rng>(rng: &mut R, n: u32) -> Self {
        let segs = (0..n)
            .map(|k| {
                let (p, d) = crate::sample::lines::uniform_line(rng);
                let t_end = if k % 2 == 0 {
                    f64::INFINITY
                } else {
                    -2.0 * p.dot(d)
                };
                Segment::new(p, d, 0.0, t_end, rng.gen_range(1..1000), k)
            })
            .collect();
        Self::new(segs, PowerScale::for_max_power(1.0))
    }

    /// The segments of photon `p` (requires `photon_start`).
    pub fn photon(&self, p: usize) -> &[Segment] {
        let (a, b) = (
            self.photon_start[p] as usize,
            self.photon_start[p + 1] as usize,
        );
        &self.segments[a..b]
    }
}
