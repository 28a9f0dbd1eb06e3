//! Scene sources of kind `detp`: photons traced from a scene file's lights, sample points on its
//! surfaces (or read from a CSV), the exact irradiance where the scene has a closed form, and the
//! photon-map baseline over the same photons.

use std::time::Instant;

use super::{PointSet, RaySet};
use crate::detp::disc::Discs;
use crate::detp::photon::trace_photons;
use crate::detp::photon_map::{self, Filter};
use crate::detp::sphere_cache::root_sphere;
use crate::detp::store::SegmentStore;
use crate::detp::surface_points::{read_points_csv, surface_points};
use crate::geom::Aabb;
use crate::lt::Scene;
use crate::sample::rng::{domain, hash_key};
use crate::spec::detp::{FilterChoice, Points, Rays};
use crate::spec::DetpConfig;

/// The scene of a scene-source point (None for lines).
pub(super) fn load(cfg: &DetpConfig) -> anyhow::Result<Option<Scene>> {
    match &cfg.rays {
        Rays::Lines => Ok(None),
        Rays::Scene(p) => Scene::load(p).map(Some).map_err(|e| anyhow::anyhow!("{e}")),
    }
}

/// Sample points on the scene's surfaces or from a CSV, with the scene's exact irradiance.
pub(super) fn points(cfg: &DetpConfig, point: u64, scene: &Scene) -> anyhow::Result<PointSet> {
    let (centers, normals) = match &cfg.points {
        Points::Surface(spacing) => surface_points(
            scene,
            *spacing,
            hash_key(&[domain::POINTS, cfg.seed, point]),
        ),
        Points::File(p) => read_points_csv(p).map_err(anyhow::Error::msg)?,
        Points::Ball(_) => {
            anyhow::bail!("points uniform in the ball belong to detp.source = \"lines\"")
        }
    };
    let discs = Discs::new(centers, normals, cfg.disc_radius).map_err(anyhow::Error::msg)?;
    let exact = discs
        .centers
        .iter()
        .zip(&discs.normals)
        .map(|(&p, &n)| scene.exact_irradiance(p, n).unwrap_or(f64::NAN))
        .collect();
    Ok(PointSet { discs, exact })
}

/// The photons of one replica, and a root sphere that holds the scene and every disc.
pub(super) fn photons(
    cfg: &DetpConfig,
    point: u64,
    replica: u64,
    scene: &Scene,
    discs: &Discs,
) -> RaySet {
    let start = Instant::now();
    let store = trace_photons(scene, cfg.photons, hash_key(&[cfg.seed, point, replica]));
    let trace_s = start.elapsed().as_secs_f64();
    let (b, d) = (scene.bounds(), discs.bounds_all());
    let root = root_sphere(&Aabb::new(b.lo.min(d.lo), b.hi.max(d.hi)));
    let n = store.len() as u64;
    RaySet {
        store,
        root,
        law_radius: root.1,
        law_ball: None,
        rays_in_root: n,
        trace_s,
    }
}

/// The photon-map estimate at every disc centre, from the impacts of the same photons.
pub(super) fn photon_map(cfg: &DetpConfig, store: &SegmentStore, discs: &Discs) -> Vec<f64> {
    let filter = match cfg.photon_map_filter {
        FilterChoice::Cone => Filter::Cone,
        FilterChoice::Disc => Filter::Disc,
    };
    photon_map::estimate(
        store,
        &discs.centers,
        &discs.normals,
        cfg.photon_map_k as usize,
        filter,
    )
}
