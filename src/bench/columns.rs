//! Every column `raycost bench` writes, declared once with its class (the bench tables are unions
//! of engines' rows: each row writes the columns it has, NaN elsewhere).

use crate::output::column::{Class, Column};

/// instruction-set path of the light-transport core.
pub const BVH_PATH: Column = Column::value(
    "bvh_path",
    "",
    Class::Parameter,
    "instruction-set path of the light-transport core",
);
/// rays whose first hit Embree places elsewhere than the exact core.
pub const EMBREE_DISAGREE: Column = Column::value(
    "embree_disagree",
    "",
    Class::Measured,
    "rays whose first hit Embree places elsewhere than the exact core",
);
/// seconds per ray of the exact core over Embree's (median of paired rounds).
pub const EMBREE_RATIO: Column = Column::value(
    "embree_ratio",
    "",
    Class::Timing,
    "seconds per ray of the exact core over Embree's (median of paired rounds)",
);
/// the light-transport scene.
pub const SCENE: Column = Column::value("scene", "", Class::Parameter, "the light-transport scene");
/// seconds building the structure.
pub const BUILD_S: Column = Column::value(
    "build_s",
    "s",
    Class::Timing,
    "seconds building the structure",
);
/// seconds per cell step (implied).
pub const CELL_S: Column = Column::value(
    "cell_s",
    "s",
    Class::Timing,
    "seconds per cell step (implied)",
);
/// grid cell width a.
pub const CELL_WIDTH: Column =
    Column::value("cell_width", "", Class::Parameter, "grid cell width a");
/// grid cells.
pub const CELLS: Column = Column::value("cells", "", Class::Measured, "grid cells");
/// rays or discs checked against the reference.
pub const CHECKED: Column = Column::value(
    "checked",
    "",
    Class::Measured,
    "rays or discs checked against the reference",
);
/// the engine benchmarked.
pub const ENGINE: Column = Column::value("engine", "", Class::Parameter, "the engine benchmarked");
/// where the rays start.
pub const EYE: Column = Column::value("eye", "", Class::Parameter, "where the rays start");
/// rays whose f32 and f64 first hits differ by a tie.
pub const F32_TIES: Column = Column::value(
    "f32_ties",
    "",
    Class::Measured,
    "rays whose f32 and f64 first hits differ by a tie",
);
/// SIMD path of the sphere-cache filter.
pub const FILTER_PATH: Column = Column::value(
    "filter_path",
    "",
    Class::Parameter,
    "SIMD path of the sphere-cache filter",
);
/// the finite reference grid's cell width.
pub const FINITE_CELL_WIDTH: Column = Column::value(
    "finite_cell_width",
    "",
    Class::Parameter,
    "the finite reference grid's cell width",
);
/// spheres in the finite reference scene.
pub const FINITE_N: Column = Column::value(
    "finite_n",
    "",
    Class::Parameter,
    "spheres in the finite reference scene",
);
/// the finite reference's rays per second.
pub const FINITE_RAYS_PER_S: Column = Column::value(
    "finite_rays_per_s",
    "1/s",
    Class::Timing,
    "the finite reference's rays per second",
);
/// seconds per frame.
pub const FRAME_S: Column = Column::value("frame_s", "s", Class::Timing, "seconds per frame");
/// spheres generated per ray (lazy infinite scene).
pub const GENERATED_MEAN: Column = Column::value(
    "generated_mean",
    "",
    Class::Measured,
    "spheres generated per ray (lazy infinite scene)",
);
/// fraction of rays that hit.
pub const HIT_MEAN: Column =
    Column::value("hit_mean", "", Class::Measured, "fraction of rays that hit");
/// implied seconds per unit of work.
pub const IMPLIED_S: Column = Column::value(
    "implied_s",
    "s",
    Class::Timing,
    "implied seconds per unit of work",
);
/// disagreements with the reference engine (0 when correct).
pub const MISMATCHES: Column = Column::value(
    "mismatches",
    "",
    Class::Check,
    "disagreements with the reference engine (0 when correct)",
);
/// scene size (spheres, or sample points).
pub const N: Column = Column::value(
    "n",
    "",
    Class::Parameter,
    "scene size (spheres, or sample points)",
);
/// mean distinct spheres tested per ray (mailbox).
pub const N_I_MB_MEAN: Column = Column::value(
    "n_i_mb_mean",
    "",
    Class::Measured,
    "mean distinct spheres tested per ray (mailbox)",
);
/// mean ray–sphere tests per ray.
pub const N_I_MEAN: Column = Column::value(
    "n_i_mean",
    "",
    Class::Measured,
    "mean ray–sphere tests per ray",
);
/// mean cell steps per ray.
pub const N_S_MEAN: Column =
    Column::value("n_s_mean", "", Class::Measured, "mean cell steps per ray");
/// peak resident bytes while running (machine dependent).
pub const PEAK_MEM_BYTES: Column = Column::value(
    "peak_mem_bytes",
    "bytes",
    Class::Timing,
    "peak resident bytes while running (machine dependent)",
);
/// photons re-traced per frame.
pub const PHOTONS_RETRACED: Column = Column::value(
    "photons_retraced",
    "",
    Class::Measured,
    "photons re-traced per frame",
);
/// ray–disc tests.
pub const RAY_DISC_TESTS: Column =
    Column::value("ray_disc_tests", "", Class::Measured, "ray–disc tests");
/// ray–disc tests per second.
pub const RAY_DISC_TESTS_PER_S: Column = Column::value(
    "ray_disc_tests_per_s",
    "1/s",
    Class::Timing,
    "ray–disc tests per second",
);
/// ray–sphere tests.
pub const RAY_SPHERE_TESTS: Column =
    Column::value("ray_sphere_tests", "", Class::Measured, "ray–sphere tests");
/// ray–sphere tests per second.
pub const RAY_SPHERE_TESTS_PER_S: Column = Column::value(
    "ray_sphere_tests_per_s",
    "1/s",
    Class::Timing,
    "ray–sphere tests per second",
);
/// rays traced in all rounds.
pub const RAYS: Column = Column::value("rays", "", Class::Parameter, "rays traced in all rounds");
/// rays per second.
pub const RAYS_PER_S: Column = Column::value("rays_per_s", "1/s", Class::Timing, "rays per second");
/// rays per scene realisation.
pub const RAYS_PER_SCENE: Column = Column::value(
    "rays_per_scene",
    "",
    Class::Parameter,
    "rays per scene realisation",
);
/// round number.
pub const ROUND: Column = Column::value("round", "", Class::Parameter, "round number");
/// slowest round, seconds.
pub const ROUND_MAX_S: Column =
    Column::value("round_max_s", "s", Class::Timing, "slowest round, seconds");
/// median round, seconds.
pub const ROUND_MEDIAN_S: Column = Column::value(
    "round_median_s",
    "s",
    Class::Timing,
    "median round, seconds",
);
/// fastest round, seconds.
pub const ROUND_MIN_S: Column =
    Column::value("round_min_s", "s", Class::Timing, "fastest round, seconds");
/// the round's seconds.
pub const ROUND_S: Column = Column::value("round_s", "s", Class::Timing, "the round's seconds");
/// timed rounds.
pub const ROUNDS: Column = Column::value("rounds", "", Class::Parameter, "timed rounds");
/// segments traced.
pub const SEGMENTS_TRACED: Column =
    Column::value("segments_traced", "", Class::Measured, "segments traced");
/// bytes of the acceleration structure.
pub const STRUCTURE_BYTES: Column = Column::value(
    "structure_bytes",
    "bytes",
    Class::Measured,
    "bytes of the acceleration structure",
);
/// largest relative difference of first-hit distances against the reference.
pub const T_REL_DIFF_MAX: Column = Column::value(
    "t_rel_diff_max",
    "",
    Class::Check,
    "largest relative difference of first-hit distances against the reference",
);
/// worker threads.
pub const THREADS: Column = Column::value("threads", "", Class::Parameter, "worker threads");
/// the engine that measured fastest.
pub const TIMED_BEST: Column = Column::value(
    "timed_best",
    "",
    Class::Timing,
    "the engine that measured fastest",
);
/// finite / infinite speed ratio (median over rounds).
pub const TIMED_FINITE_RATIO: Column = Column::value(
    "timed_finite_ratio",
    "",
    Class::Timing,
    "finite / infinite speed ratio (median over rounds)",
);
/// its largest round value.
pub const TIMED_FINITE_RATIO_MAX: Column = Column::value(
    "timed_finite_ratio_max",
    "",
    Class::Timing,
    "its largest round value",
);
/// its smallest round value.
pub const TIMED_FINITE_RATIO_MIN: Column = Column::value(
    "timed_finite_ratio_min",
    "",
    Class::Timing,
    "its smallest round value",
);
/// rays stopped at the walk limit.
pub const TRUNCATED: Column = Column::value(
    "truncated",
    "",
    Class::Measured,
    "rays stopped at the walk limit",
);
/// wall seconds.
pub const WALL_S: Column = Column::value("wall_s", "s", Class::Timing, "wall seconds");
