//! What the photon tracer and the reference path tracer ask of a ray caster, as a trait: the
//! scene's own exact core ([`Scene`]) answers it, and so does Intel Embree (feature `embree`,
//! `crate::embree::EmbreeTriangles`), so `raycost bench` can time both engines on the same
//! light-transport loops.

use glam::DVec3;

use super::{Hit, Prim, Scene};

/// A ray caster over a scene's geometry. Every query ignores crossings at t ≤ t_min and the
/// triangle `skip` (the surface a ray leaves).
pub trait Caster: Sync {
    /// The nearest hit and the t of the next crossing beyond it (+∞ if none).
    fn first_two_hits(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        skip: Option<Prim>,
    ) -> (Option<Hit>, f64);
    /// The nearest hit with t < `limit`.
    fn first_hit_before(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        limit: f64,
        skip: Option<Prim>,
    ) -> Option<Hit>;
    /// Is there any hit with t < `limit`?
    fn occluded(&self, o: DVec3, d: DVec3, t_min: f64, limit: f64, skip: Option<Prim>) -> bool;
    /// The nearest hit.
    fn first_hit(&self, o: DVec3, d: DVec3, t_min: f64, skip: Option<Prim>) -> Option<Hit> {
        self.first_hit_before(o, d, t_min, f64::INFINITY, skip)
    }
}

impl Caster for Scene {
    fn first_two_hits(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        skip: Option<Prim>,
    ) -> (Option<Hit>, f64) {
        Scene::first_two_hits(self, o, d, t_min, skip)
    }
    fn first_hit_before(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        limit: f64,
        skip: Option<Prim>,
    ) -> Option<Hit> {
        Scene::first_hit_before(self, o, d, t_min, limit, skip)
    }
    fn occluded(&self, o: DVec3, d: DVec3, t_min: f64, limit: f64, skip: Option<Prim>) -> bool {
        Scene::occluded(self, o, d, t_min, limit, skip)
    }
}
