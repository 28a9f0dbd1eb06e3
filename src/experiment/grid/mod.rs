//! The three grid kinds of the Márton & Szirmay-Kalos study: `grid` (N_I, N_S, t* and the hit rate
//! against Results 3.1/3.2 and the exponential first-hit law), `grid-scaling` (finite scenes of
//! growing n: O(1) expected cost, brute force, Proposition 4.1's concentration) and `grid-cost-model`
//! (the machine's T_I and T_S and the model t = N_I·T_I + N_S·T_S). They share the spec file
//! (`spec.rs`), the validated point (`config.rs`), the tracer (`run.rs`), the measurement
//! (`measure.rs`: typed means, fits and histograms), the closed forms (`theory.rs`) and the columns
//! with their accessors (`columns.rs`); each kind adds what it measures beyond the common counts.

pub mod columns;
pub mod config;
pub mod measure;
pub mod run;
pub mod spec;
pub mod theory;

pub use config::{GridConfig, SceneModel, Variant};
pub use run::BATCH;
pub use spec::{GridSpec, DEFAULT_RAYS_PER_SCENE};

use super::inputs::Inputs;
use super::kind::{Check, ConfigError, Context, Kind, Memory, Need, Output, Rate, Table, Work};
use super::machine::{self, MachineCosts};
use crate::error::Error;
use measure::{GridMeasured, HistBin};

crate::side_tables!(
    /// `NAME.hist.csv`: the t* histogram against the exponential law, and the N_I,mb histogram
    /// against the fitted geometric law.
    GridTables for GridConfig { hist: HistBin = columns::HIST }
);

fn describe(g: &GridConfig) -> String {
    let scene = match &g.scene {
        SceneModel::Infinite => "infinite scene".to_string(),
        SceneModel::Finite(f) => format!(
            "finite scene, ~{:.0} spheres, side {:.4}",
            f.expected_count(),
            f.side()
        ),
    };
    format!("{scene}, {} rays", g.rays)
}

/// A finite scene's spheres and cell lists; an infinite scene's per-ray working set: the spheres
/// drawn for the first cell's reach box, ρ·(a + 2r_max)³ of them (each thread walks one ray at a
/// time; with shared realisations a batch's block of cells).
fn memory(g: &GridConfig, threads: usize) -> Memory {
    let r_max = g.classes.iter().map(|c| c.radius.max()).fold(0.0, f64::max);
    let threads = threads as f64;
    let needs = match &g.scene {
        SceneModel::Infinite => {
            let per_box = g.intensity * (g.cell_width + 2.0 * r_max).powi(3);
            let rays_in_flight = threads * (g.rays_per_scene as f64).max(1.0);
            // Blame the factor of ρ·(a + 2r)³ that drives it.
            let logs = [
                (g.intensity.ln(), "scene.intensity"),
                (3.0 * (2.0 * r_max).ln(), "scene.radius"),
                (3.0 * g.cell_width.ln(), "grid.cell_width"),
            ];
            let key = logs
                .iter()
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .map_or("scene.intensity", |l| l.1);
            vec![Need {
                bytes: per_box * 64.0 * rays_in_flight.max(1.0) * 8.0,
                key,
                what: format!("{per_box:.3e} spheres per cell reach box"),
                per_photon: false,
            }]
        }
        SceneModel::Finite(f) => {
            let n = f.expected_count();
            vec![Need {
                bytes: n * 40.0 * 2.0,
                key: "scene.spheres",
                what: format!("{n:.3e} spheres and their cell listings"),
                per_photon: false,
            }]
        }
    };
    Memory {
        needs,
        budget: Some(("grid.memory_budget_gib", g.memory_budget_gib)),
        batching: None,
    }
}

/// What distinguishes the three grid kinds: name, description, [`Variant`], and what a run measures
/// once (the cost model's machine constants).
pub trait GridVariant: Send + Sync + 'static {
    /// `experiment.kind`.
    const NAME: &'static str;
    /// Description.
    const ABOUT: &'static str;
    /// The variant of the shared tracer.
    const VARIANT: Variant;
    /// Measured once per run.
    type Shared: Send + Sync + 'static;
    /// Measures it.
    fn shared() -> Self::Shared;
    /// The machine constants, if this variant has them.
    fn machine(s: &Self::Shared) -> Option<MachineCosts>;
}

/// A grid kind: one impl of [`Kind`] for all three variants.
pub struct Grid<V>(std::marker::PhantomData<V>);

impl<V: GridVariant> Kind for Grid<V> {
    const NAME: &'static str = V::NAME;
    const ABOUT: &'static str = V::ABOUT;
    type Raw = GridSpec;
    type Point = GridConfig;
    type Measured = GridMeasured;
    type Tables = GridTables;
    type Shared = V::Shared;
    const MAIN: Table<GridConfig, GridMeasured> = columns::MAIN;

    fn configure(raw: &GridSpec, _: &mut Inputs) -> Result<GridConfig, ConfigError> {
        Ok(GridConfig::from_spec(raw, V::VARIANT)?)
    }
    fn describe(p: &GridConfig) -> String {
        describe(p)
    }
    fn work(p: &GridConfig) -> Work {
        Work {
            units: p.rays,
            unit: "rays",
            points: 1,
        }
    }
    fn memory(p: &GridConfig, threads: usize) -> Memory {
        memory(p, threads)
    }
    fn shared(_: &[&GridConfig]) -> Result<V::Shared, Error> {
        Ok(V::shared())
    }
    fn shared_meta(s: &V::Shared) -> toml::Table {
        let mut outer = toml::Table::new();
        if let Some(m) = V::machine(s) {
            let mut t = toml::Table::new();
            t.insert("t_i_s".into(), toml::Value::Float(m.t_i));
            t.insert("t_s_s".into(), toml::Value::Float(m.t_s));
            outer.insert("cost_model".into(), toml::Value::Table(t));
        }
        outer
    }
    fn run(
        p: &GridConfig,
        s: &V::Shared,
        ctx: &Context,
    ) -> Result<Output<GridMeasured, GridTables>, Error> {
        let traced = run::run_point(p, ctx.stream_point, ctx.threads, ctx.progress);
        let (measured, hist) = measure::measure(p, &traced, V::machine(s));
        let checks = measured
            .scaling
            .map(|s| Check {
                name: columns::BF_MISMATCHES.name,
                what: "the grid's first hit ≠ brute force's",
                failures: s.bf_mismatches,
                checked: s.bf_rays,
            })
            .into_iter()
            .collect();
        let rate = Rate {
            per_s: measured.rays_per_s,
            unit: "rays",
        };
        Ok(Output {
            measured,
            tables: GridTables { hist },
            checks,
            rate,
            warnings: Vec::new(),
        })
    }
}

/// Kind `grid`.
pub struct Study;

impl GridVariant for Study {
    const NAME: &'static str = "grid";
    const ABOUT: &'static str = "Rays from an eye through a regular grid (3D-DDA) over Poisson spheres (an infinite scene generated lazily where rays go, or a finite cube): ray–sphere tests N_I (with and without mailboxing) against Result 3.1/3.2's band and raycost's sharper predictors, cell steps N_S against their exact expectation, the first-hit distance t* against the exponential law (KS and χ²), and the hit rate.";
    const VARIANT: Variant = Variant::Study;
    type Shared = ();
    fn shared() {}
    fn machine(_: &()) -> Option<MachineCosts> {
        None
    }
}

/// Kind `grid-scaling`.
pub struct Scaling;

impl GridVariant for Scaling {
    const NAME: &'static str = "grid-scaling";
    const ABOUT: &'static str = "Finite Poisson scenes of growing sphere count n, several realisations each: N_I and N_S settle on the infinite scene's values (E[t(n)] = O(1)), brute force checks the grid's first hits, memory and build time grow with n, and Proposition 4.1's tails P(N_I ≥ c·ln n) and P(N_I ≥ c·√n) fall with n.";
    const VARIANT: Variant = Variant::Scaling;
    type Shared = ();
    fn shared() {}
    fn machine(_: &()) -> Option<MachineCosts> {
        None
    }
}

/// Kind `grid-cost-model`.
pub struct CostModel;

impl GridVariant for CostModel {
    const NAME: &'static str = "grid-cost-model";
    const ABOUT: &'static str = "The query-time model t = N_I·T_I + N_S·T_S: T_I and T_S measured on this machine once per run, the model's time from the predicted and from the measured counts, beside the timed query.";
    const VARIANT: Variant = Variant::CostModel;
    type Shared = MachineCosts;
    fn shared() -> MachineCosts {
        machine::measure()
    }
    fn machine(m: &MachineCosts) -> Option<MachineCosts> {
        Some(*m)
    }
}
