//! Dynamic objects and their motion: what moves through a quasi-static scene, and where it is at
//! each frame.
//!
//! A [`Mover`] is rest geometry (triangles and spheres, in scene coordinates) plus a [`Motion`]. Its
//! pose at normalised time τ ∈ [0, 1] maps rest geometry to the world:
//! `world(p) = M(τ) · (c + s·(p − c))`, with c the centre of the rest geometry's bounding sphere and s
//! the uniform scale a spec applies to sweep r_D/r_0 (1: as in the file). Frame f of F is
//! τ = f / (F − 1) (τ = 0 for a single frame).
//!
//! Poses are pure functions of τ, so a frame's geometry never depends on which frames came before:
//! the incremental recalculation and a full recalculation of the same frame see the very same
//! triangles, bit for bit.

use glam::{DAffine3, DQuat, DVec3};

use super::shapes::{Ball, Triangle};

/// How a dynamic object moves. Paths move the rest geometry's bounding-sphere centre c along a curve
/// and spin it about c; keyframed chains (BART's `x NAME` transforms) map it wholesale.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// c travels `turns` times around a circle (centre, radius, unit axis), starting at
    /// `center + radius·u` with u ⟂ axis, while spinning `spin_deg` degrees about `spin_axis`.
    Circle {
        /// Circle centre.
        center: DVec3,
        /// Circle radius.
        radius: f64,
        /// Unit normal of the circle's plane.
        axis: DVec3,
        /// Turns over τ ∈ [0, 1].
        turns: f64,
        /// Spin about `spin_axis` through c over τ ∈ [0, 1], degrees.
        spin_deg: f64,
        /// Unit spin axis.
        spin_axis: DVec3,
    },
    /// c moves along the polyline through `points` at constant speed (τ = 0 at the first point, 1 at
    /// the last), spinning `spin_deg` degrees about `spin_axis`.
    Path {
        /// At least two points.
        points: Vec<DVec3>,
        /// Spin over τ ∈ [0, 1], degrees.
        spin_deg: f64,
        /// Unit spin axis.
        spin_axis: DVec3,
    },
    /// A chain of fixed and keyframed (Kochanek–Bartels) transforms, outermost first, evaluated at
    /// animation time `start + τ·(end − start)` (BART's `x NAME` / `k NAME`). The chain maps the
    /// part's own coordinates to the world.
    Keyframed {
        /// Outermost first.
        chain: Vec<super::spline::Node>,
        /// Animation time at τ = 0.
        start: f64,
        /// Animation time at τ = 1.
        end: f64,
    },
}

impl Motion {
    /// The map from rest geometry to the world at τ, for rest bounding-sphere centre `c`.
    pub fn pose(&self, c: DVec3, tau: f64) -> DAffine3 {
        let about_c = |pos: DVec3, spin: DQuat| {
            DAffine3::from_translation(pos)
                * DAffine3::from_quat(spin)
                * DAffine3::from_translation(-c)
        };
        match self {
            Motion::Circle {
                center,
                radius,
                axis,
                turns,
                spin_deg,
                spin_axis,
            } => {
                let (u, v) = axis.any_orthonormal_pair();
                let phi = std::f64::consts::TAU * turns * tau;
                let pos = *center + (u * phi.cos() + v * phi.sin()) * *radius;
                about_c(
                    pos,
                    DQuat::from_axis_angle(*spin_axis, (spin_deg * tau).to_radians()),
                )
            }
            Motion::Path {
                points,
                spin_deg,
                spin_axis,
            } => about_c(
                polyline_at(points, tau),
                DQuat::from_axis_angle(*spin_axis, (spin_deg * tau).to_radians()),
            ),
            Motion::Keyframed { chain, start, end } => {
                super::spline::compose(chain, start + tau * (end - start))
            }
        }
    }
}

/// The point at fraction `tau` of the polyline's length.
fn polyline_at(points: &[DVec3], tau: f64) -> DVec3 {
    let total: f64 = points.windows(2).map(|w| w[0].distance(w[1])).sum();
    if total == 0.0 {
        return points[0];
    }
    let mut left = tau.clamp(0.0, 1.0) * total;
    for w in points.windows(2) {
        let l = w[0].distance(w[1]);
        if left <= l && l > 0.0 {
            return w[0].lerp(w[1], left / l);
        }
        left -= l;
    }
    *points.last().expect("a path has points")
}

/// One rigidly moving group of a dynamic object: rest geometry and its motion.
#[derive(Clone, Debug, PartialEq)]
pub struct MoverPart {
    /// Rest triangles (surface ids index the scene's surfaces).
    pub triangles: Vec<Triangle>,
    /// Rest spheres (posed by their centre; the motion must not scale them unevenly).
    pub balls: Vec<Ball>,
    /// Its motion.
    pub motion: Motion,
}

/// A dynamic object: one or more parts (a BART car's body and wheels) that move together as one
/// object for DETP (one bounding sphere, one engine choice).
#[derive(Clone, Debug, PartialEq)]
pub struct Mover {
    /// Name (a scene file's `[[dynamic]] name`, or a BART transform's).
    pub name: String,
    /// Its parts.
    pub parts: Vec<MoverPart>,
    /// Centre of the rest geometry's bounding sphere (the scale's fixed point).
    pub rest_center: DVec3,
    /// Radius of the rest geometry's bounding sphere, before `scale`.
    pub rest_radius: f64,
    /// Uniform scale about `rest_center` (set by a spec's `dynamic.ratio`).
    pub scale: f64,
}

/// The posed geometry of one mover at one τ.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Posed {
    /// World triangles.
    pub triangles: Vec<Triangle>,
    /// World spheres.
    pub balls: Vec<Ball>,
}

impl Mover {
    /// A mover over `parts`, its bounding sphere taken from the rest geometry.
    pub fn new(name: String, parts: Vec<MoverPart>) -> Self {
        let (c, r) = bounding_sphere(
            parts
                .iter()
                .flat_map(|p| p.triangles.iter().flat_map(|t| t.v))
                .collect::<Vec<_>>()
                .as_slice(),
            &parts
                .iter()
                .flat_map(|p| p.balls.iter().copied())
                .collect::<Vec<_>>(),
        );
        Self {
            name,
            parts,
            rest_center: c,
            rest_radius: r,
            scale: 1.0,
        }
    }

    /// A keyframed object (BART): parts in their own coordinates, so its rest bounding sphere is
    /// taken at τ = 0 in the world (scale 1: it keeps its size).
    pub fn keyframed(name: String, parts: Vec<MoverPart>) -> Self {
        let mut m = Self::new(name, parts);
        (m.rest_center, m.rest_radius) = m.bounds_at(0.0);
        m
    }

    /// Does some part follow keyframes (so a spec cannot rescale it about a rest centre)?
    pub fn is_keyframed(&self) -> bool {
        self.parts
            .iter()
            .any(|p| matches!(p.motion, Motion::Keyframed { .. }))
    }

    /// The bounding-sphere radius of the scaled object (r_D).
    pub fn radius(&self) -> f64 {
        self.rest_radius * self.scale
    }

    /// Every part's map from rest geometry to the world at τ, scale included.
    fn maps(&self, tau: f64) -> impl Iterator<Item = (&MoverPart, DAffine3)> + '_ {
        let c = self.rest_center;
        let scale = DAffine3::from_translation(c)
            * DAffine3::from_scale(DVec3::splat(self.scale))
            * DAffine3::from_translation(-c);
        self.parts
            .iter()
            .map(move |p| (p, p.motion.pose(c, tau) * scale))
    }

    /// Each part's map from rest geometry to the world at τ (scale included), in part order.
    pub fn part_maps(&self, tau: f64) -> Vec<DAffine3> {
        self.maps(tau).map(|(_, m)| m).collect()
    }

    /// The object's geometry at τ.
    pub fn posed(&self, tau: f64) -> Posed {
        let mut out = Posed::default();
        for (part, m) in self.maps(tau) {
            let r_scale = m.matrix3.determinant().abs().cbrt();
            out.triangles
                .extend(part.triangles.iter().map(|t| Triangle {
                    v: t.v.map(|v| m.transform_point3(v)),
                    surface: t.surface,
                }));
            out.balls.extend(part.balls.iter().map(|b| Ball {
                center: m.transform_point3(b.center),
                radius: b.radius * r_scale,
                ..*b
            }));
        }
        out
    }

    /// A sphere holding the posed object at τ: the posed geometry's own bounding sphere.
    pub fn bounds_at(&self, tau: f64) -> (DVec3, f64) {
        let p = self.posed(tau);
        let v: Vec<DVec3> = p.triangles.iter().flat_map(|t| t.v).collect();
        bounding_sphere(&v, &p.balls)
    }
}

/// A sphere around points and balls: centred on their box's centre, radius the farthest reach.
pub fn bounding_sphere(points: &[DVec3], balls: &[Ball]) -> (DVec3, f64) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for &p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    for b in balls {
        lo = lo.min(b.center - DVec3::splat(b.radius));
        hi = hi.max(b.center + DVec3::splat(b.radius));
    }
    if !lo.is_finite() {
        return (DVec3::ZERO, 0.0);
    }
    let c = (lo + hi) * 0.5;
    let r = points
        .iter()
        .map(|&p| p.distance(c))
        .chain(balls.iter().map(|b| b.center.distance(c) + b.radius))
        .fold(0.0, f64::max);
    (c, r)
}

/// τ of frame `f` of `frames`.
pub fn tau(f: u32, frames: u32) -> f64 {
    if frames <= 1 {
        0.0
    } else {
        f64::from(f) / f64::from(frames - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube_part(motion: Motion) -> MoverPart {
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        MoverPart {
            triangles: vec![
                Triangle {
                    v: [v(-1.0, -1.0, -1.0), v(1.0, -1.0, -1.0), v(1.0, 1.0, 1.0)],
                    surface: 0,
                },
                Triangle {
                    v: [v(-1.0, 1.0, 1.0), v(-1.0, -1.0, 1.0), v(1.0, 1.0, -1.0)],
                    surface: 0,
                },
            ],
            balls: vec![],
            motion,
        }
    }

    #[test]
    fn circle_moves_the_centre_around_and_keeps_the_shape() {
        let m = Mover::new(
            "c".into(),
            vec![cube_part(Motion::Circle {
                center: DVec3::new(5.0, 0.0, 0.0),
                radius: 2.0,
                axis: DVec3::Z,
                turns: 1.0,
                spin_deg: 90.0,
                spin_axis: DVec3::Z,
            })],
        );
        assert!((m.rest_radius - 3f64.sqrt()).abs() < 1e-12);
        for k in 0..=8 {
            let tau = f64::from(k) / 8.0;
            let (c, r) = m.bounds_at(tau);
            assert!(
                (c.distance(DVec3::new(5.0, 0.0, 0.0)) - 2.0).abs() < 1e-9,
                "{c}"
            );
            assert!(r <= m.radius() * (1.0 + 1e-12) + 1e-12);
            let p = m.posed(tau);
            let t = p.triangles[0];
            assert!((t.area() - m.parts[0].triangles[0].area()).abs() < 1e-9);
        }
        assert!(m.bounds_at(0.0).0.distance(m.bounds_at(1.0).0) < 1e-9);
    }

    #[test]
    fn scale_changes_the_radius_about_the_rest_centre() {
        let mut m = Mover::new(
            "s".into(),
            vec![cube_part(Motion::Path {
                points: vec![DVec3::new(0.0, 0.0, 0.0), DVec3::new(4.0, 0.0, 0.0)],
                spin_deg: 0.0,
                spin_axis: DVec3::Y,
            })],
        );
        m.scale = 0.25;
        let (c, r) = m.bounds_at(0.5);
        assert!(c.distance(DVec3::new(2.0, 0.0, 0.0)) < 1e-12);
        assert!((r - 0.25 * 3f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn polyline_is_walked_at_constant_speed() {
        let pts = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 3.0, 0.0)];
        assert_eq!(polyline_at(&pts, 0.0), DVec3::ZERO);
        assert!(polyline_at(&pts, 0.25).distance(DVec3::X) < 1e-12);
        assert!(polyline_at(&pts, 1.0).distance(pts[2]) < 1e-12);
        assert_eq!(tau(0, 1), 0.0);
        assert_eq!(tau(9, 10), 1.0);
    }
}
