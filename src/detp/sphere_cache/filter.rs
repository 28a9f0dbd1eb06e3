//! The ray–sphere filter that builds every list of the sphere cache, and the exact rule it answers.
//!
//! # The rule: when a segment *meets* a sphere
//! Segment (o, v, t ∈ [0, t_end]) meets sphere (s, r) at level j when, computed in f64,
//! `|v·t_c − w|² ≤ (r + κ_j·(|w| + r))²` with `w = s − o` and `t_c = clamp(w·v / v·v, 0, t_end)`
//! (the closest point of the segment to s). The tolerance `κ_j = 2⁻³⁰·(1 − j/256)` is far above
//! rounding (a few ulps of `|w| + r`, i.e. ~10⁻¹⁵ relative) and far below any radius in use, and
//! it *shrinks with depth*. Two facts follow, derived with every f64 operation rounding by at most
//! ε = 2⁻⁵³ and `|w|` bounding every length in the formula (so each computed distance is within
//! ~20ε·(|w| + r) of the true one):
//! 1. **Containment.** If a disc (c, d) satisfies `|c − s| + d ≤ r` (computed), every segment that
//!    [`crate::detp::disc::crosses`] accepts meets the sphere: `crosses` accepted at some computed
//!    t ∈ (0, t_end], and the point o + v·t lies within `d + 10ε·(|c − o| + d)` of c, hence within
//!    `r + 20ε·(|w| + r)` of s; the closest point is no farther, and its computed distance adds
//!    another ~20ε·(|w| + r), all below `κ_j·(|w| + r) ≥ 2⁻³⁸·(|w| + r)` for j < 256.
//! 2. **Nesting.** If sphere A at level i encloses sphere C at level j > i
//!    (`|s_C − s_A| + r_C ≤ r_A`, computed), every segment that meets C meets A: the true distance
//!    to s_A is at most the distance to s_C plus `|s_C − s_A|`, so at most
//!    `r_A + κ_j·(|w_A| + r_A) + 40ε·(|w_A| + r_A)`, and `κ_i − κ_j ≥ 2⁻³⁸` exceeds the rounding
//!    terms by a factor of ~10⁵. This is what lets a child take its list from any enclosing
//!    ancestor and still hold exactly the segments that meet it.
//!
//! # Why the f32 filter decides only what it may
//! Lists are SoA f32: origin relative to a reference point (the root's centre), direction (the
//! stored f32, exact), t_end (the stored f32, exact). A lane computes in f32 the same closest-point
//! distance `q` for the probe sphere (centre rounded to f32 relative to the reference). With
//! `Λ = max|o − ref| + |s − ref| + r` bounding every length involved and u = 2⁻²⁴, rounding the
//! origin and centre moves w by ≤ 3uΛ; b = w·d by ≤ 7uΛ; using w·d instead of w·v/|v|² (|v|² is
//! 1 within 3u) moves the clamp parameter by ≤ 4uΛ, which moves the distance at most as much (the
//! distance to points of a line is 1-Lipschitz in the position along it); forming p = d·t − w and
//! |p| adds ≤ 13uΛ. So `√q` is within ~30uΛ < 2⁻¹⁹Λ of the distance the exact rule computes. With
//! the margin `m = 2⁻¹⁶·Λ` (8× that):
//! - `q ≤ (r − m)²` ⇒ the exact rule accepts (its threshold is ≥ r);
//! - `q > (r + κ_j·Λ + m)²` ⇒ it rejects;
//! - otherwise the lane is decided by the exact f64 rule on the stored segment.
//!
//! So every path (AVX-512, AVX2, portable, with or without FMA) produces exactly the list of
//! segments the exact rule accepts, in source order; the tests force each path and compare.

use glam::DVec3;

use crate::detp::store::Segment;

// The AVX-512 intrinsics are stable since Rust 1.89, the crate's MSRV.
#[cfg(target_arch = "x86_64")]
mod x86;

/// Lanes a list has room for before a filter first grows it.
const FIRST_ROOM: usize = 1024;

/// The deepest level a cache may build: keeps `κ_j` positive and ≥ 2⁻³⁸ (see the module doc).
pub const MAX_LEVEL: usize = 255;

/// Relative tolerance of the exact rule at `level` (see the module doc).
#[inline]
pub fn kappa(level: usize) -> f64 {
    assert!(
        level <= MAX_LEVEL,
        "sphere cache level {level} > {MAX_LEVEL}"
    );
    (1.0 - level as f64 / 256.0) * (-30f64).exp2()
}

/// The exact rule: does `seg` meet the sphere (s, r) with tolerance `kappa`?
#[inline]
pub fn meets(seg: &Segment, s: DVec3, r: f64, kappa: f64) -> bool {
    let o = seg.o();
    let v = seg.d();
    let w = s - o;
    // max/min rather than clamp: t_end is positive by construction, but a NaN must not panic.
    let t = (w.dot(v) / v.length_squared()).max(0.0).min(seg.t_end());
    let p = v * t - w;
    let tol = r + kappa * (w.length() + r);
    p.length_squared() <= tol * tol
}

/// A list of segments in SoA f32 (origin relative to the list frame's reference point), with the
/// store index of each lane.
#[derive(Clone, Debug, Default)]
pub struct RayList {
    ox: Vec<f32>,
    oy: Vec<f32>,
    oz: Vec<f32>,
    dx: Vec<f32>,
    dy: Vec<f32>,
    dz: Vec<f32>,
    te: Vec<f32>,
    idx: Vec<u32>,
}

impl RayList {
    /// Every segment of `segments`, origins relative to `reference`.
    pub fn from_segments(segments: &[Segment], reference: DVec3) -> Self {
        let mut l = Self::default();
        l.reserve(segments.len());
        for (i, s) in segments.iter().enumerate() {
            let o = s.o() - reference;
            l.push_lane(
                [o.x as f32, o.y as f32, o.z as f32],
                s.dir,
                s.t_end,
                i as u32,
            );
        }
        l
    }

    /// Number of lanes.
    #[inline]
    pub fn len(&self) -> usize {
        self.idx.len()
    }

    /// No lanes?
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.idx.is_empty()
    }

    /// Store indices of the lanes, in order.
    #[inline]
    pub fn indices(&self) -> &[u32] {
        &self.idx
    }

    /// Largest |origin| (relative to the reference) over the lanes, rounded up.
    pub fn origin_bound(&self) -> f64 {
        let mut m = 0f64;
        for i in 0..self.len() {
            let o = DVec3::new(
                f64::from(self.ox[i]),
                f64::from(self.oy[i]),
                f64::from(self.oz[i]),
            );
            m = m.max(o.length());
        }
        m * (1.0 + 1e-6)
    }

    /// The seven per-lane columns (not `idx`), for what is done to each alike.
    fn lanes_mut(&mut self) -> [&mut Vec<f32>; 7] {
        [
            &mut self.ox,
            &mut self.oy,
            &mut self.oz,
            &mut self.dx,
            &mut self.dy,
            &mut self.dz,
            &mut self.te,
        ]
    }

    fn clear(&mut self) {
        for v in self.lanes_mut() {
            v.clear();
        }
        self.idx.clear();
    }

    fn reserve(&mut self, n: usize) {
        for v in self.lanes_mut() {
            v.reserve(n);
        }
        self.idx.reserve(n);
    }

    /// Lanes every column can hold without reallocating.
    #[inline]
    fn capacity(&self) -> usize {
        [
            &self.ox, &self.oy, &self.oz, &self.dx, &self.dy, &self.dz, &self.te,
        ]
        .iter()
        .map(|v| v.capacity())
        .min()
        .unwrap_or(0)
        .min(self.idx.capacity())
    }

    /// Makes room for `len + 16` lanes after the vector paths wrote `len` lanes past the columns'
    /// lengths: the lengths are set to `len` first (those lanes are written), then every column
    /// grows (at least doubling, so a list that grows to L lanes reallocates O(log L) times).
    ///
    /// # Safety
    /// The first `len` lanes of every column must have been written.
    #[cold]
    unsafe fn room(&mut self, len: usize) {
        // SAFETY: the caller wrote the first `len` lanes of every column.
        unsafe { set_lanes(self, len) };
        let more = len.max(FIRST_ROOM) + 16;
        for v in self.lanes_mut() {
            v.reserve(more);
        }
        self.idx.reserve(more);
    }

    #[inline]
    fn push_lane(&mut self, o: [f32; 3], d: [f32; 3], te: f32, idx: u32) {
        self.ox.push(o[0]);
        self.oy.push(o[1]);
        self.oz.push(o[2]);
        self.dx.push(d[0]);
        self.dy.push(d[1]);
        self.dz.push(d[2]);
        self.te.push(te);
        self.idx.push(idx);
    }

    #[inline]
    fn copy_lane(&mut self, src: &RayList, i: usize) {
        self.push_lane(
            [src.ox[i], src.oy[i], src.oz[i]],
            [src.dx[i], src.dy[i], src.dz[i]],
            src.te[i],
            src.idx[i],
        );
    }
}

/// A sphere prepared for the f32 filter: centre relative to the reference, and the two squared
/// thresholds of the module doc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    s: [f32; 3],
    /// Lanes with q ≤ `sure2` meet the sphere.
    sure2: f32,
    /// Lanes with q > `maybe2` do not; those between are decided exactly.
    maybe2: f32,
    /// The sphere in f64, for the exact rule.
    center: DVec3,
    radius: f64,
    kappa: f64,
}

impl Probe {
    /// The probe for sphere (s, r) at a level of tolerance `kappa`, for lists whose origins lie
    /// within `origin_bound` of `reference`.
    pub fn new(reference: DVec3, origin_bound: f64, s: DVec3, r: f64, kappa: f64) -> Self {
        let rel = s - reference;
        let lambda = origin_bound + rel.length() + r;
        let m = lambda * (-16f64).exp2();
        let sure = (r - m).max(0.0);
        let maybe = r + kappa * lambda + m;
        Self {
            s: [rel.x as f32, rel.y as f32, rel.z as f32],
            // Rounding the thresholds to f32 moves them by 2⁻²⁴ relative, inside the margin.
            sure2: (sure * sure) as f32,
            maybe2: (maybe * maybe) as f32,
            center: s,
            radius: r,
            kappa,
        }
    }

    /// The exact rule for the stored segment.
    #[inline]
    pub fn exact(&self, seg: &Segment) -> bool {
        meets(seg, self.center, self.radius, self.kappa)
    }

    /// The f32 closest-point distance² of lane i (the portable path).
    #[inline]
    fn q(&self, l: &RayList, i: usize) -> f32 {
        let wx = self.s[0] - l.ox[i];
        let wy = self.s[1] - l.oy[i];
        let wz = self.s[2] - l.oz[i];
        let b = wx * l.dx[i] + wy * l.dy[i] + wz * l.dz[i];
        let t = b.max(0.0).min(l.te[i]);
        let px = l.dx[i] * t - wx;
        let py = l.dy[i] * t - wy;
        let pz = l.dz[i] * t - wz;
        px * px + py * py + pz * pz
    }
}

/// Which implementation of the filter runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterPath {
    /// 16 lanes (x86_64 with AVX-512 F and VL): masked compress-stores of the passing lanes.
    Avx512,
    /// 8 lanes (x86_64 with AVX2 and FMA).
    Avx2,
    /// One lane at a time, any CPU.
    Portable,
}

impl FilterPath {
    /// The fastest path this CPU has.
    pub fn detect() -> Self {
        Self::all_available()[0]
    }

    /// Every path this CPU can run, fastest first.
    pub fn all_available() -> Vec<Self> {
        [Self::Avx512, Self::Avx2, Self::Portable]
            .into_iter()
            .filter(|p| p.is_available())
            .collect()
    }

    /// Can this CPU run the path? (Feature detection is cached by std: cheap to ask per call.)
    pub fn is_available(self) -> bool {
        match self {
            Self::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Self::Avx512 => {
                is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl")
            }
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// Name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Avx512 => "avx512",
            Self::Avx2 => "avx2",
            Self::Portable => "portable",
        }
    }
}

/// Replaces `out` by the lanes of `src` whose segment meets the probe's sphere (the exact rule),
/// in order. `segments` is the store the lane indices point into.
///
/// # Panics
/// If `path` is not available on this CPU.
pub fn filter(
    path: FilterPath,
    src: &RayList,
    probe: &Probe,
    segments: &[Segment],
    out: &mut RayList,
) {
    out.clear();
    // Room for a first block; the vector paths grow `out` as lanes are kept (`RayList::room`),
    // so a reused list keeps its capacity and holds no more than what it was ever asked to keep.
    out.reserve(FIRST_ROOM.min(src.len()) + 16);
    match path {
        FilterPath::Portable => portable(src, 0, probe, segments, out),
        #[cfg(target_arch = "x86_64")]
        FilterPath::Avx512 => {
            assert!(
                FilterPath::all_available().contains(&path),
                "no AVX-512 here"
            );
            // SAFETY: the CPU has AVX-512 F and VL (checked above); `out` is empty with room for
            // src.len() + 16 lanes.
            unsafe { x86::avx512(src, probe, segments, out) }
        }
        #[cfg(target_arch = "x86_64")]
        FilterPath::Avx2 => {
            assert!(path.is_available(), "no AVX2 here");
            // SAFETY: the CPU has AVX2 and FMA (checked above); `out` is empty with room for
            // src.len() + 16 lanes.
            unsafe { x86::avx2(src, probe, segments, out) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        _ => panic!("filter path {path:?} needs x86_64"),
    }
}

/// Sets every column of `out` to `len` lanes after the vector paths wrote them.
///
/// # Safety
/// The first `len` elements of every column must have been written (within capacity).
unsafe fn set_lanes(out: &mut RayList, len: usize) {
    for v in [
        &mut out.ox,
        &mut out.oy,
        &mut out.oz,
        &mut out.dx,
        &mut out.dy,
        &mut out.dz,
        &mut out.te,
    ] {
        // SAFETY: see the function's contract.
        unsafe { v.set_len(len) };
    }
    // SAFETY: as above.
    unsafe { out.idx.set_len(len) };
}

/// Lanes `from..` one at a time (the portable path, and the tail of the 8-lane path).
fn portable(src: &RayList, from: usize, probe: &Probe, segments: &[Segment], out: &mut RayList) {
    for i in from..src.len() {
        let q = probe.q(src, i);
        let keep =
            q <= probe.sure2 || (q <= probe.maybe2 && probe.exact(&segments[src.idx[i] as usize]));
        if keep {
            out.copy_lane(src, i);
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::Rng;

    use super::*;
    use crate::detp::fixed::PowerScale;
    use crate::detp::store::SegmentStore;
    use crate::sample::{lines::uniform_line, rng::stream};

    /// Lines through the unit ball, half of them with t_end = +∞, plus segments built to graze
    /// the probe sphere within a few ulps, from far and near origins.
    fn store(center: DVec3, r: f64) -> SegmentStore {
        let mut rng = stream(&[0xf1, 1]);
        let mut segs = Vec::new();
        for k in 0..20_000 {
            let (p, d) = uniform_line(&mut rng);
            let t_end = if k % 2 == 0 {
                f64::INFINITY
            } else {
                rng.gen_range(0.0..2.0)
            };
            segs.push(Segment::new(p, d, 0.0, t_end, 1, k));
        }
        for k in 0..4_000u32 {
            // A tangent line at distance r·(1 + δ), δ within ±8 ulps·scale, plus segments ending
            // just before/after the tangent point.
            let dir = crate::sample::lines::uniform_on_sphere(&mut rng);
            let side = dir.any_orthonormal_vector();
            let delta = f64::from(rng.gen_range(-8..=8)) * 1e-16;
            let foot = center + side * r * (1.0 + delta);
            let back = rng.gen_range(0.0..3.0);
            let t_end = if k % 3 == 0 {
                back * (1.0 + delta)
            } else {
                f64::INFINITY
            };
            segs.push(Segment::new(foot - dir * back, dir, 0.0, t_end, 1, k));
        }
        SegmentStore::new(segs, PowerScale::for_max_power(1.0))
    }

    #[test]
    fn every_path_gives_exactly_the_exact_rules_list() {
        for (center, r, reference) in [
            (DVec3::new(0.1, -0.2, 0.3), 0.05, DVec3::ZERO),
            (DVec3::new(0.5, 0.5, 0.0), 0.3, DVec3::new(0.01, 0.0, 0.0)),
            (DVec3::ZERO, 1e-3, DVec3::ZERO),
        ] {
            let st = store(center, r);
            let all = RayList::from_segments(&st.segments, reference);
            let probe = Probe::new(reference, all.origin_bound(), center, r, kappa(3));
            let paths = FilterPath::all_available();
            #[cfg(target_arch = "x86_64")]
            {
                use std::is_x86_feature_detected as has;
                if has!("avx512f") && has!("avx512vl") {
                    assert!(paths.contains(&FilterPath::Avx512), "CPU paths: {paths:?}");
                }
                if has!("avx2") && has!("fma") {
                    assert!(paths.contains(&FilterPath::Avx2), "CPU paths: {paths:?}");
                }
            }
            // Every tail length of the 8- and 16-lane loops.
            for len in (st.len() - 17..=st.len()).chain(0..20) {
                let src = RayList::from_segments(&st.segments[..len], reference);
                let want: Vec<u32> = (0..len as u32)
                    .filter(|&i| meets(&st.segments[i as usize], center, r, kappa(3)))
                    .collect();
                if len == st.len() {
                    assert!(!want.is_empty() && want.len() < len);
                }
                for &path in &paths {
                    let mut out = RayList::default();
                    filter(path, &src, &probe, &st.segments, &mut out);
                    assert_eq!(out.indices(), &want[..], "{path:?} at r = {r}, {len} lanes");
                    // The copied lanes are the source lanes.
                    for (k, &i) in out.indices().iter().enumerate() {
                        let seg = &st.segments[i as usize];
                        assert_eq!((out.te[k], out.dx[k]), (seg.t_end, seg.dir[0]));
                        assert_eq!(out.ox[k], all.ox[i as usize]);
                    }
                }
            }
        }
    }

    #[test]
    fn grazing_segments_are_decided_by_the_exact_rule_near_the_threshold() {
        // A tangent at distance exactly r meets; one at r·(1 + 10⁻⁶) does not.
        let st = SegmentStore::new(
            vec![
                Segment::new(DVec3::new(-1.0, 0.25, 0.0), DVec3::X, 0.0, 2.0, 1, 0),
                Segment::new(
                    DVec3::new(-1.0, 0.25 * (1.0 + 1e-6), 0.0),
                    DVec3::X,
                    0.0,
                    2.0,
                    1,
                    1,
                ),
                // Ends short of the sphere: the closest point is its end.
                Segment::new(DVec3::new(-1.0, 0.0, 0.0), DVec3::X, 0.0, 0.7, 1, 2),
                Segment::new(DVec3::new(-1.0, 0.0, 0.0), DVec3::X, 0.0, 0.76, 1, 3),
            ],
            PowerScale::for_max_power(1.0),
        );
        let src = RayList::from_segments(&st.segments, DVec3::ZERO);
        let probe = Probe::new(DVec3::ZERO, src.origin_bound(), DVec3::ZERO, 0.25, kappa(1));
        for path in FilterPath::all_available() {
            let mut out = RayList::default();
            filter(path, &src, &probe, &st.segments, &mut out);
            assert_eq!(out.indices(), &[0, 3], "{path:?}");
        }
    }

    #[test]
    fn tolerance_shrinks_with_depth() {
        assert!(kappa(0) > kappa(1) && kappa(MAX_LEVEL) > 0.0);
        assert!(kappa(MAX_LEVEL) >= (-38f64).exp2());
    }
}
