//! Kochanek–Bartels (tension–continuity–bias) keyframe splines, as BART's `k NAME` blocks drive its
//! animated transforms (`x NAME`).
//!
//! A `k` block lists up to three tracks, each `KIND N` followed by N keys:
//!
//! ```text
//! transl N   time  x y z            tension continuity bias   (N times)
//! rot N      time  ax ay az angle°  tension continuity bias
//! scale N    time  sx sy sz         tension continuity bias
//! ```
//!
//! **Semantics follow BART's reference code** (Eberly's `kbsplpos.c`/`kbsplrot.c`, shipped with
//! the benchmark). With four or more keys the *first and last keys are phantom control points*: the
//! curve runs from key 1 to key N−2 (0-based) and is clamped to those keys' values outside; the end
//! keys only shape the tangents at key 1 and key N−2. That is why BART files repeat their first and
//! last keys (the kitchen's `toycar` starts with −1.0 and 3.0 holding the same pose). Tangents are
//! the KB ones with Kochanek's time adjustment `2·Δt_out/(Δt_in+Δt_out)`, so with t = c = b = 0 the
//! curve is a Catmull–Rom spline that is C¹ *in time*, also for unevenly spaced keys. Tracks of two
//! or three keys (which the reference code cannot read) are padded with a repeated end key on each
//! side, so all their keys are interpolated; a single key is a constant.
//!
//! **Rotations** are interpolated as unit quaternions, as the reference code does: each axis/angle
//! key becomes a quaternion, consecutive keys are put on the same hemisphere (so the spline takes
//! the short way: 350° after 10° about one axis is a 20° turn, not 340°), and each segment is a
//! `squad(p, a, b, q)` whose inner control quaternions are built from the KB tangents in the
//! logarithmic (tangent) space, `a = p·exp((T_out − log(p⁻¹q))/2)`, `b = q·exp((log(p⁻¹q) − T_in)/2)`.
//! Rotation matrices are therefore orthonormal at every time.
//!
//! The transform of an animated node is `M = T · R · S` (scale first, then rotation, then
//! translation), as BART's `_GetMatrix` composes it; missing tracks are identity.

use glam::{DAffine3, DMat3, DQuat, DVec3};

/// One key of a track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KbKey<T> {
    /// Time.
    pub time: f64,
    /// Value.
    pub value: T,
    /// Tension (1: zero tangents).
    pub tension: f64,
    /// Continuity.
    pub continuity: f64,
    /// Bias.
    pub bias: f64,
}

/// What a KB track can interpolate: points (Hermite cubics) and rotations (squad).
pub trait KbValue: Copy + std::fmt::Debug + PartialEq {
    /// Adjusts the keys before segments are built (quaternions: normalise, same hemisphere).
    fn prepare(_keys: &mut [KbKey<Self>]) {}
    /// The four coefficients of the segment from `k[1]` to `k[2]` (`k[0]`, `k[3]` its neighbours).
    fn segment(k: [&KbKey<Self>; 4]) -> [Self; 4];
    /// The segment at parameter u ∈ [0, 1].
    fn eval(c: &[Self; 4], u: f64) -> Self;
}

/// Kochanek's multipliers of the outgoing tangent at `k[1]` and the incoming one at `k[2]`:
/// (out0, out1, in0, in1), weights of (P1−P0, P2−P1) and (P2−P1, P3−P2).
fn multipliers<T>(k: [&KbKey<T>; 4]) -> (f64, f64, f64, f64) {
    // As the reference code, but a zero denominator (three keys at one time) gives 1, not NaN.
    let adj = |num: f64, den: f64| if den != 0.0 { 2.0 * num / den } else { 1.0 };
    let (t0, t1, t2, t3) = (k[0].time, k[1].time, k[2].time, k[3].time);
    let a = k[1];
    let adj0 = adj(t2 - t1, t2 - t0);
    let out0 = 0.5 * adj0 * (1.0 - a.tension) * (1.0 + a.continuity) * (1.0 + a.bias);
    let out1 = 0.5 * adj0 * (1.0 - a.tension) * (1.0 - a.continuity) * (1.0 - a.bias);
    let b = k[2];
    let adj1 = adj(t2 - t1, t3 - t1);
    let in0 = 0.5 * adj1 * (1.0 - b.tension) * (1.0 - b.continuity) * (1.0 + b.bias);
    let in1 = 0.5 * adj1 * (1.0 - b.tension) * (1.0 + b.continuity) * (1.0 - b.bias);
    (out0, out1, in0, in1)
}

impl KbValue for DVec3 {
    fn segment(k: [&KbKey<Self>; 4]) -> [Self; 4] {
        let (out0, out1, in0, in1) = multipliers(k);
        let dp = k[2].value - k[1].value;
        let t_out = out1 * dp + out0 * (k[1].value - k[0].value);
        let t_in = in1 * (k[3].value - k[2].value) + in0 * dp;
        [
            k[1].value,
            t_out,
            3.0 * dp - 2.0 * t_out - t_in,
            -2.0 * dp + t_out + t_in,
        ]
    }

    fn eval(c: &[Self; 4], u: f64) -> Self {
        c[0] + u * (c[1] + u * (c[2] + u * c[3]))
    }
}

/// log of a unit quaternion: (0, θ·axis) with q = (cos θ, sin θ·axis), as a 4-vector.
fn qlog(q: DQuat) -> DQuat {
    let v = DVec3::new(q.x, q.y, q.z);
    let s = v.length();
    let theta = s.atan2(q.w);
    let k = if s > 1e-12 { theta / s } else { 1.0 };
    DQuat::from_xyzw(v.x * k, v.y * k, v.z * k, 0.0)
}

/// exp of a pure quaternion (0, v).
fn qexp(q: DQuat) -> DQuat {
    let v = DVec3::new(q.x, q.y, q.z);
    let theta = v.length();
    let k = if theta > 1e-12 {
        theta.sin() / theta
    } else {
        1.0
    };
    DQuat::from_xyzw(v.x * k, v.y * k, v.z * k, theta.cos())
}

/// Slerp without the shortest-path flip (squad needs the plain great-circle arc).
fn slerp_raw(p: DQuat, q: DQuat, t: f64) -> DQuat {
    let c = p.dot(q).clamp(-1.0, 1.0);
    let angle = c.acos();
    if angle.abs() < 1e-9 {
        return p;
    }
    let s = angle.sin();
    if s.abs() < 1e-12 {
        // Antipodal: no unique arc; fall back to a normalised lerp.
        return (p * (1.0 - t) + q * t).normalize();
    }
    p * (((1.0 - t) * angle).sin() / s) + q * ((t * angle).sin() / s)
}

impl KbValue for DQuat {
    fn prepare(keys: &mut [KbKey<Self>]) {
        let mut prev: Option<DQuat> = None;
        for k in keys {
            let mut q = k.value.normalize();
            if !q.is_finite() {
                q = DQuat::IDENTITY;
            }
            if let Some(p) = prev {
                if p.dot(q) < 0.0 {
                    q = -q;
                }
            }
            k.value = q;
            prev = Some(q);
        }
    }

    fn segment(k: [&KbKey<Self>; 4]) -> [Self; 4] {
        let (out0, out1, in0, in1) = multipliers(k);
        let (q0, q1, q2, q3) = (k[0].value, k[1].value, k[2].value, k[3].value);
        let logdq = qlog(q1.inverse() * q2);
        let t_out = logdq * out1 + qlog(q0.inverse() * q1) * out0;
        let t_in = logdq * in0 + qlog(q2.inverse() * q3) * in1;
        let a = q1 * qexp((t_out - logdq) * 0.5);
        let b = q2 * qexp((logdq - t_in) * 0.5);
        [q1, a, b, q2]
    }

    fn eval(c: &[Self; 4], u: f64) -> Self {
        let pq = slerp_raw(c[0], c[3], u);
        let ab = slerp_raw(c[1], c[2], u);
        slerp_raw(pq, ab, 2.0 * u * (1.0 - u)).normalize()
    }
}

#[derive(Clone, Debug, PartialEq)]
struct Segment<T> {
    t0: f64,
    t1: f64,
    c: [T; 4],
}

/// A Kochanek–Bartels track: keys with tension, continuity and bias (see the module notes for the
/// end-key convention). Evaluation clamps outside the key range; one key is a constant.
#[derive(Clone, Debug, PartialEq)]
pub struct KbTrack<T> {
    keys: Vec<KbKey<T>>,
    segments: Vec<Segment<T>>,
    sorted: bool,
}

impl<T: KbValue> KbTrack<T> {
    /// A track from its keys (at least one, finite times). Times should not decrease; BART's own
    /// files break that (the robots' `gun_rot` tracks jump back from 48 to 42), so decreasing times
    /// are accepted and evaluated as the reference code does: the first segment whose end time lies
    /// after `t` is used (see [`KbTrack::monotonic`]).
    pub fn new(mut keys: Vec<KbKey<T>>) -> Result<Self, crate::error::Invalid> {
        if keys.is_empty() {
            return Err("a keyframe track needs at least one key".into());
        }
        if keys.iter().any(|k| !k.time.is_finite()) {
            return Err("key times must be finite".into());
        }
        T::prepare(&mut keys);
        let n = keys.len();
        let mut ext: Vec<KbKey<T>> = Vec::new();
        let src: &[KbKey<T>] = if n == 2 || n == 3 {
            let mut first = keys[0];
            first.time = keys[0].time - (keys[1].time - keys[0].time);
            let mut last = keys[n - 1];
            last.time = keys[n - 1].time + (keys[n - 1].time - keys[n - 2].time);
            ext.push(first);
            ext.extend_from_slice(&keys);
            ext.push(last);
            &ext
        } else {
            &keys
        };
        let segments = src
            .windows(4)
            .map(|w| Segment {
                t0: w[1].time,
                t1: w[2].time,
                c: T::segment([&w[0], &w[1], &w[2], &w[3]]),
            })
            .collect();
        let sorted = keys.windows(2).all(|w| w[0].time <= w[1].time);
        Ok(KbTrack {
            keys,
            segments,
            sorted,
        })
    }

    /// Are the key times non-decreasing?
    pub fn monotonic(&self) -> bool {
        self.keys.windows(2).all(|w| w[0].time <= w[1].time)
    }

    /// The keys, as given (quaternions normalised and hemisphere-aligned).
    pub fn keys(&self) -> &[KbKey<T>] {
        &self.keys
    }

    /// The time range over which the curve moves (BART: key 1 to key N−2 for N ≥ 4).
    pub fn active_range(&self) -> (f64, f64) {
        match (self.segments.first(), self.segments.last()) {
            (Some(a), Some(b)) => (a.t0, b.t1),
            _ => (self.keys[0].time, self.keys[0].time),
        }
    }

    /// Value at `time` (clamped to the active range).
    pub fn at(&self, time: f64) -> T {
        let segs = &self.segments;
        let Some(first) = segs.first() else {
            return self.keys[0].value;
        };
        if time.is_nan() || time <= first.t0 {
            return T::eval(&first.c, 0.0);
        }
        let last = &segs[segs.len() - 1];
        if time >= last.t1 {
            return T::eval(&last.c, 1.0);
        }
        // The first segment with time < t1 (a binary search when the times are sorted).
        let i = if self.sorted {
            segs.partition_point(|s| s.t1 <= time)
        } else {
            segs.iter()
                .position(|s| time < s.t1)
                .unwrap_or(segs.len() - 1)
        }
        .min(segs.len() - 1);
        let s = &segs[i];
        let range = s.t1 - s.t0;
        let u = if range > 0.0 {
            ((time - s.t0) / range).clamp(0.0, 1.0)
        } else {
            0.0
        };
        T::eval(&s.c, u)
    }
}

/// A rotation key's value from BART's axis and angle in degrees (a zero axis is the identity).
pub fn axis_angle_deg(axis: DVec3, angle_deg: f64) -> DQuat {
    let a = axis.normalize_or_zero();
    if a == DVec3::ZERO {
        return DQuat::IDENTITY;
    }
    DQuat::from_axis_angle(a, angle_deg.to_radians())
}

/// The keyframed transform of an animated node: `M(t) = T(t) · R(t) · S(t)`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KbTransform {
    /// Translation track.
    pub translate: Option<KbTrack<DVec3>>,
    /// Rotation track (quaternions, from axis + angle keys).
    pub rotate: Option<KbTrack<DQuat>>,
    /// Scale track.
    pub scale: Option<KbTrack<DVec3>>,
}

impl KbTransform {
    /// The transform at `time`.
    pub fn at(&self, time: f64) -> DAffine3 {
        let t = self.translate.as_ref().map_or(DVec3::ZERO, |k| k.at(time));
        let r = self.rotate.as_ref().map_or(DQuat::IDENTITY, |k| k.at(time));
        let s = self.scale.as_ref().map_or(DVec3::ONE, |k| k.at(time));
        DAffine3 {
            matrix3: DMat3::from_quat(r) * DMat3::from_diagonal(s),
            translation: t,
        }
    }
}

/// One level of a transform chain.
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    /// A static transform (one or more merged `xs`).
    Fixed(DAffine3),
    /// A keyframed transform `x NAME` with its `k NAME` tracks.
    Animated {
        /// Its name.
        name: String,
        /// Its tracks.
        kb: KbTransform,
    },
}

impl Node {
    /// The transform at `time`.
    pub fn at(&self, time: f64) -> DAffine3 {
        match self {
            Node::Fixed(m) => *m,
            Node::Animated { kb, .. } => kb.at(time),
        }
    }
}

/// The product of a chain of transforms (outermost first) at `time`.
pub fn compose(chain: &[Node], time: f64) -> DAffine3 {
    chain.iter().fold(DAffine3::IDENTITY, |m, n| m * n.at(time))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key<T>(time: f64, value: T, t: f64, c: f64, b: f64) -> KbKey<T> {
        KbKey {
            time,
            value,
            tension: t,
            continuity: c,
            bias: b,
        }
    }

    fn sample_track(t: f64, c: f64, b: f64) -> KbTrack<DVec3> {
        let pts = [
            (-1.0, DVec3::new(0.0, 0.0, 0.0)),
            (0.0, DVec3::new(1.0, 2.0, 0.5)),
            (0.7, DVec3::new(2.0, -1.0, 1.0)),
            (2.0, DVec3::new(0.5, 0.3, 4.0)),
            (2.5, DVec3::new(-3.0, 1.0, 2.0)),
            (4.0, DVec3::new(1.0, 1.0, 1.0)),
        ];
        KbTrack::new(pts.iter().map(|&(tm, v)| key(tm, v, t, c, b)).collect()).unwrap()
    }

    #[test]
    fn passes_through_keys() {
        for (t, c, b) in [
            (0.0, 0.0, 0.0),
            (0.3, -0.5, 0.75),
            (1.0, 0.0, 0.0),
            (-0.4, 0.9, -1.0),
        ] {
            let tr = sample_track(t, c, b);
            // BART's end keys are phantoms: the curve passes through keys 1..N-2.
            for k in &tr.keys()[1..tr.keys().len() - 1] {
                assert!((tr.at(k.time) - k.value).length() < 1e-12, "{t} {c} {b}");
            }
        }
        // Two and three keys: all of them.
        for n in [2, 3] {
            let keys: Vec<_> = (0..n)
                .map(|i| {
                    key(
                        i as f64 * 1.5,
                        DVec3::splat(i as f64 * i as f64),
                        0.0,
                        0.0,
                        0.0,
                    )
                })
                .collect();
            let tr = KbTrack::new(keys.clone()).unwrap();
            for k in &keys {
                assert!((tr.at(k.time) - k.value).length() < 1e-12);
            }
        }
    }

    #[test]
    fn catmull_rom_is_c1_in_time() {
        let tr = sample_track(0.0, 0.0, 0.0);
        let h = 1e-6;
        for k in &tr.keys()[2..tr.keys().len() - 2] {
            let left = (tr.at(k.time) - tr.at(k.time - h)) / h;
            let right = (tr.at(k.time + h) - tr.at(k.time)) / h;
            assert!(
                (left - right).length() < 1e-4,
                "{left} vs {right} at {}",
                k.time
            );
        }
        // A continuity of 0.8 breaks it (sanity of the test).
        let tr = sample_track(0.0, 0.8, 0.0);
        let k = tr.keys()[2];
        let left = (tr.at(k.time) - tr.at(k.time - h)) / h;
        let right = (tr.at(k.time + h) - tr.at(k.time)) / h;
        assert!((left - right).length() > 1e-2);
    }

    #[test]
    fn tension_one_gives_zero_tangents() {
        let tr = sample_track(1.0, 0.0, 0.0);
        let h = 1e-7;
        for k in &tr.keys()[1..tr.keys().len() - 1] {
            for t in [k.time - h, k.time + h] {
                if t > tr.active_range().0 && t < tr.active_range().1 {
                    let d = (tr.at(t) - tr.at(k.time)).length() / h;
                    assert!(d < 1e-4, "speed {d} at key {}", k.time);
                }
            }
        }
    }

    #[test]
    fn single_key_is_constant_and_clamping() {
        let tr = KbTrack::new(vec![key(3.0, DVec3::new(1.0, 2.0, 3.0), 0.2, 0.1, 0.0)]).unwrap();
        for t in [-100.0, 0.0, 3.0, 7.5, f64::NAN] {
            assert_eq!(tr.at(t), DVec3::new(1.0, 2.0, 3.0));
        }
        let tr = sample_track(0.0, 0.0, 0.0);
        assert_eq!(tr.at(-50.0), tr.at(0.0));
        assert_eq!(tr.at(50.0), tr.at(2.5));
        assert!(KbTrack::<DVec3>::new(vec![]).is_err());
        // Decreasing times (as in BART's robot files) are accepted and stay finite.
        let tr = KbTrack::new(vec![
            key(0.0, DVec3::ZERO, 0.0, 0.0, 0.0),
            key(1.0, DVec3::X, 0.0, 0.0, 0.0),
            key(2.0, DVec3::Y, 0.0, 0.0, 0.0),
            key(1.5, DVec3::Z, 0.0, 0.0, 0.0),
            key(2.5, DVec3::ONE, 0.0, 0.0, 0.0),
            key(3.0, DVec3::ONE, 0.0, 0.0, 0.0),
        ])
        .unwrap();
        assert!(!tr.monotonic());
        for i in 0..40 {
            assert!(tr.at(i as f64 * 0.1).is_finite());
        }
        // Repeated times (BART's robot camera starts with two keys at 0.0) are harmless.
        let tr = KbTrack::new(vec![
            key(0.0, DVec3::ZERO, 0.0, 0.0, 0.0),
            key(0.0, DVec3::ZERO, 0.0, 0.0, 0.0),
            key(1.0, DVec3::X, 0.0, 0.0, 0.0),
            key(2.0, DVec3::Y, 0.0, 0.0, 0.0),
        ])
        .unwrap();
        assert!(tr.at(0.5).is_finite());
        assert!((tr.at(1.0) - DVec3::X).length() < 1e-12);
    }

    fn rot_track() -> KbTrack<DQuat> {
        let keys = [
            (-1.0, DVec3::Y, 180.0),
            (0.0, DVec3::Y, 180.0),
            (1.0, DVec3::new(1.0, 1.0, 0.0), 45.0),
            (2.0, DVec3::new(0.0, 0.3, 1.0), -120.0),
            (3.0, DVec3::X, 350.0),
            (4.0, DVec3::X, 10.0),
            (5.0, DVec3::X, 10.0),
        ];
        KbTrack::new(
            keys.iter()
                .map(|&(t, a, d)| key(t, axis_angle_deg(a, d), 0.1, -0.2, 0.3))
                .collect(),
        )
        .unwrap()
    }

    #[test]
    fn rotations_pass_keys_and_stay_orthonormal() {
        let tr = rot_track();
        for k in &tr.keys()[1..tr.keys().len() - 1] {
            let q = tr.at(k.time);
            assert!(q.dot(k.value).abs() > 1.0 - 1e-12, "{q} vs {}", k.value);
        }
        let kb = KbTransform {
            translate: None,
            rotate: Some(tr),
            scale: None,
        };
        for i in 0..=400 {
            let m = kb.at(-0.5 + i as f64 * 0.0137).matrix3;
            let e = m.transpose() * m - DMat3::IDENTITY;
            let err = e.x_axis.length() + e.y_axis.length() + e.z_axis.length();
            assert!(err < 1e-12, "not orthonormal: {err}");
            assert!((m.determinant() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn rotation_takes_the_short_way() {
        // 350° then 10° about x: a 20° turn, so halfway is near 0°.
        let tr = rot_track();
        let q = tr.at(3.5);
        let (_, angle) = q.to_axis_angle();
        let angle = angle.to_degrees();
        let angle = if angle > 180.0 { 360.0 - angle } else { angle };
        assert!(angle < 15.0, "halfway between 350° and 10° is {angle}°");
    }

    #[test]
    fn transform_is_t_r_s() {
        let one = |v: DVec3| KbTrack::new(vec![key(0.0, v, 0.0, 0.0, 0.0)]).unwrap();
        let kb = KbTransform {
            translate: Some(one(DVec3::new(1.0, 2.0, 3.0))),
            rotate: Some(
                KbTrack::new(vec![key(
                    0.0,
                    axis_angle_deg(DVec3::Z, 90.0),
                    0.0,
                    0.0,
                    0.0,
                )])
                .unwrap(),
            ),
            scale: Some(one(DVec3::new(2.0, 1.0, 1.0))),
        };
        let p = kb.at(0.0).transform_point3(DVec3::X);
        // scale x by 2 → (2,0,0); rotate 90° about z → (0,2,0); translate → (1,4,3).
        assert!((p - DVec3::new(1.0, 4.0, 3.0)).length() < 1e-12);
        let chain = [
            Node::Fixed(DAffine3::from_translation(DVec3::X)),
            Node::Animated {
                name: "a".into(),
                kb,
            },
        ];
        let p = compose(&chain, 0.0).transform_point3(DVec3::X);
        assert!((p - DVec3::new(2.0, 4.0, 3.0)).length() < 1e-12);
    }
}
