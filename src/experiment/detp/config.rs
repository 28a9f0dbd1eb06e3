//! `[detp]` validated: what a DETP point needs, in the engines' own types ([`DetpConfig`]), with
//! the checks that span keys, one part of the table at a time: where the rays come from
//! ([`Rays::from_raw`]), where the points sit ([`Points::from_raw`]), which engines run, d, the
//! sphere cache and the index, and the edge remedy. The scene and points files are loaded once per
//! run through [`Inputs`], so a missing or bad file is refused before anything is written.
//!
//! This is the interface of the DETP module that kind `quasi-static` and `raycost render` use too.

use std::sync::Arc;

use glam::DVec3;

use super::spec::{
    DirectChoice, DiscRadius, LengthUnit, EdgeChoice, EngineChoice, FilterChoice, IndexChoice, ListModeChoice, OrderChoice,
    PointSourceKind, PopRuleChoice, RawDetp, RaySource, EDGE_GAP, EDGE_MIN_RADIUS,
    EDGE_RADIUS_FACTOR, RADIUS_SCHEDULE_EXPONENT,
};
use super::estimators::{self, Role};
use crate::detp::disc_index::IndexKind;
use crate::detp::edge::EdgeMode;
use crate::detp::order::Order;
use crate::detp::photon_map::KGrowth;
use crate::detp::sphere_cache::{ListMode, PopRule, SphereCacheParams};
use crate::experiment::inputs::{Inputs, PointsFile, SceneFile};
use crate::experiment::kind::{refuse, ConfigError};
use crate::geom::Aabb;
use crate::theory::detp::scheduled_radius;

/// The rays of a point.
#[derive(Clone, Debug)]
pub enum Rays {
    /// μ-random lines through the unit ball.
    Lines,
    /// Photons traced from this scene (loaded once per run).
    Scene(Arc<SceneFile>),
}

/// The sample points of a point.
#[derive(Clone, Debug)]
pub enum Points {
    /// n points uniform in the unit ball with uniform normals.
    Ball(u64),
    /// k³ points on eq. 4's lattice (k per side, spacing 2/(√3·k)) with uniform normals.
    Grid(u64),
    /// On the scene's surfaces: a lattice, or a keyed nested subsample of it.
    Surface(SurfacePoints),
    /// Read from a CSV (once per run).
    File(Arc<PointsFile>),
}

/// Surface points: the lattice of `detp.point_spacing` on the scene's open surfaces and, with
/// `detp.points = n`, the first n of its permutation keyed by the seed alone
/// ([`crate::sample::subset::keyed_prefix`]): the same n on the same scene and spacing gives the
/// same points at every sweep point, and a smaller n keeps a prefix of a larger one's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoints {
    /// The lattice's spacing (scene units).
    pub spacing: f64,
    /// The points kept from the lattice (all of them when `None`).
    pub keep: Option<u64>,
}

/// Everything a DETP point needs, validated, in the engines' own types.
#[derive(Clone, Debug)]
pub struct DetpConfig {
    /// Master seed.
    pub seed: u64,
    /// Ray source.
    pub rays: Rays,
    /// n_R.
    pub photons: u64,
    /// Point source.
    pub points: Points,
    /// d: `detp.disc_radius` in scene units, or with a radius schedule d(N) at this point's
    /// photons (every engine's d; surface points keep the spacing of the unscheduled d).
    pub disc_radius: f64,
    /// `detp.radius_schedule_photons` and `_exponent` (None: d is fixed).
    pub radius_schedule: Option<RadiusSchedule>,
    /// Scene units per unit of `detp.length_unit` (r_s for `"root"`, else 1).
    pub length_scale: f64,
    /// r_s: the radius of the sphere around the scene's bounds (1 for lines).
    pub root_radius: f64,
    /// Point order of the sphere cache.
    pub order: Order,
    /// Key bits per axis of the order.
    pub order_bits: u32,
    /// The sphere cache's Q, threshold, list mode and chunking (its `law_ball` is set per replica).
    pub cache: SphereCacheParams,
    /// The disc index.
    pub index: IndexKind,
    /// Engines, in spec order.
    pub engines: Vec<EngineChoice>,
    /// Points checked against brute force.
    pub brute_force_points: u64,
    /// Photon-map k.
    pub photon_map_k: u64,
    /// Photon-map filter.
    pub photon_map_filter: FilterChoice,
    /// Paths per sample point of the reference.
    pub reference_samples: u64,
    /// Engine `photon-map-growing`'s k(N).
    pub k_growth: KGrowth,
    /// K: paths per point of engine `path-tracing`.
    pub path_samples: u64,
    /// Points engine `path-tracing` runs on (None: all).
    pub path_points: Option<u64>,
    /// Direct light: DETP's photons, or next-event estimation with S samples per area light.
    pub direct: Direct,
    /// How far the points table's `edge_distance` looks, in d.
    pub edge_distance_reach: f64,
    /// Realisations.
    pub replicas: u64,
    /// Write NAME.points.csv.
    pub write_points: bool,
    /// `detp.memory_budget_gib`.
    pub memory_budget_gib: f64,
    /// `detp.photon_batches` when a number (None: `"auto"`).
    pub photon_batches: Option<u64>,
    /// Whether the spec gave `detp.point_spacing` (else surface points are 2d apart).
    pub spacing_given: bool,
    /// `detp.edge` with its parameter.
    pub edge: EdgeMode,
    /// `detp.radius_crossings` (None: each disc keeps its radius).
    pub radius_crossings: Option<RadiusCrossings>,
}

/// The k-nearest-crossings radius: `detp.radius_crossings` (k_ref) and
/// `detp.radius_crossings_photons` (N_ref), with the k they give at this point's photons
/// ([`crate::detp::nearest::k_for`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiusCrossings {
    /// k_ref.
    pub k_ref: u64,
    /// N_ref (None: k = k_ref at every photon count).
    pub photons: Option<u64>,
    /// k at this point's photons: the crossings each disc keeps.
    pub k: usize,
}

/// The radius schedule d(N) = d_ref·(N/N_ref)^(−β) ([`crate::theory::detp::scheduled_radius`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiusSchedule {
    /// N_ref: photons at which d = d_ref.
    pub photons: u64,
    /// β.
    pub exponent: f64,
    /// d_ref, in scene units.
    pub d_ref: f64,
}

/// `detp.direct`, with its sample count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direct {
    /// The paper's DETP of all light.
    Photons,
    /// Next-event estimation at each point with this many samples per area light; DETP (and the
    /// photon maps) of the segments after the first bounce.
    Nee(u64),
}

impl DetpConfig {
    /// Q.
    pub fn q(&self) -> f64 {
        self.cache.q
    }

    /// Whether each replica draws its own sample points (see `detp::points`): points uniform in the
    /// ball and the lattice's random normals are part of what a replica samples (the specs' "new
    /// lines and points each"); a scene's surface lattice and a user's points file are fixed by
    /// design and shared by every replica.
    pub fn points_per_replica(&self) -> bool {
        matches!(self.points, Points::Ball(_) | Points::Grid(_))
    }

    /// The scene, for a scene source.
    pub fn scene(&self) -> Option<&SceneFile> {
        match &self.rays {
            Rays::Lines => None,
            Rays::Scene(s) => Some(s),
        }
    }

    /// Cross-key checks of `[detp]`; files are loaded (once per run) through `inputs`, so a missing
    /// or bad file is refused before anything is written.
    /// Counted warnings known before running: the scene's own (degenerate triangles, non-planar
    /// quads), points outside the unit ball for lines (no exact value there, and the lines are not
    /// μ-random), and for a points file with a scene, points farther than d from every surface along
    /// their normal and normals facing into the surface the point lies on.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if let Some(s) = self.scene() {
            w.extend(s.scene.warnings.iter().cloned());
        }
        let Points::File(f) = &self.points else {
            return w;
        };
        match self.scene() {
            None => {
                let out = f
                    .centers
                    .iter()
                    .filter(|c| c.length() + self.disc_radius > 1.0)
                    .count();
                if out > 0 {
                    w.push(format!(
                        "{out} of {} points of {} reach outside the unit ball (|c| + d > 1): the lines are μ-random inside it only, and those points have no exact irradiance",
                        f.centers.len(),
                        f.path.display()
                    ));
                }
            }
            Some(s) => {
                let d = self.disc_radius;
                let (mut off, mut inward) = (0usize, 0usize);
                let sc = &s.scene;
                for (&c, &n) in f.centers.iter().zip(&f.normals) {
                    // The surface a point lies on: met within 2d by a ray from d before the point,
                    // from either side. Its light-receiving side is its winding normal (triangles)
                    // or the sphere's normal, the convention of surface points.
                    let on = [n, -n].into_iter().find_map(|dir| {
                        let (hit, _) = sc.first_two_hits(c + dir * d, -dir, 0.0, None);
                        hit.filter(|h| h.t <= 2.0 * d).map(|h| match h.prim {
                            crate::lt::Prim::Triangle(t) => sc.triangles[t as usize].normal(),
                            crate::lt::Prim::Ball(b) => {
                                let p = c + dir * d - dir * h.t;
                                sc.balls[b as usize].normal_at(p)
                            }
                        })
                    });
                    match on {
                        None => off += 1,
                        Some(g) if g.dot(n) < 0.0 => inward += 1,
                        Some(_) => {}
                    }
                }
                if off > 0 {
                    w.push(format!(
                        "{off} of {} points of {} are farther than d = {d} from every surface (along their normal): they gather light in mid-air",
                        f.centers.len(),
                        f.path.display()
                    ));
                }
                if inward > 0 {
                    w.push(format!(
                        "{inward} of {} points of {} have a normal facing into the surface they lie on (against its light-receiving side): DETP counts crossings from the normal's side only",
                        f.centers.len(),
                        f.path.display()
                    ));
                }
            }
        }
        w
    }

    /// How many sample points the point has (surface points: the sampler's own count, one per
    /// spacing² of area and at least one per triangle).
    pub fn point_count(&self) -> u64 {
        match &self.points {
            Points::Ball(n) => *n,
            Points::Grid(k) => k.pow(3),
            Points::File(f) => f.centers.len() as u64,
            Points::Surface(SurfacePoints { keep: Some(n), .. }) => *n,
            Points::Surface(SurfacePoints { spacing: s, .. }) => self.scene().map_or(0, |sc| {
                let tris: f64 = sc
                    .scene
                    .triangles
                    .iter()
                    .map(|t| (t.area().sqrt() / s).ceil().max(1.0).powi(2))
                    .sum();
                let balls: f64 = sc.scene.balls.iter().map(|b| b.area() / (s * s)).sum();
                (tris + balls).min(u64::MAX as f64) as u64
            }),
        }
    }

    /// A box holding every sample point: the unit ball, the scene, or the file's points.
    pub fn points_bounds(&self) -> Aabb {
        match &self.points {
            Points::Ball(_) | Points::Grid(_) => Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
            Points::Surface(_) => self
                .scene()
                .map_or(Aabb::new(DVec3::ZERO, DVec3::ZERO), |s| s.scene.bounds()),
            Points::File(f) => f.centers.iter().fold(
                Aabb::new(DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |b, &c| Aabb::new(b.lo.min(c), b.hi.max(c)),
            ),
        }
    }

    /// Cells of the disc grid (`detp.index = "grid"`) over the discs' bounds, `None` for an octree.
    pub fn grid_cells(&self) -> Option<f64> {
        let IndexKind::Grid(w) = self.index else {
            return None;
        };
        let b = self.points_bounds();
        let ext = (b.hi - b.lo).max(DVec3::ZERO) + DVec3::splat(2.0 * self.disc_radius);
        let dims = (ext / w).ceil().max(DVec3::ONE) + DVec3::ONE;
        Some(dims.x * dims.y * dims.z)
    }
    /// Validates `[detp]` (checks that span keys) and translates it into the engines' types,
    /// loading the scene and points files once through `inputs`.
    pub fn from_raw(seed: u64, d: &RawDetp, inputs: &mut Inputs) -> Result<Self, ConfigError> {
        let rays = Rays::from_raw(d, inputs)?;
        let in_scene_units = in_scene_units(d, &rays);
        let d = &in_scene_units;
        let points = Points::from_raw(d, &rays, inputs)?;
        check_engines(d, &rays)?;
        check_sizes(d, &points)?;
        let d_ref = disc_radius(d, &points, &rays)?;
        let radius_schedule = radius_schedule(d, d_ref)?;
        let disc_radius = match radius_schedule {
            None => d_ref,
            Some(s) => {
                let x = scheduled_radius(d_ref, d.photons as f64, s.photons as f64, s.exponent);
                check_radius(&rays, x, "detp.radius_schedule_photons")?;
                x
            }
        };
        let edge = edge_mode(d, &rays)?;
        let root_radius = root_radius(&rays);
        let length_scale = match d.length_unit {
            LengthUnit::Root => root_radius,
            LengthUnit::Scene => 1.0,
        };
        let cfg = Self {
            seed,
            rays,
            photons: d.photons,
            points,
            disc_radius,
            radius_schedule,
            length_scale,
            root_radius,
            order: match d.order {
                OrderChoice::None => Order::None,
                OrderChoice::Morton => Order::Morton,
                OrderChoice::Hilbert => Order::Hilbert,
            },
            order_bits: d.order_bits as u32,
            cache: cache_params(d),
            index: match d.index {
                IndexChoice::Grid => {
                    IndexKind::Grid(d.index_cell_width.unwrap_or(2.0 * disc_radius))
                }
                IndexChoice::Octree => IndexKind::Octree(d.octree_leaf as usize),
            },
            engines: d.engines.clone(),
            brute_force_points: d.brute_force_points,
            photon_map_k: d.photon_map_k,
            photon_map_filter: d.photon_map_filter,
            reference_samples: d.reference_samples,
            k_growth: KGrowth {
                k0: d.photon_map_k as f64,
                n0: d.photon_map_k_photons as f64,
                beta: d.photon_map_k_growth,
            },
            path_samples: d.path_samples,
            path_points: d.path_points,
            direct: match d.direct {
                DirectChoice::Photons => Direct::Photons,
                DirectChoice::Nee => Direct::Nee(d.direct_samples),
            },
            edge_distance_reach: d.edge_distance_reach,
            replicas: d.replicas,
            write_points: d.write_points,
            memory_budget_gib: d.memory_budget_gib,
            photon_batches: d.photon_batches.forced(),
            spacing_given: d.point_spacing.is_some(),
            edge,
            radius_crossings: radius_crossings(d)?,
        };
        cfg.check_grid_cells(d)?;
        cfg.check_path_points()?;
        Ok(cfg)
    }

    /// `detp.path_points` at most the points, where their count is known before they are made
    /// (surface points: the competitor runs on all of them when they are fewer).
    fn check_path_points(&self) -> Result<(), ConfigError> {
        let (Some(m), false) = (self.path_points, matches!(self.points, Points::Surface(_))) else {
            return Ok(());
        };
        let n = self.point_count();
        if m > n {
            return refuse(
                "detp.path_points",
                format!("got {m}, more than the {n} sample points"),
            );
        }
        Ok(())
    }

    /// A disc grid (`detp.index = "grid"`) of at most 2³¹ cells over the points' bounds.
    fn check_grid_cells(&self, d: &RawDetp) -> Result<(), ConfigError> {
        let (Some(cells), IndexKind::Grid(w)) = (self.grid_cells(), self.index) else {
            return Ok(());
        };
        if cells >= (1u64 << 31) as f64 {
            return refuse(
                if d.index_cell_width.is_some() { "detp.index_cell_width" } else { "detp.disc_radius" },
                format!(
                    "a disc grid of cell width {w} over the points' bounds would have {cells:.3e} cells (at most 2³¹): widen the cells or use detp.index = \"octree\"",
                ),
            );
        }
        Ok(())
    }
}

impl Rays {
    /// `detp.source` and `detp.scene`: lines, or a scene file (loaded once per run).
    pub fn from_raw(d: &RawDetp, inputs: &mut Inputs) -> Result<Rays, ConfigError> {
        match (d.source, &d.scene) {
            (RaySource::Lines, None) => Ok(Rays::Lines),
            (RaySource::Lines, Some(_)) => refuse(
                "detp.scene",
                "a scene file needs detp.source = \"scene\" (lines need none)",
            ),
            (RaySource::Scene, Some(p)) => {
                let s = inputs.scene("detp.scene", p)?;
                // Irradiance and its Poisson error multiply powers: beyond 1e100 W in total they
                // overflow f64 and a result would be written as inf.
                let total = s.scene.total_power();
                if !(total.is_finite() && total <= 1e100) {
                    return refuse(
                        "detp.scene",
                        format!(
                            "the scene emits {total:e} W in total: above 1e100 W the irradiance and its standard error overflow; rescale its powers"
                        ),
                    );
                }
                Ok(Rays::Scene(s))
            }
            (RaySource::Scene, None) => refuse(
                "detp.scene",
                "missing: detp.source = \"scene\" needs a scene file",
            ),
        }
    }
}

impl Points {
    /// `detp.point_source` with its count, spacing or file, for rays `rays`.
    pub fn from_raw(d: &RawDetp, rays: &Rays, inputs: &mut Inputs) -> Result<Points, ConfigError> {
        let kind = d.point_source.unwrap_or(match rays {
            Rays::Lines => PointSourceKind::Ball,
            Rays::Scene(_) => PointSourceKind::Surface,
        });
        let in_ball = matches!(kind, PointSourceKind::Ball | PointSourceKind::Grid);
        if in_ball && matches!(rays, Rays::Scene(_)) {
            return refuse(
                "detp.point_source",
                format!(
                    "\"{}\" points in the unit ball go with lines; a scene takes \"surface\" or \"file\"",
                    kind.as_str()
                ),
            );
        }
        let count = |missing: &str| {
            d.points
                .ok_or_else(|| ConfigError::Key(crate::spec::KeyError::new("detp.points", missing)))
        };
        let points = match kind {
            PointSourceKind::Ball => {
                Points::Ball(count("missing: points uniform in the ball need a count")?)
            }
            PointSourceKind::Grid => Points::Grid(lattice_side(count(
                "missing: points on a lattice need a count (k = round(∛points) per side)",
            )?)),
            PointSourceKind::Surface => Points::Surface(SurfacePoints {
                spacing: surface_spacing(d, rays)?,
                keep: d.points,
            }),
            PointSourceKind::File => match d.points_file.as_deref() {
                Some(p) => Points::File(inputs.points("detp.points_file", p)?),
                None => {
                    return refuse(
                        "detp.points_file",
                        "missing: point_source = \"file\" needs a CSV",
                    )
                }
            },
        };
        if d.points.is_some() && !in_ball && kind != PointSourceKind::Surface {
            return refuse(
                "detp.points",
                format!(
                    "a count belongs to point_source = \"ball\", \"grid\" or \"surface\", not \"{}\"",
                    kind.as_str()
                ),
            );
        }
        if d.points_file.is_some() && kind != PointSourceKind::File {
            return refuse("detp.points_file", "needs detp.point_source = \"file\"");
        }
        Ok(points)
    }
}

/// `[detp]` with its lengths in the scene's units: with `length_unit = "root"`, the spacing, d and
/// the index cell width times r_s (the half diagonal of the scene's bounds; 1 for lines).
fn in_scene_units(d: &RawDetp, rays: &Rays) -> RawDetp {
    let r = match (d.length_unit, rays) {
        (LengthUnit::Scene, _) | (LengthUnit::Root, Rays::Lines) => return d.clone(),
        (LengthUnit::Root, Rays::Scene(_)) => root_radius(rays),
    };
    RawDetp {
        point_spacing: d.point_spacing.map(|x| x * r),
        disc_radius: match d.disc_radius {
            DiscRadius::Value(x) => DiscRadius::Value(x * r),
            DiscRadius::Spacing => DiscRadius::Spacing,
        },
        index_cell_width: d.index_cell_width.map(|x| x * r),
        ..d.clone()
    }
}

/// r_s: the radius of the sphere around the scene's bounds (1 for lines through the unit ball).
fn root_radius(rays: &Rays) -> f64 {
    match rays {
        Rays::Lines => 1.0,
        Rays::Scene(s) => crate::detp::sphere_cache::root_sphere(&s.scene.bounds()).1,
    }
}

/// `detp.radius_schedule_photons` and `detp.radius_schedule_exponent`, checked: the exponent
/// belongs to a schedule and is a finite number ≥ 0 (a negative one would grow the disc with the
/// photons, and its bias with it).
fn radius_schedule(d: &RawDetp, d_ref: f64) -> Result<Option<RadiusSchedule>, ConfigError> {
    let Some(photons) = d.radius_schedule_photons else {
        if d.radius_schedule_exponent.is_some() {
            return refuse(
                "detp.radius_schedule_exponent",
                "belongs to a radius schedule: give detp.radius_schedule_photons (N_ref) too",
            );
        }
        return Ok(None);
    };
    let exponent = d.radius_schedule_exponent.unwrap_or(RADIUS_SCHEDULE_EXPONENT);
    if !(exponent.is_finite() && exponent >= 0.0) {
        return refuse(
            "detp.radius_schedule_exponent",
            format!("got {exponent}, expected a finite exponent ≥ 0 (1/6 minimises the mean square error; 0 keeps d)"),
        );
    }
    Ok(Some(RadiusSchedule {
        photons,
        exponent,
        d_ref,
    }))
}

/// `detp.radius_crossings` and `detp.radius_crossings_photons`, checked: N_ref belongs to the rule.
/// (k ≥ 2 is checked where the key is read.)
fn radius_crossings(d: &RawDetp) -> Result<Option<RadiusCrossings>, ConfigError> {
    let Some(k_ref) = d.radius_crossings else {
        if d.radius_crossings_photons.is_some() {
            return refuse(
                "detp.radius_crossings_photons",
                "belongs to the k-nearest-crossings radius: give detp.radius_crossings (k_ref) too",
            );
        }
        return Ok(None);
    };
    Ok(Some(RadiusCrossings {
        k_ref,
        photons: d.radius_crossings_photons,
        k: crate::detp::nearest::k_for(k_ref, d.photons, d.radius_crossings_photons),
    }))
}

/// How much finer than √(area/n) the lattice of a subsample is by default: a lattice of spacing
/// √(area/n)/1.2 holds about 1.44·n points before covered points are dropped, so n of them usually
/// remain to choose from.
const SUBSAMPLE_REFINEMENT: f64 = 1.2;

/// The spacing of surface points: `detp.point_spacing`; else, with `detp.points = n`,
/// √(area/n)/1.2 over the scene's whole surface area (covered parts included); else 2d.
fn surface_spacing(d: &RawDetp, rays: &Rays) -> Result<f64, ConfigError> {
    let Rays::Scene(file) = rays else {
        return refuse(
            "detp.point_source",
            "\"surface\" needs a scene (detp.source = \"scene\")",
        );
    };
    if let (None, Some(n)) = (d.point_spacing, d.points) {
        let sc = &file.scene;
        let area: f64 = sc.triangles.iter().map(|t| t.area()).sum::<f64>()
            + sc.balls.iter().map(|b| b.area()).sum::<f64>();
        return Ok((area / n as f64).sqrt() / SUBSAMPLE_REFINEMENT);
    }
    match (d.point_spacing, d.disc_radius) {
        (Some(s), _) => Ok(s),
        (None, DiscRadius::Value(r)) => Ok(2.0 * r),
        (None, DiscRadius::Spacing) => refuse(
            "detp.point_spacing",
            "missing: with disc_radius = \"spacing\" surface points need a spacing",
        ),
    }
}

/// `detp.engines` (at least one DETP engine, none twice, baselines only where they apply),
/// `detp.reference_samples` and `detp.photons`.
fn check_engines(d: &RawDetp, rays: &Rays) -> Result<(), ConfigError> {
    let lines = matches!(rays, Rays::Lines);
    if d.engines.is_empty() {
        return refuse("detp.engines", "empty: name at least one engine");
    }
    if d.engines.iter().all(|x| x.is_baseline()) {
        return refuse(
            "detp.engines",
            format!(
                "name a DETP engine ({}): the photon map and the reference are baselines beside them",
                estimators::names_of(Role::Detp, "or")
            ),
        );
    }
    for (i, a) in d.engines.iter().enumerate() {
        if d.engines[..i].contains(a) {
            return refuse(
                "detp.engines",
                format!("\"{}\" is listed twice", a.as_str()),
            );
        }
    }
    if d.direct == DirectChoice::Nee && lines {
        return refuse(
            "detp.direct",
            "\"nee\" samples a scene's lights at each point: it needs detp.source = \"scene\" (lines have no lights)",
        );
    }
    if d.direct_samples < 2 {
        return refuse(
            "detp.direct_samples",
            "got 1, at least 2 (the direct part's standard error comes from its samples' variance)",
        );
    }
    // Each estimator's own refusals, in the spec's order.
    for e in &d.engines {
        e.estimator().check(d, lines)?;
    }
    Ok(())
}

/// `detp.photons` at most 2³¹ and at most 2²⁸ points in the ball.
fn check_sizes(d: &RawDetp, points: &Points) -> Result<(), ConfigError> {
    if d.photons > 1 << 31 {
        return refuse("detp.photons", format!("got {}, at most 2³¹", d.photons));
    }
    let n = match points {
        Points::Ball(n) => *n,
        Points::Grid(k) => k.pow(3),
        Points::Surface(s) => s.keep.unwrap_or(0),
        Points::File(_) => 0,
    };
    if n > 1 << 28 {
        return refuse("detp.points", format!("got {n}, at most 2²⁸"));
    }
    Ok(())
}

/// d: `detp.disc_radius`, or the points' spacing; at most the space the rays cover.
fn disc_radius(d: &RawDetp, points: &Points, rays: &Rays) -> Result<f64, ConfigError> {
    let disc_radius = match (d.disc_radius, points) {
        (DiscRadius::Value(r), _) => r,
        (DiscRadius::Spacing, Points::Ball(n)) => crate::theory::detp::ball_spacing(1.0, *n as f64),
        (DiscRadius::Spacing, Points::Grid(k)) => lattice_spacing(*k),
        (DiscRadius::Spacing, Points::Surface(s)) => s.spacing,
        (DiscRadius::Spacing, Points::File(_)) => {
            return refuse(
                "detp.disc_radius",
                "\"spacing\" is unknown for points from a file: give a radius",
            )
        }
    };
    let key = if matches!(d.disc_radius, DiscRadius::Spacing) { "detp.point_spacing" } else { "detp.disc_radius" };
    check_radius(rays, disc_radius, key)?;
    Ok(disc_radius)
}

/// A disc radius (given, or scheduled) small against the scene and representable at its
/// coordinates; refused at `key` otherwise.
fn check_radius(rays: &Rays, disc_radius: f64, key: &str) -> Result<(), ConfigError> {
    // A disc must be small against the space the rays cover: d ≤ 1 for lines through the unit
    // ball (each line is a segment reaching 1 beyond the ball), d ≤ the scene's diagonal for
    // photons. Larger discs lose precision in the crossing test (d² at 1e200 overflows).
    let reach = match rays {
        Rays::Lines => (
            1.0,
            "the unit ball's radius (lines are segments reaching 1 beyond it)".to_string(),
        ),
        Rays::Scene(s) => {
            let b = s.scene.bounds();
            let diag = (b.hi - b.lo).length();
            (diag, format!("the scene's diagonal {diag:.4}"))
        }
    };
    if !(disc_radius * disc_radius).is_finite() || disc_radius > reach.0 {
        return refuse(
            key,
            format!("d = {disc_radius:e} is larger than {}: a tangent disc must be small against the scene", reach.1),
        );
    }
    // Enough of f64 left for d and the scene at the scene's coordinates.
    if let Rays::Scene(s) = rays {
        s.scene
            .precision()
            .check(disc_radius)
            .or_else(|m| refuse("detp.scene", m))?;
    }
    Ok(())
}

/// The sphere cache's parameters (its `law_ball` is set per replica).
fn cache_params(d: &RawDetp) -> SphereCacheParams {
    SphereCacheParams {
        q: d.q,
        threshold: d.threshold as usize,
        list_mode: match d.list_mode {
            ListModeChoice::Exact => ListMode::Exact,
            ListModeChoice::Inherited => ListMode::Inherited,
        },
        pop_rule: match d.pop_rule {
            PopRuleChoice::Chain => PopRule::Chain,
            PopRuleChoice::Paper => PopRule::Paper,
        },
        chunk_points: d.chunk_points as usize,
        law_ball: None,
    }
}

/// Points per side of eq. 4's lattice for a target count: round(∛n), at least 1.
pub fn lattice_side(n: u64) -> u64 {
    ((n as f64).cbrt().round() as u64).max(1)
}

/// Spacing of eq. 4's lattice with `k` points per side: its cube (side k·spacing) is inscribed in
/// the unit ball, r_0 = √3·d·k/2 = 1.
pub fn lattice_spacing(k: u64) -> f64 {
    2.0 / (3f64.sqrt() * k as f64)
}

/// `detp.edge` and its parameter, checked: a remedy needs a scene, and each parameter belongs to
/// its own mode.
fn edge_mode(d: &RawDetp, rays: &Rays) -> Result<EdgeMode, ConfigError> {
    if d.edge != EdgeChoice::Paper && matches!(rays, Rays::Lines) {
        return refuse(
            "detp.edge",
            format!(
                "\"{}\" needs surfaces: lines through the unit ball have no edges (use detp.source = \"scene\")",
                d.edge.as_str()
            ),
        );
    }
    let clamps = matches!(d.edge, EdgeChoice::ClampRadius | EdgeChoice::ClampFirstHit);
    let cuts = matches!(d.edge, EdgeChoice::FirstHit | EdgeChoice::ClampFirstHit);
    if d.edge_min_radius.is_some() && !clamps {
        return refuse(
            "detp.edge_min_radius",
            "belongs to detp.edge = \"clamp-radius\" or \"clamp-first-hit\"",
        );
    }
    if d.edge_gap.is_some() && !cuts {
        return refuse(
            "detp.edge_gap",
            "belongs to detp.edge = \"first-hit\" or \"clamp-first-hit\"",
        );
    }
    if d.edge_radius_factor.is_some() && !clamps {
        return refuse(
            "detp.edge_radius_factor",
            "belongs to detp.edge = \"clamp-radius\" or \"clamp-first-hit\"",
        );
    }
    let factor = d.edge_radius_factor.unwrap_or(EDGE_RADIUS_FACTOR);
    if !(factor > 0.0 && factor.is_finite()) {
        return refuse(
            "detp.edge_radius_factor",
            format!("got {factor}, expected a finite factor κ > 0 on the distance to the nearest other surface"),
        );
    }
    let min = d.edge_min_radius.unwrap_or(EDGE_MIN_RADIUS);
    if !(min > 0.0 && min <= 1.0) {
        return refuse(
            "detp.edge_min_radius",
            format!("got {min}, expected a fraction of d in (0, 1]"),
        );
    }
    let gap = d.edge_gap.unwrap_or(EDGE_GAP);
    if !(gap.is_finite() && gap >= 0.0) {
        return refuse(
            "detp.edge_gap",
            format!("got {gap}, expected a fraction of d ≥ 0"),
        );
    }
    Ok(match d.edge {
        EdgeChoice::Paper => EdgeMode::Paper,
        EdgeChoice::ClampRadius => EdgeMode::ClampRadius { min, factor },
        EdgeChoice::FirstHit => EdgeMode::FirstHit { gap },
        EdgeChoice::ClampFirstHit => EdgeMode::ClampFirstHit { min, factor, gap },
    })
}
