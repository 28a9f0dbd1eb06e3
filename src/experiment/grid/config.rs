//! The validated configuration of one grid point: what the engines see, with the checks that span
//! keys.

use glam::DVec3;

use super::spec::{Extent, GridSpec, RawDist, RawDraw, RawGrid, RawRadius, RawScene};
use crate::grid::build::estimated_bytes;
use crate::sample::radius::{RadiusClass, RadiusDist, RadiusDraw};
use crate::scene::finite::{FiniteScene, FiniteSize};
use crate::spec::KeyError;
use crate::theory::grid::Eye;

/// The scene model of a point.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneModel {
    /// Infinite Poisson scene, generated lazily; a new realisation per ray batch.
    Infinite,
    /// A finite cube, one realisation per point, built into a grid.
    Finite(FiniteScene),
}

/// Which of the three grid kinds a point belongs to: what it measures beyond the common counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// Kind `grid`: N_I, N_S, t*, hit rate and their laws.
    Study,
    /// Kind `grid-scaling`: finite scenes of growing n, brute force, concentration (Prop. 4.1).
    Scaling,
    /// Kind `grid-cost-model`: the machine's T_I and T_S and the model t = N_I·T_I + N_S·T_S.
    CostModel,
}

impl Variant {
    /// The kind's name.
    pub fn name(self) -> &'static str {
        match self {
            Variant::Study => "grid",
            Variant::Scaling => "grid-scaling",
            Variant::CostModel => "grid-cost-model",
        }
    }
}

/// Everything the grid engines need for one point.
#[derive(Clone, Debug, PartialEq)]
pub struct GridConfig {
    /// Which grid kind.
    pub variant: Variant,
    /// Master seed.
    pub seed: u64,
    /// Rays to trace.
    pub rays: u64,
    /// ρ.
    pub intensity: f64,
    /// Radius classes (one class of constant radius for `scene.radius`).
    pub classes: Vec<RadiusClass>,
    /// When radii are drawn.
    pub draw: RadiusDraw,
    /// Infinite or finite.
    pub scene: SceneModel,
    /// a.
    pub cell_width: f64,
    /// Mailboxing on (skip repeated tests).
    pub mailbox: bool,
    /// Eye placement.
    pub eye: Eye,
    /// Independent finite-scene realisations per point (1 for infinite scenes).
    pub replicas: u64,
    /// Rays sharing one infinite-scene realisation (divides nothing: the last group may be short).
    pub rays_per_scene: u64,
    /// Walk cut-off in infinite scenes.
    pub max_steps: u64,
    /// t* histogram bins.
    pub bins: usize,
    /// t* histogram right edge, mean free paths.
    pub t_max_mfp: f64,
    /// Brute force only for n ≤ this.
    pub brute_force_max_n: u64,
    /// Rays checked by brute force.
    pub brute_force_rays: u64,
    /// c of Proposition 4.1.
    pub concentration_c: f64,
    /// Memory the structures of one point may take, GiB (`grid.memory_budget_gib`).
    pub memory_budget_gib: f64,
}

/// `[scene]` validated: the radius classes, when radii are drawn, and the scene model.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneSpec {
    /// The radius classes (one class of constant radius for `scene.radius`).
    pub classes: Vec<RadiusClass>,
    /// When radii are drawn.
    pub draw: RadiusDraw,
    /// Infinite or finite.
    pub model: SceneModel,
}

impl TryFrom<&RawScene> for SceneSpec {
    type Error = KeyError;

    /// The radius classes (fractions summing to 1), the draw, and the scene's extent: infinite, a
    /// cube of a side, or a cube holding n spheres; a centre and replicas only for a finite one.
    fn try_from(s: &RawScene) -> Result<Self, KeyError> {
        let e = |k: &str, m: &str| KeyError::new(k, m);
        let classes = radius_classes(s)?;
        let total: f64 = classes.iter().map(|c| c.fraction).sum();
        if (total - 1.0).abs() > 1e-9 {
            return Err(KeyError::new(
                "scene.class",
                format!("fractions sum to {total}, expected 1"),
            ));
        }
        let draw = match s.radius_draw {
            None | Some(RawDraw::PerSphere) => RadiusDraw::PerSphere,
            Some(RawDraw::PerScene) => RadiusDraw::PerScene,
        };
        let size = match (s.extent, s.spheres) {
            (Some(Extent::Side(_)), Some(_)) => return Err(e("scene.spheres", "give either a numeric scene.extent or scene.spheres, not both")),
            (Some(Extent::Infinite), Some(_)) => return Err(e("scene.spheres", "an infinite scene has no sphere count; set scene.extent to a side or drop scene.spheres")),
            (Some(Extent::Side(l)), None) => Some(FiniteSize::Side(l)),
            (None, Some(n)) => Some(FiniteSize::Count(n)),
            (None | Some(Extent::Infinite), None) => None,
        };
        let model = match size {
            None if s.center.is_some() => {
                return Err(e(
                    "scene.center",
                    "only a finite scene has a centre (the infinite scene is stationary)",
                ))
            }
            None => SceneModel::Infinite,
            Some(size) => SceneModel::Finite(FiniteScene {
                intensity: s.intensity,
                classes: classes.clone(),
                draw,
                size,
                center: s.center.map(DVec3::from).unwrap_or(DVec3::ZERO),
            }),
        };
        if s.replicas.is_some() && model == SceneModel::Infinite {
            return Err(e("scene.replicas", "only a finite scene has replicas (every batch of an infinite scene is a new realisation already)"));
        }
        Ok(Self {
            classes,
            draw,
            model,
        })
    }
}

/// `scene.radius` as one class, or the `[[scene.class]]` tables (exactly one of them).
fn radius_classes(s: &RawScene) -> Result<Vec<RadiusClass>, KeyError> {
    match (s.radius, s.class.is_empty()) {
        (Some(r), true) => Ok(vec![RadiusClass {
            fraction: 1.0,
            radius: RadiusDist::Constant(r),
        }]),
        (None, false) => Ok(s
            .class
            .iter()
            .map(|c| RadiusClass {
                fraction: c.fraction,
                radius: match &c.radius {
                    RawRadius::Constant(r) => RadiusDist::Constant(*r),
                    RawRadius::Dist(RawDist::Uniform { lo, hi }) => {
                        RadiusDist::Uniform { lo: *lo, hi: *hi }
                    }
                    RawRadius::Dist(RawDist::Lognormal { median, sigma, max }) => {
                        RadiusDist::LogNormal {
                            median: *median,
                            sigma: *sigma,
                            max: *max,
                        }
                    }
                },
            })
            .collect()),
        (Some(_), false) => Err(KeyError::new(
            "scene.radius",
            "give either scene.radius or [[scene.class]] tables, not both",
        )),
        (None, true) => Err(KeyError::new(
            "scene.radius",
            "missing: give scene.radius or [[scene.class]] tables",
        )),
    }
}

impl GridConfig {
    /// Validates one point's spec of a grid kind: each table ([`SceneSpec`], `[grid]`,
    /// `[histogram]`), then the rules that span tables (rays and replicas, the kind's own tables,
    /// rounding far from the origin, the finite grid's memory).
    pub fn from_spec(raw: &GridSpec, variant: Variant) -> Result<Self, KeyError> {
        let e = |k: &str, m: String| KeyError::new(k, m);
        let rays = raw.experiment.rays.ok_or_else(|| {
            e(
                "experiment.rays",
                format!("missing: kind {} needs it", variant.name()),
            )
        })?;
        let scene = SceneSpec::try_from(&raw.scene)?;
        if raw.scene.replicas.is_some_and(|r| r > rays) {
            let r = raw.scene.replicas.unwrap_or(0);
            return Err(e(
                "scene.replicas",
                format!("got {r}, more than experiment.rays = {rays}"),
            ));
        }
        let g = &raw.grid;
        check_rounding(&scene, g.cell_width)?;
        if variant == Variant::Scaling && scene.model == SceneModel::Infinite {
            return Err(e("scene.spheres", "kind grid-scaling needs a finite scene: set scene.spheres (or scene.extent to a side)".into()));
        }
        if raw.scaling.is_some() && variant != Variant::Scaling {
            return Err(e(
                "scaling",
                format!(
                    "the [scaling] table belongs to kind grid-scaling, not {}",
                    variant.name()
                ),
            ));
        }
        check_grid_memory(&scene, g)?;
        if rays > 10_000_000_000 {
            return Err(e("experiment.rays", format!("got {rays}, at most 10¹⁰")));
        }
        if g.rays_per_scene > super::run::BATCH {
            return Err(e(
                "grid.rays_per_scene",
                format!(
                    "got {}, at most {} (one batch)",
                    g.rays_per_scene,
                    super::run::BATCH
                ),
            ));
        }
        let h = raw.histogram.clone().unwrap_or_default();
        if h.bins > 100_000 {
            return Err(e(
                "histogram.bins",
                format!("got {}, at most 100000", h.bins),
            ));
        }
        let sc = raw.scaling.clone().unwrap_or_default();
        Ok(Self {
            variant,
            seed: raw.experiment.stream_seed(),
            rays,
            intensity: raw.scene.intensity,
            classes: scene.classes,
            draw: scene.draw,
            scene: scene.model,
            cell_width: g.cell_width,
            mailbox: g.mailbox,
            eye: g.eye,
            rays_per_scene: g.rays_per_scene,
            replicas: raw.scene.replicas.unwrap_or(1),
            max_steps: g.max_steps,
            bins: h.bins as usize,
            t_max_mfp: h.t_max_mfp,
            brute_force_max_n: sc.brute_force_max_n,
            brute_force_rays: sc.brute_force_rays,
            concentration_c: sc.c,
            memory_budget_gib: g.memory_budget_gib,
        })
    }
}

/// Far from the origin, rounding (and so the listing pad, 64ε × coordinate magnitude) grows until
/// it is no longer negligible against the spheres and cells: such a finite scene is refused.
fn check_rounding(scene: &SceneSpec, cell_width: f64) -> Result<(), KeyError> {
    let SceneModel::Finite(fs) = &scene.model else {
        return Ok(());
    };
    let r_min = scene
        .classes
        .iter()
        .map(|c| match c.radius {
            RadiusDist::Constant(r) => r,
            RadiusDist::Uniform { lo, .. } => lo,
            RadiusDist::LogNormal { median, sigma, max } => {
                (median * (-6.0 * sigma).exp()).min(max)
            }
        })
        .fold(f64::INFINITY, f64::min);
    let magnitude = fs.center.abs().max_element() + fs.side() + 2.0 * cell_width;
    let pad = 64.0 * f64::EPSILON * magnitude;
    if pad > 1e-6 * r_min.min(cell_width) {
        return Err(KeyError::new(
            "scene.center",
            format!("coordinates of magnitude {magnitude:.3e} make rounding (64ε·magnitude = {pad:.2e}) exceed 10⁻⁶ of the smallest radius or the cell width ({:.2e}); place the scene nearer the origin", r_min.min(cell_width)),
        ));
    }
    Ok(())
}

/// The memory of a finite grid, estimated before anything is allocated: within
/// `grid.memory_budget_gib` and the 2³² index limit.
fn check_grid_memory(scene: &SceneSpec, g: &RawGrid) -> Result<(), KeyError> {
    let SceneModel::Finite(fs) = &scene.model else {
        return Ok(());
    };
    let a = g.cell_width;
    let n = fs.expected_count();
    let side = fs.side() + 2.0 * fs.max_radius() + 2.0 * a;
    let cells = (side / a).ceil().powi(3);
    let per_sphere: f64 = scene
        .classes
        .iter()
        .map(|c| {
            c.fraction
                * c.radius
                    .expect(|r| crate::theory::grid::offset_cube_volume(a, r))
                / (a * a * a)
        })
        .sum();
    let listings = n * per_sphere;
    let spheres_bytes = n * 40.0;
    let bytes =
        estimated_bytes(cells.min(1e18) as u64, listings.min(1e18) as u64) as f64 + spheres_bytes;
    let budget = g.memory_budget_gib * (1u64 << 30) as f64;
    if bytes.is_nan() || bytes > budget || cells > u32::MAX as f64 || listings > u32::MAX as f64 {
        return Err(KeyError::new(
            "grid.cell_width",
            format!(
                "a grid of {cells:.3e} cells listing {listings:.3e} spheres would need about {:.2} GiB, over the budget of {} GiB (grid.memory_budget_gib) or the 2³² index limit; use a larger cell width or fewer spheres",
                bytes / (1u64 << 30) as f64,
                g.memory_budget_gib
            ),
        ));
    }
    Ok(())
}
