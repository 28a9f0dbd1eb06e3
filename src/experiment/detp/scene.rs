//! Scene sources of kind `detp`: photons traced from a scene file's lights, sample points on its
//! surfaces (or read from a CSV), the exact irradiance where the scene has a closed form, and the
//! photon-map baseline over the same photons.

use std::ops::Range;
use std::time::Instant;

use super::config::{DetpConfig, Direct, Points};
use super::{PointSet, RaySet};
use crate::detp::disc::Discs;
use crate::detp::indirect::indirect_store;
use crate::detp::edge::{clamped_radii, clip_to_first_hit};
use crate::detp::photon::trace_photon_range;
use crate::detp::sphere_cache::root_sphere;
use crate::detp::surface_points::open_surface_points;
use crate::error::{Error, InputError};
use crate::geom::Aabb;
use crate::lt::Scene;
use crate::sample::rng::hash_key;
use crate::sample::subset::keyed_prefix;
use glam::DVec3;

/// Sample points on the scene's surfaces or from a CSV, with the scene's exact irradiance.
/// (The lattice is deterministic and a subsample of it keyed by the seed alone: every sweep point of
/// a scene gets the same surface points.)
pub(super) fn points(cfg: &DetpConfig, scene: &Scene) -> Result<PointSet, Error> {
    let (centers, normals, covered) = match &cfg.points {
        Points::Surface(s) => {
            let (c, n, k) = open_surface_points(scene, s.spacing);
            let (c, n) = match s.keep {
                Some(keep) => keyed_subsample(cfg, c, n, keep)?,
                None => (c, n),
            };
            (c, n, Some(k))
        }
        Points::File(p) => (p.centers.clone(), p.normals.clone(), None),
        Points::Ball(_) | Points::Grid(_) => {
            unreachable!("the spec check gives a scene surface or file points")
        }
    };
    if centers.is_empty() {
        return Err(no_open_points(cfg, covered));
    }
    let mut discs = Discs::new(centers, normals, cfg.disc_radius).map_err(Error::internal)?;
    let start = Instant::now();
    if let (Some(min), Some(factor)) = (cfg.edge.clamp_min(), cfg.edge.clamp_factor()) {
        let (c, n) = (&discs.centers, &discs.normals);
        let radii = clamped_radii(scene, c, n, discs.radius, min, factor);
        discs = discs.with_radii(radii).map_err(Error::internal)?;
    }
    let edge_s = start.elapsed().as_secs_f64();
    let exact = discs
        .centers
        .iter()
        .zip(&discs.normals)
        .map(|(&p, &n)| scene.exact_irradiance(p, n).unwrap_or(f64::NAN))
        .collect();
    Ok(PointSet {
        discs,
        exact,
        edge_s,
        covered,
    })
}

/// The first `keep` open lattice points of the permutation keyed by the seed (never the sweep point:
/// the same n gives the same points everywhere, a smaller n a prefix); refused when the lattice holds
/// fewer.
fn keyed_subsample(
    cfg: &DetpConfig,
    centers: Vec<DVec3>,
    normals: Vec<DVec3>,
    keep: u64,
) -> Result<(Vec<DVec3>, Vec<DVec3>), Error> {
    let Some(ids) = keyed_prefix(centers.len(), keep as usize, cfg.seed) else {
        let file = cfg
            .scene()
            .map_or_else(String::new, |s| s.path.display().to_string());
        let spacing = match &cfg.points {
            Points::Surface(s) => s.spacing,
            _ => f64::NAN,
        };
        return Err(InputError::new(
            file,
            format!(
                "got {keep} points, but the surface lattice of spacing {spacing} holds only {} open points: give fewer points or a smaller detp.point_spacing",
                centers.len()
            ),
        )
        .key("detp.points")
        .into());
    };
    Ok(ids.iter().map(|&i| (centers[i], normals[i])).unzip())
}

/// Every lattice point covered (exactly coincident surfaces cover each other: a floor given twice):
/// nothing to measure, said by what covers what rather than an engine's panic on zero discs.
fn no_open_points(cfg: &DetpConfig, covered: Option<u64>) -> Error {
    let file = cfg
        .scene()
        .map_or_else(String::new, |s| s.path.display().to_string());
    let why = match covered {
        Some(k) => format!(
            "all {k} surface points are covered by other geometry (a surface within the contact \
             distance along each point's normal, or inside a solid); exactly coincident surfaces \
             cover each other: remove the duplicate, or give points with point_source = \"file\""
        ),
        None => "the points file holds no points".to_string(),
    };
    InputError::new(file, format!("no sample points to measure: {why}"))
        .key("detp.scene")
        .into()
}

/// The photons `ids` of one replica (all of them unless `--photon-shard` splits them), and a root sphere that holds the scene and every disc.
pub(super) fn photons(
    cfg: &DetpConfig,
    point: u64,
    replica: u64,
    ids: Range<u64>,
    scene: &Scene,
    discs: &Discs,
) -> RaySet {
    let start = Instant::now();
    let key = hash_key(&[cfg.seed, point, replica]);
    let mut store = trace_photon_range(scene, ids, cfg.photons, key);
    let trace_s = start.elapsed().as_secs_f64();
    let start = Instant::now();
    if let Some(gap) = cfg.edge.first_hit_gap() {
        clip_to_first_hit(&mut store, gap * cfg.disc_radius);
    }
    let edge_s = start.elapsed().as_secs_f64();
    // `detp.direct = "nee"`: the engines read the segments after the first bounce only (timed as
    // part of making the rays).
    let start = Instant::now();
    let traced = store.len() as u64;
    if let Direct::Nee(_) = cfg.direct {
        store = indirect_store(&store);
    }
    let trace_s = trace_s + start.elapsed().as_secs_f64();
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
        edge_s,
        segments_direct: traced - n,
        direct: None,
    }
}
