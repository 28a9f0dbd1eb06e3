//! Kind `quasi-static`: the `[detp]` table (a scene source, surface points, d, Q, …) plus
//! `[dynamic]`: how many frames, the dynamic objects' size r_D/r_0, the engine choice for their
//! points and how often a frame is checked against a full recalculation.
//!
//! Everything that can be checked before running is checked here, so bad input is refused before
//! anything is written: the scene must have a dynamic object; once scaled, no object may be as large
//! as the scene, leave the scene's box at any frame, or overlap another object.

use crate::detp::quasi_static::{Feed, Predictor};
use crate::experiment::detp::estimators::{path_tracing::PathTracing, sphere_cache::SphereCache};
use crate::experiment::detp::{DetpConfig, DynamicEngine, Points, RawDetp, Rays, SurfacePoints};
use crate::experiment::inputs::{Inputs, SceneFile};
use crate::experiment::kind::{refuse, ConfigError};
use crate::lt::Scene;
use crate::toml_text::de::{count, count_or_zero, number, opt_count, opt_count_or_zero};

crate::spec_file! {
    /// The spec file of kind `quasi-static`: `[experiment]`, `[detp]`, `[dynamic]` and `[sweep]`.
    pub struct QuasiStaticSpec {
        /// `[detp]`.
        detp: RawDetp = {table};
        /// `[dynamic]` (required; missing is reported at `dynamic`).
        dynamic: Option<RawDynamicSpec> = {optional_table};
    }
}

crate::spec_table! {
    /// `[dynamic]`: frames, the objects' r_D/r_0, the hybrid crossover, the full-recalculation
    /// check period, the points table's frame, a reference run and the engine predictor.
    pub struct RawDynamicSpec {
        /// F: frames; frame 0 is the full trace, the objects sit at τ = f/(F − 1) of their motion.
        frames: u64 = {required} read count, "integer", "frames", "≥ 1";
        /// r_D/r_0 of every dynamic object, each scaled about its centre (r_0: radius of the
        /// sphere around the static scene).
        ratio: Option<f64> = {absent "the objects' size in the scene"} read opt_ratio,
            "number", "", "(0, 1)";
        /// The hybrid engine's crossover r_D/r_0: smaller objects use the sphere cache.
        crossover: Option<f64> = {absent "Theorem 2 at the run's Q and n_D"} read opt_ratio,
            "number", "", "(0, 1)";
        /// Check every k-th frame (and the last) against a full recalculation (`full_mismatch`,
        /// `full_frame_s`); 0: never. A mismatch fails the run (exit 1).
        check_every: u64 = {default 1} read count_or_zero, "integer", "frames", "≥ 0";
        /// The frame whose irradiance goes to `NAME.points.csv` (with `detp.write_points`).
        points_frame: Option<u64> = {absent "the last frame"} read opt_count_or_zero,
            "integer", "", "0 … frames − 1";
        /// Photons of a reference full recalculation of the last frame (another seed); the run's
        /// error against it is `irradiance_rel_rmse`.
        reference_photons: Option<u64> = {absent "no reference"} read opt_count,
            "integer", "photons", "≥ 1";
        /// The §4.1 predictor: the fraction of the photons whose segments predict each engine's
        /// cost at frame 0.
        predict: Option<f64> = {absent "0.05 with `detp.engine = \"predicted\"`, else none"}
            read opt_fraction, "number", "", "(0, 1]";
        /// Which §4.1 predictor: `"subsample"` times both engines on the fraction and scales their
        /// seconds by 1/fraction; `"paper"` predicts the sphere cache's tests level by level (the
        /// upper levels simulated on the fraction down to the last level whose parent still holds
        /// the threshold's rays there, the lower ones from theory: N_s·Q^(2(i−s)) rays per sphere,
        /// spheres per level from the points) and scales the fraction's sphere-cache seconds by
        /// those tests over the fraction's counted ones; the disc index's prediction is the
        /// subsample's.
        predictor: PredictorChoice = {default PredictorChoice::Subsample}, "string", "",
            "`\"subsample\"`, `\"paper\"` (needs the predictor)";
        /// With the predictor: each replica also times both engines warm on every segment this
        /// many times, interleaved (`warm_sphere_cache_s`, `warm_disc_index_s`: the faster engine
        /// the pick is judged against); 0: only the predictor's one measured pass.
        warm_repeats: u64 = {default 0} read count_or_zero, "integer", "", "≥ 0 (needs the predictor)";
        /// Which segments the dynamic points' engines get: Theorem 2's model (the sphere cache
        /// the segment index's answer, the disc index every segment), both the segment index's
        /// answer, or both every segment.
        feed: FeedChoice = {default FeedChoice::Paper}, "string", "",
            "`\"paper\"`, `\"segment-index\"`, `\"all\"`";
    }
}

crate::choice!(
    /// `dynamic.predictor`.
    PredictorChoice { Subsample => "subsample", Paper => "paper" } default Subsample
);

crate::choice!(
    /// `dynamic.feed`.
    FeedChoice { Paper => "paper", SegmentIndex => "segment-index", All => "all" } default Paper
);

fn opt_fraction<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    use serde::de::Error as _;
    let x = number(d)?;
    if x.is_finite() && x > 0.0 && x <= 1.0 {
        Ok(Some(x))
    } else {
        Err(D::Error::custom(format!(
            "got {x}, expected a fraction of the photons in (0, 1]"
        )))
    }
}

fn opt_ratio<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    use serde::de::Error as _;
    let x = number(d)?;
    if x.is_finite() && x > 0.0 && x < 1.0 {
        Ok(Some(x))
    } else {
        Err(D::Error::custom(format!(
            "got {x}, expected a ratio r_D/r_0 in (0, 1)"
        )))
    }
}

/// A validated quasi-static point, in the engines' own types: the scene loaded once per run and
/// scaled to this point's r_D/r_0.
#[derive(Clone, Debug)]
pub struct QuasiStaticConfig {
    /// The DETP settings (scene file, points, d, Q, threshold, order, index).
    pub detp: DetpConfig,
    /// The scene, its dynamic objects scaled to `ratio`.
    pub scene: Scene,
    /// Surface point spacing.
    pub spacing: f64,
    /// Frames.
    pub frames: u32,
    /// r_D/r_0 of every dynamic object, if the spec sets it.
    pub ratio: Option<f64>,
    /// Hybrid crossover, if the spec sets it.
    pub crossover: Option<f64>,
    /// Full-recalculation check period (0: never).
    pub check_every: u64,
    /// The engine choice.
    pub engine: DynamicEngine,
    /// Frame whose irradiance goes to the points table (default: the last).
    pub points_frame: Option<u32>,
    /// Photons of the reference recalculation of the last frame.
    pub reference_photons: Option<u64>,
    /// The predictor's fraction of photons (set, or 0.05 when the engine is "predicted").
    pub predict: Option<f64>,
    /// Which predictor (with `predict`).
    pub predictor: Predictor,
    /// Warm timings of both engines per replica, with the predictor.
    pub warm_repeats: u64,
    /// Which segments the dynamic points' engines get.
    pub feed: Feed,
    /// Counted warnings about the scene and its motion (shown by `check`, printed and counted by
    /// `run`).
    pub warnings: Vec<String>,
    /// `detp.source = "lines"`: μ-random lines and a sphere circling in the unit ball
    /// ([`crate::detp::quasi_static::lines`]), static points uniform in the ball.
    pub lines: bool,
}

impl QuasiStaticConfig {
    /// Per-point path tracing at frame 0 and the checked frames (`"path-tracing"` in
    /// `detp.engines`; [`super::path_tracing`]).
    pub fn path_tracing(&self) -> bool {
        self.detp.engines.iter().any(|e| e.is::<PathTracing>())
    }

    /// Validates `[detp]` and `[dynamic]` together, loading the scene (once per run, through
    /// `inputs`) and checking its motion at this point's scale.
    pub fn from_raw(raw: &QuasiStaticSpec, inputs: &mut Inputs) -> Result<Self, ConfigError> {
        let Some(dy) = &raw.dynamic else {
            return refuse(
                "experiment.kind",
                "kind quasi-static needs a [dynamic] table (frames = …); for one frame use kind \"detp\"",
            );
        };
        let d = &raw.detp;
        let detp = DetpConfig::from_raw(raw.experiment.stream_seed(), d, inputs)?;
        paper_method_only(&detp)?;
        let Rays::Scene(file) = &detp.rays else {
            return lines_config(raw, dy, detp);
        };
        let Points::Surface(SurfacePoints { spacing, keep }) = detp.points else {
            return refuse(
                "detp.point_source",
                "kind quasi-static puts its points on the scene's surfaces (\"surface\")",
            );
        };
        if keep.is_some() {
            return refuse(
                "detp.points",
                "kind quasi-static keeps every lattice point of its surfaces (static and dynamic ones move apart): give point_spacing instead of a count",
            );
        }
        dy.check()?;
        let scene = scaled(file, dy.ratio)?;
        // A size or motion problem is the scene's, or the ratio's when the spec rescales.
        let blame = if dy.ratio.is_some() {
            "dynamic.ratio"
        } else {
            "detp.scene"
        };
        let mut warnings = check_motion(&scene, dy.frames as u32, blame)?;
        warnings.extend(scene.warnings.iter().cloned());
        check_lights(&scene)?;
        let (predict, predictor, feed) = dy.choices(d.engine)?;
        Ok(Self {
            detp,
            scene,
            spacing,
            frames: dy.frames as u32,
            ratio: dy.ratio,
            crossover: dy.crossover,
            check_every: dy.check_every,
            engine: d.engine.unwrap_or_default(),
            points_frame: dy.points_frame.map(|f| f as u32),
            reference_photons: dy.reference_photons,
            feed,
            predict,
            predictor,
            warm_repeats: dy.warm_repeats,
            warnings,
            lines: false,
        })
    }
}

/// A lines point (`detp.source = "lines"`): static points uniform in the ball (`detp.points`), a
/// sphere of radius `dynamic.ratio` circling inside it (the scene-file keys and the reference
/// recalculation, which traces the scene's lights, are refused); its points lie every
/// (4π/3/n_P)^⅓ on the sphere, the static points' mean spacing.
fn lines_config(
    raw: &QuasiStaticSpec,
    dy: &RawDynamicSpec,
    detp: DetpConfig,
) -> Result<QuasiStaticConfig, ConfigError> {
    let Points::Ball(n) = detp.points else {
        return refuse(
            "detp.point_source",
            "kind quasi-static with lines puts its static points uniform in the unit ball: point_source = \"ball\" with detp.points",
        );
    };
    let Some(ratio) = dy.ratio else {
        return refuse(
            "dynamic.ratio",
            "missing: with detp.source = \"lines\" the moving object is a sphere of radius r_D = ratio·r_0 (r_0 = 1) that the spec sizes",
        );
    };
    if dy.reference_photons.is_some() {
        return refuse(
            "dynamic.reference_photons",
            "a reference run traces a scene's lights: with detp.source = \"lines\" there is none",
        );
    }
    dy.check()?;
    let d = &raw.detp;
    let (predict, predictor, feed) = dy.choices(d.engine)?;
    Ok(QuasiStaticConfig {
        scene: crate::detp::quasi_static::lines::lines_scene(ratio),
        spacing: crate::theory::detp::ball_spacing(1.0, n as f64),
        detp,
        frames: dy.frames as u32,
        ratio: Some(ratio),
        crossover: dy.crossover,
        check_every: dy.check_every,
        engine: d.engine.unwrap_or_default(),
        points_frame: dy.points_frame.map(|f| f as u32),
        reference_photons: None,
        feed,
        predict,
        predictor,
        warm_repeats: dy.warm_repeats,
        warnings: Vec::new(),
        lines: true,
    })
}

/// Kind quasi-static runs the paper's method with its own per-object engine choice, for scenes and
/// lines alike: the edge remedies and the other engines of `detp.engines` belong to kind detp; of
/// its baselines only `"path-tracing"` runs here (per frame, [`super::path_tracing`]).
fn paper_method_only(detp: &DetpConfig) -> Result<(), ConfigError> {
    if detp.direct != crate::experiment::detp::config::Direct::Photons {
        return refuse(
            "detp.direct",
            "kind quasi-static traces all light in its photons (\"photons\"); \"nee\" is measured by kind \"detp\"",
        );
    }
    if detp.edge != crate::detp::edge::EdgeMode::Paper {
        return refuse(
            "detp.edge",
            "kind quasi-static runs the paper's method only (its incremental updates keep the stored segments and d); the remedies are measured by kind \"detp\"",
        );
    }
    if detp.radius_crossings.is_some() {
        return refuse(
            "detp.radius_crossings",
            "kind quasi-static keeps one integer sum per disc and updates it as objects move; the k-nearest-crossings radius (each disc's k nearest crossings) is measured by kind \"detp\"",
        );
    }
    // `check_engines` already refused duplicates and a list of baselines alone.
    if detp
        .engines
        .iter()
        .any(|e| !(e.is::<SphereCache>() || e.is::<PathTracing>()))
    {
        return refuse(
            "detp.engines",
            "kind quasi-static chooses its engine per object with detp.engine (hybrid, sphere-cache, disc-index, predicted); detp.engines takes \"sphere-cache\" and, to path-trace frame 0 and the checked frames, \"path-tracing\"",
        );
    }
    Ok(())
}

impl RawDynamicSpec {
    /// The engine choices of `[dynamic]`, shared by scenes and lines: the predictor's fraction (set,
    /// or 0.05 when the engine is "predicted"), which predictor, the feed; warm timings and the
    /// paper's predictor need the predictor to run.
    fn choices(
        &self,
        engine: Option<DynamicEngine>,
    ) -> Result<(Option<f64>, Predictor, Feed), ConfigError> {
        let predict = self
            .predict
            .or((engine == Some(DynamicEngine::Predicted)).then_some(0.05));
        if self.warm_repeats > 0 && predict.is_none() {
            return refuse(
                "dynamic.warm_repeats",
                "times the engines beside the predictor: set dynamic.predict or detp.engine = \"predicted\"",
            );
        }
        if self.predictor == PredictorChoice::Paper && predict.is_none() {
            return refuse(
                "dynamic.predictor",
                "chooses the §4.1 predictor: set dynamic.predict or detp.engine = \"predicted\"",
            );
        }
        if self.warm_repeats > 1000 {
            return refuse(
                "dynamic.warm_repeats",
                format!("got {}, at most 1000", self.warm_repeats),
            );
        }
        let predictor = match self.predictor {
            PredictorChoice::Subsample => Predictor::Subsample,
            PredictorChoice::Paper => Predictor::Paper,
        };
        let feed = match self.feed {
            FeedChoice::Paper => Feed::Paper,
            FeedChoice::SegmentIndex => Feed::SegmentIndex,
            FeedChoice::All => Feed::All,
        };
        Ok((predict, predictor, feed))
    }

    /// The rules within `[dynamic]`: at most 2²⁰ frames, a points frame among them, at most 2³¹
    /// reference photons.
    fn check(&self) -> Result<(), ConfigError> {
        if let Some(n) = self.reference_photons {
            if n > 1 << 31 {
                return refuse("dynamic.reference_photons", format!("got {n}, at most 2³¹"));
            }
        }
        if self.frames > 1 << 20 {
            return refuse(
                "dynamic.frames",
                format!("got {}, at most 2²⁰", self.frames),
            );
        }
        if let Some(f) = self.points_frame {
            if f >= self.frames {
                return refuse(
                    "dynamic.points_frame",
                    format!("got {f}, the frames are 0…{}", self.frames - 1),
                );
            }
        }
        Ok(())
    }
}

/// The scene of `file` with its dynamic objects scaled to `ratio` r_0 (keyframed AFF objects keep
/// their size: refused).
fn scaled(file: &SceneFile, ratio: Option<f64>) -> Result<Scene, ConfigError> {
    if ratio.is_some() {
        if let Some(m) = file.scene.movers.iter().find(|m| m.is_keyframed()) {
            return refuse(
                "dynamic.ratio",
                format!(
                    "dynamic object \"{}\" is keyframed (an AFF scene): it keeps its size; r_D/r_0 can be swept for scene-file objects with a path",
                    m.name
                ),
            );
        }
    }
    let mut scene = file.scene.clone();
    apply_ratio(&mut scene, ratio);
    Ok(scene)
}

/// Scales every dynamic object about its centre to r_D = ratio·r_0 (r_0: the radius of the sphere
/// around the scene's static box).
pub fn apply_ratio(scene: &mut crate::lt::Scene, ratio: Option<f64>) {
    let Some(ratio) = ratio else { return };
    let r0 = crate::detp::sphere_cache::root_sphere(&scene.bounds()).1;
    for m in &mut scene.movers {
        m.scale = ratio * r0 / m.rest_radius.max(1e-300);
    }
}

/// The motion's checks over every frame: a dynamic object at all; none as large as the scene
/// (r_D < r_0); each inside the scene's box (to 1 % of its diagonal) at every frame; no two
/// overlapping (posed boxes meet).
pub fn check_motion(
    scene: &crate::lt::Scene,
    frames: u32,
    blame: &str,
) -> Result<Vec<String>, ConfigError> {
    let mut warnings = Vec::new();
    use crate::lt::motion::tau;
    if scene.movers.is_empty() {
        return refuse(
            "detp.scene",
            "kind quasi-static needs a dynamic object: mark surfaces with dynamic = \"NAME\" and add a [[dynamic]] table (or an AFF animated transform)",
        );
    }
    let b = scene.bounds();
    let r0 = crate::detp::sphere_cache::root_sphere(&b).1;
    // Poking out of the box by up to 1 % of its diagonal is allowed (BART's robots dip their feet
    // 4 cm under a 535-unit-tall city); the segment index searches outside its box exactly anyway.
    let slack = 0.01 * (b.hi - b.lo).length();
    for m in &scene.movers {
        if m.radius() >= r0 {
            return refuse(
                blame,
                format!(
                "dynamic object \"{}\" has r_D = {:.4} ≥ r_0 = {:.4}: it is larger than the scene",
                m.name,
                m.radius(),
                r0
            ),
            );
        }
    }
    // Every frame when there are few, else 4096 evenly spaced ones plus the ends (motions are smooth).
    let step = (frames / 4096).max(1);
    let mut fs: Vec<u32> = (0..frames).step_by(step as usize).collect();
    fs.push(frames - 1);
    for f in fs {
        let t = tau(f, frames);
        let boxes: Vec<(glam::DVec3, glam::DVec3)> = scene
            .movers
            .iter()
            .map(|m| {
                let p = m.posed(t);
                let mut lo = glam::DVec3::splat(f64::INFINITY);
                let mut hi = -lo;
                for v in p.triangles.iter().flat_map(|t| t.v) {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                for s in &p.balls {
                    lo = lo.min(s.center - s.radius);
                    hi = hi.max(s.center + s.radius);
                }
                (lo, hi)
            })
            .collect();
        for (m, (lo, hi)) in scene.movers.iter().zip(&boxes) {
            if lo.cmplt(b.lo - slack).any() || hi.cmpgt(b.hi + slack).any() {
                return refuse(blame, format!(
                        "dynamic object \"{}\" leaves the scene's box at frame {f} (its box {lo:.3}…{hi:.3}, the scene's {:.3}…{:.3})",
                        m.name, b.lo, b.hi
                    ));
            }
        }
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                let (a, c) = (boxes[i], boxes[j]);
                let pair = (&scene.movers[i].name, &scene.movers[j].name);
                if a.0.cmple(c.1).all()
                    && c.0.cmple(a.1).all()
                    && !warnings
                        .iter()
                        .any(|w: &String| w.contains(&format!("\"{}\" and \"{}\"", pair.0, pair.1)))
                {
                    // Boxes meeting is not proof of interpenetration (BART's robots walk side by
                    // side), and exactness does not depend on it: a counted warning.
                    warnings.push(format!(
                        "dynamic objects \"{}\" and \"{}\" may overlap: their boxes meet at frame {f}",
                        pair.0, pair.1
                    ));
                }
            }
        }
    }
    Ok(warnings)
}

/// Lights shut inside closed geometry light nothing: a point or spot light inside a sphere seen from
/// outside is refused (`Scene` has no other closed solids it can decide exactly).
pub fn check_lights(scene: &crate::lt::Scene) -> Result<(), ConfigError> {
    use crate::lt::Light;
    let mut enclosed = 0;
    let mut lights = 0;
    for l in &scene.lights {
        let (Light::Point { position, .. } | Light::Spot { position, .. }) = l else {
            continue;
        };
        lights += 1;
        if scene
            .balls
            .iter()
            .copied()
            .chain(scene.movers.iter().flat_map(|m| m.posed(0.0).balls))
            .any(|b| !b.inside && b.center.distance(*position) < b.radius)
        {
            enclosed += 1;
        }
    }
    if lights > 0 && enclosed == lights && lights == scene.lights.len() {
        return refuse("detp.scene", format!(
            "every light ({lights}) is inside a closed sphere seen from outside: no photon can leave it"
        ));
    }
    Ok(())
}
