//! Embree 3 over a light-transport scene's triangles, as a [`Caster`]: the baseline the photon
//! tracer and the reference path tracer are timed against in `raycost bench`.
//!
//! One `RTC_GEOMETRY_TYPE_TRIANGLE` mesh (f32 vertices, build quality high), `primID` = the index
//! in `Scene::triangles`; spheres (the bench scenes have none) are tested in f64 as the scene
//! does. What it answers, and how it differs from the exact core:
//! - the nearest hit: `rtcIntersect1` (f32, Embree's watertight test); t is Embree's f32 t;
//! - the second crossing: a second `rtcIntersect1` from just past the first (t₁·(1 + 10⁻⁶)), so a
//!   shared edge's twin hit is skipped as the exact core's 10⁻¹² rule skips it;
//! - any hit before a distance: `rtcOccluded1`.
//!
//! Embree cannot skip the triangle a ray leaves; like f32 renderers it starts rays at
//! max(t_min, 2⁻¹⁶·M) (M the scene's magnitude), past its own f32 self-intersection noise.

use std::ptr;

use anyhow::{bail, Result};
use glam::DVec3;

use super::ffi;
use crate::lt::cast::Caster;
use crate::lt::{Hit, Prim, Scene};

/// Embree's BVH over a scene's triangles (as posed when built).
pub struct EmbreeTriangles<'s> {
    device: ffi::RTCDevice,
    scene: ffi::RTCScene,
    lt: &'s Scene,
    /// Rays start no nearer than this (f32 self-intersection noise).
    floor: f64,
}

// SAFETY: as for `EmbreeScene`: a committed scene is only read, and Embree documents queries on it
// as thread-safe; `lt` is a shared reference.
unsafe impl Send for EmbreeTriangles<'_> {}
unsafe impl Sync for EmbreeTriangles<'_> {}

impl Drop for EmbreeTriangles<'_> {
    fn drop(&mut self) {
        // SAFETY: both handles were created by `build` and are released exactly once.
        unsafe {
            if !self.scene.is_null() {
                ffi::rtcReleaseScene(self.scene);
            }
            if !self.device.is_null() {
                ffi::rtcReleaseDevice(self.device);
            }
        }
    }
}

impl<'s> EmbreeTriangles<'s> {
    /// Builds over `lt`'s triangles (f32), build quality high.
    pub fn build(lt: &'s Scene) -> Result<Self> {
        let tris = &lt.triangles;
        // SAFETY: plain FFI calls in the documented order; every handle is owned by `this`, whose
        // Drop releases it, so early returns do not leak.
        unsafe {
            let device = ffi::rtcNewDevice(ptr::null());
            if device.is_null() {
                bail!("rtcNewDevice failed (is libembree3 usable on this CPU?)");
            }
            let mut this = Self {
                device,
                scene: ptr::null_mut(),
                lt,
                floor: (-16f64).exp2() * lt.magnitude(),
            };
            this.scene = ffi::rtcNewScene(device);
            this.check("rtcNewScene")?;
            ffi::rtcSetSceneBuildQuality(this.scene, ffi::RTC_BUILD_QUALITY_HIGH);
            if !tris.is_empty() {
                let geom = ffi::rtcNewGeometry(device, ffi::RTC_GEOMETRY_TYPE_TRIANGLE);
                this.check("rtcNewGeometry")?;
                ffi::rtcSetGeometryBuildQuality(geom, ffi::RTC_BUILD_QUALITY_HIGH);
                let vb = ffi::rtcSetNewGeometryBuffer(
                    geom,
                    ffi::RTC_BUFFER_TYPE_VERTEX,
                    0,
                    ffi::RTC_FORMAT_FLOAT3,
                    12,
                    3 * tris.len(),
                ) as *mut [f32; 3];
                let ib = ffi::rtcSetNewGeometryBuffer(
                    geom,
                    ffi::RTC_BUFFER_TYPE_INDEX,
                    0,
                    ffi::RTC_FORMAT_UINT3,
                    12,
                    tris.len(),
                ) as *mut [u32; 3];
                if vb.is_null() || ib.is_null() {
                    ffi::rtcReleaseGeometry(geom);
                    this.check("rtcSetNewGeometryBuffer")?;
                    bail!("rtcSetNewGeometryBuffer returned null");
                }
                let v = std::slice::from_raw_parts_mut(vb, 3 * tris.len());
                let ix = std::slice::from_raw_parts_mut(ib, tris.len());
                for (k, t) in tris.iter().enumerate() {
                    for j in 0..3 {
                        v[3 * k + j] = t.v[j].as_vec3().to_array();
                    }
                    let b = 3 * k as u32;
                    ix[k] = [b, b + 1, b + 2];
                }
                ffi::rtcCommitGeometry(geom);
                ffi::rtcAttachGeometry(this.scene, geom);
                ffi::rtcReleaseGeometry(geom);
                this.check("geometry setup")?;
            }
            ffi::rtcCommitScene(this.scene);
            this.check("rtcCommitScene")?;
            Ok(this)
        }
    }

    fn check(&self, what: &str) -> Result<()> {
        super::check(self.device, what)
    }

    fn ray(&self, o: DVec3, d: DVec3, t_min: f64, limit: f64) -> ffi::RTCRay {
        ffi::RTCRay {
            org_x: o.x as f32,
            org_y: o.y as f32,
            org_z: o.z as f32,
            tnear: t_min.max(self.floor) as f32,
            dir_x: d.x as f32,
            dir_y: d.y as f32,
            dir_z: d.z as f32,
            time: 0.0,
            tfar: limit as f32,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        }
    }

    /// One `rtcIntersect1`: the nearest triangle hit in [t_min, limit] (index, f32 t).
    fn intersect(&self, o: DVec3, d: DVec3, t_min: f64, limit: f64) -> Option<(u32, f64)> {
        // SAFETY: a committed scene.
        unsafe { ffi::intersect1(self.scene, self.ray(o, d, t_min, limit)) }
            .map(|(i, t)| (i, f64::from(t)))
    }

    /// The nearest sphere root in (t_min, limit), in f64 as the scene tests spheres.
    fn ball(&self, o: DVec3, d: DVec3, t_min: f64, limit: f64) -> Option<(u32, f64)> {
        let mut best = None;
        let mut bt = limit;
        for (i, b) in self.lt.balls.iter().enumerate() {
            if let Some((t0, t1)) = b.roots(o, d) {
                for r in [t0, t1] {
                    if r > t_min && r < bt {
                        bt = r;
                        best = Some((i as u32, r));
                    }
                }
            }
        }
        best
    }

    fn hit(&self, tri: Option<(u32, f64)>, ball: Option<(u32, f64)>) -> Option<Hit> {
        let (prim, t) = match (tri, ball) {
            (Some((_, tt)), Some((b, tb))) if tb < tt => (Prim::Ball(b), tb),
            (Some((i, tt)), _) => (Prim::Triangle(i), tt),
            (None, Some((b, tb))) => (Prim::Ball(b), tb),
            (None, None) => return None,
        };
        let surface = match prim {
            Prim::Triangle(i) => self.lt.triangles[i as usize].surface,
            Prim::Ball(i) => self.lt.balls[i as usize].surface,
        };
        Some(Hit { t, prim, surface })
    }
}

impl Caster for EmbreeTriangles<'_> {
    fn first_two_hits(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        _skip: Option<Prim>,
    ) -> (Option<Hit>, f64) {
        let Some(h) = self.first_hit_before(o, d, t_min, f64::INFINITY, None) else {
            return (None, f64::INFINITY);
        };
        let next = self.first_hit_before(o, d, h.t * (1.0 + 1e-6), f64::INFINITY, None);
        (Some(h), next.map_or(f64::INFINITY, |n| n.t))
    }

    fn first_hit_before(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        limit: f64,
        _skip: Option<Prim>,
    ) -> Option<Hit> {
        let tri = self.intersect(o, d, t_min, limit);
        let ball = if self.lt.balls.is_empty() {
            None
        } else {
            self.ball(o, d, t_min, limit)
        };
        self.hit(tri, ball)
    }

    fn occluded(&self, o: DVec3, d: DVec3, t_min: f64, limit: f64, _skip: Option<Prim>) -> bool {
        if self.ball(o, d, t_min, limit).is_some() {
            return true;
        }
        let mut ctx = ffi::RTCIntersectContext::new();
        let mut ray = self.ray(o, d, t_min, limit);
        // SAFETY: a committed scene, an initialised context and ray.
        unsafe { ffi::rtcOccluded1(self.scene, &mut ctx, &mut ray) };
        ray.tfar == f32::NEG_INFINITY
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    #[test]
    fn embree_agrees_with_the_exact_core_on_the_cornell_box() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/scenes/cornell.toml");
        let scene = Scene::load(&path).expect("the Cornell box");
        let e = EmbreeTriangles::build(&scene).expect("Embree");
        let mut rng = crate::sample::rng::stream(&[5]);
        let (mut agree, mut total) = (0, 0);
        for _ in 0..2000 {
            // Inside the box, above the blocks; the box is open at z = 0.
            let o = DVec3::new(278.0, 450.0, 280.0);
            let d = crate::sample::directions::uniform_direction(&mut rng);
            let (want, got) = match (
                scene.first_hit(o, d, 1e-6, None),
                e.first_hit(o, d, 1e-6, None),
            ) {
                (None, None) => continue,
                (Some(w), Some(g)) => (w, g),
                other => panic!("{other:?}"),
            };
            total += 1;
            if got.prim == want.prim || got.surface == want.surface {
                agree += 1;
            }
            assert!(
                (got.t - want.t).abs() <= 1e-4 * want.t,
                "{got:?} vs {want:?}"
            );
            assert!(!e.occluded(o, d, 1e-6, want.t * (1.0 - 1e-4), None));
            assert!(e.occluded(o, d, 1e-6, want.t * (1.0 + 1e-4), None));
        }
        assert!(agree * 1000 >= total * 999, "{agree} of {total}");
    }
}
