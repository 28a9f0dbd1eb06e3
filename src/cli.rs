//! Command-line definitions only (clap derive). Nothing below this layer imports clap.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::experiment::runner::Shard;

/// `--version`: the crate version, the git commit it was built from (and whether the tree was
/// dirty), and the compiler, as `meta.toml` records them.
const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (commit ",
    env!("RAYCOST_GIT_COMMIT"),
    ", dirty tree: ",
    env!("RAYCOST_GIT_DIRTY"),
    "; ",
    env!("RAYCOST_RUSTC"),
    ")"
);

/// The top-level `--help`'s epilogue: the exit codes scripts rely on.
const EXIT_CODES: &str = "\
Exit codes:
  0    success
  1    a built-in check failed (the tables are kept as evidence), or an internal failure
  2    bad input or usage: a spec, scene or points file, a flag, a refused output (nothing written)
  130  interrupted (Ctrl-C): what was kept and the command that resumes are printed
  101  a panic: a bug in raycost, please report it

Start: raycost check experiments/quickstart.toml && raycost run experiments/quickstart.toml
Reference: docs/cli.md, docs/spec.md, docs/scene.md, docs/columns.md (or raycost doc, raycost man)";

/// Measure what ray-tracing acceleration structures really cost, against closed-form theory.
#[derive(Debug, Parser)]
#[command(name = "raycost", version = VERSION, about, long_about = None, propagate_version = true,
          after_help = EXIT_CODES)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run an experiment spec and write DIR/NAME/NAME.csv (+ .meta.toml, .hist.csv).
    #[command(after_help = "\
Examples:
  raycost run experiments/quickstart.toml
  raycost run experiments/grid-cell-width.toml --set experiment.rays=100000 --out /tmp/r
  raycost run spec.toml --shard 2/8          # points 2, 10, 18, …; then raycost merge
  raycost run detp.toml --photon-shard 2/8   # photons [2P/8, 3P/8) of every point; then merge
  raycost run spec.toml --resume             # continue after Ctrl-C")]
    Run(RunArgs),
    /// Validate a spec and print its expanded points; runs nothing.
    #[command(after_help = "\
Examples:
  raycost check experiments/detp-accuracy.toml
  raycost check spec.toml --set detp.q=0.5 --json | jq '.points[].work'")]
    Check(CheckArgs),
    /// Print closed forms for given parameters.
    #[command(after_help = "\
Examples:
  raycost theory grid --intensity 1 --radius 0.2 --cell-width 0.5
  raycost theory detp --rays 1e6 --points 1e5 --json")]
    Theory(TheoryArgs),
    /// Speed figures of every engine, side by side in one run (results/bench/bench.csv).
    #[command(after_help = "\
Examples:
  raycost bench --quick --out /tmp/r
  raycost bench --threads 4 --force")]
    Bench(BenchArgs),
    /// Join the shards of a sweep (NAME.shard-K-of-N.csv), or a run's photon shards
    /// (NAME.photon-shard-K-of-N.json), into NAME.csv, checking that they fit.
    #[command(after_help = "\
Examples:
  raycost merge results/grid-scaling
  raycost merge results/detp-big            # its NAME.photon-shard-*-of-N.json: sums added
  raycost merge a/x.shard-0-of-2.csv b/x.shard-1-of-2.csv --out x.csv")]
    Merge(MergeArgs),
    /// Which method when (DETP, a photon map or per-point path tracing): from a fronts run, an n_P sweep and optionally a frames run of
    /// one scene, the photons or paths each method needs per target error, N* (points beyond which
    /// DETP beats path tracing, with a bootstrap CI) and F* (frames), in DIR/crossover.csv,
    /// DIR/best.csv and DIR/frames.csv.
    #[command(after_help = "\
Examples:
  raycost crossover results/fronts-cornell results/point-sweep-cornell \\
      --targets 0.1,0.05,0.02 --out results/which-method-cornell
  raycost crossover fronts points frames --targets 0.05 --out /tmp/x --force")]
    Crossover(CrossoverArgs),
    /// Rerun a result from its metadata (spec, --set, seed, run, shard; or a crossover's inputs)
    /// into a scratch folder and compare: counted columns byte for byte, timings against their
    /// intervals. Exit 0 reproduced, 1 something counted differs, 2 refused (the spec or an input
    /// changed).
    #[command(after_help = "\
Examples:
  raycost reproduce results/quickstart
  raycost reproduce results/detp-engines-cost/runs/1 --threads 2
  raycost reproduce results/which-method-hard --out /tmp/rerun --force
  raycost reproduce results/grid-first-hit --json | jq '.tables[] | select(.same | not)'

Counted columns are every column whose class in NAME.meta.toml is not timing. A timing X_mean with
an X_se beside it is held to |a - b| <= 3*sqrt(se_a^2 + se_b^2) when both runs had the same CPU
model and a quiet machine; other timings are reported as ratios only.")]
    Reproduce(ReproduceArgs),
    /// Render the DETP radiosity (B = albedo·E/π) of a quasi-static spec's frame(s), seen from the
    /// scene's camera.
    #[command(after_help = "\
Examples:
  raycost render experiments/render-cornell.toml --frame 3 --out cornell.png
  raycost render experiments/render-cornell.toml --frames 0,2,4,6 --gif cornell.gif --colormap")]
    Render(RenderArgs),
    /// Print reference documentation generated from the code, as Markdown.
    #[command(after_help = "\
Examples:
  raycost doc spec > docs/spec.md
  raycost doc columns | less")]
    Doc(DocArgs),
    /// Write DIR/index.html: one static page of every result (plots, claims, tables, bench).
    #[command(after_help = "\
Examples:
  raycost report --out report              # report/index.html of results/
  raycost report scratch --out scratch/report --force")]
    Report(ReportArgs),
    /// Print a shell completion script.
    #[command(after_help = "\
Examples:
  raycost completions bash > ~/.local/share/bash-completion/completions/raycost
  raycost completions zsh > ~/.zfunc/_raycost
  raycost completions fish > ~/.config/fish/completions/raycost.fish")]
    Completions(CompletionsArgs),
    /// Print the man page (roff).
    #[command(after_help = "\
Examples:
  raycost man > ~/.local/share/man/man1/raycost.1 && man raycost
  raycost man | man -l -")]
    Man,
}

/// `raycost report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// The results root.
    #[arg(default_value = "results")]
    pub results: PathBuf,
    /// The output folder (index.html, img/).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Replace an existing DIR/index.html.
    #[arg(long)]
    pub force: bool,
}

/// `raycost crossover`.
#[derive(Debug, Args)]
pub struct CrossoverArgs {
    /// The fronts' results folder (kind detp with engine reference and ≥ 2 replicas: it reads
    /// NAME.replica_errors.csv, or the points table of a run written before that table);
    /// with runs/R (raycost run --run R) every run, each adding configurations of its own (e.g. a
    /// radius rule that cannot share the first run's sweep).
    pub fronts: PathBuf,
    /// The n_P sweep's results folder (kind detp over detp.points × detp.photons); with runs/R
    /// every run.
    pub points: PathBuf,
    /// A frames run's results folder (kind quasi-static with path-tracing columns), optional.
    pub frames: Option<PathBuf>,
    /// Target relative RMSEs, comma-separated.
    #[arg(long, value_delimiter = ',', required = true, value_name = "EPS,...")]
    pub targets: Vec<f64>,
    /// A head-to-head run's results folder (kind detp: DETP at N_ε and path tracing at its paths
    /// per point on the same points at a few n_P around N*): its measured crossing goes beside the
    /// predicted one (n_star_head_to_head).
    #[arg(long, value_name = "DIR")]
    pub confirm: Option<PathBuf>,
    /// The output folder (crossover.csv, best.csv, frames.csv, crossover.meta.toml).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Replace existing outputs.
    #[arg(long)]
    pub force: bool,
}

/// `raycost reproduce`.
#[derive(Debug, Args)]
pub struct ReproduceArgs {
    /// The result folder (NAME.csv + NAME.meta.toml, or a crossover's crossover.meta.toml).
    pub dir: PathBuf,
    /// The scratch folder the rerun writes (default: a fresh temporary folder, removed when the
    /// result reproduces); never inside DIR or the spec's folder.
    #[arg(long, value_name = "SCRATCH")]
    pub out: Option<PathBuf>,
    /// Worker threads (default: the count the result recorded, at most this machine's cores; the
    /// counted columns do not depend on it, the timings do).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Replace the rerun's files in SCRATCH if they exist.
    #[arg(long)]
    pub force: bool,
    /// Print the comparison as JSON (the exit code is the same).
    #[arg(long)]
    pub json: bool,
    /// Timing means: held against their stated intervals (`judge`) or only reported (`report`;
    /// a run's standard errors cover its replicas, not the spread between separate runs).
    #[arg(long, value_enum, default_value_t = Timings::Judge)]
    pub timings: Timings,
    /// Only check that the result can be rerun as recorded (spec and its keys' defaults, inputs,
    /// point count; a crossover's input files): runs and writes nothing. Exit 0 if it can, 2 with
    /// the reason if not.
    #[arg(long)]
    pub check: bool,
}

/// How `raycost reproduce` treats timing means.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Timings {
    /// Held against their stated intervals when both runs are comparable.
    Judge,
    /// Reported as ratios, never counted.
    Report,
}

/// `raycost completions`.
#[derive(Debug, Args)]
pub struct CompletionsArgs {
    /// The shell.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}

/// `raycost doc`.
#[derive(Debug, Args)]
pub struct DocArgs {
    /// What to print.
    #[arg(value_enum)]
    pub what: DocTopic,
}

/// A reference topic.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum DocTopic {
    /// The experiment kinds: what each measures and its tables (docs/kinds.md).
    Kinds,
    /// Every CSV column of every kind: unit, class and meaning (docs/columns.md).
    Columns,
    /// Every spec key: type, unit, default, allowed values, kinds, meaning (docs/spec.md).
    Spec,
    /// Every scene-file key and the scene conventions (docs/scene.md).
    Scene,
}

/// `raycost render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// A kind quasi-static spec (or kind detp with detp.source = "scene": frame 0 only).
    pub spec: PathBuf,
    /// Worker threads (default: all cores; at most 8 per CPU).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Override a spec key; repeatable.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// The frame to render (default 0).
    #[arg(long, conflicts_with = "frames")]
    pub frame: Option<u32>,
    /// Several frames, side by side in one PNG (left to right, reached in this order).
    #[arg(long, value_delimiter = ',', value_name = "F1,F2,...")]
    pub frames: Vec<u32>,
    /// Which sweep point of the spec (0-based).
    #[arg(long, default_value_t = 0)]
    pub point: usize,
    /// The PNG (default results/render/NAME.frame-F.png).
    #[arg(long, value_name = "PNG")]
    pub out: Option<PathBuf>,
    /// Also an animated GIF of the frames.
    #[arg(long, value_name = "GIF")]
    pub gif: Option<PathBuf>,
    /// Also the difference image |incremental − full recalculation| (black: exact; red: not), and
    /// the count of differing pixels on stdout.
    #[arg(long, value_name = "PNG")]
    pub diff: Option<PathBuf>,
    /// Image width in pixels (the height keeps the camera's aspect ratio).
    #[arg(long)]
    pub width: Option<u32>,
    /// Three panels: the paper's method, this detp.edge remedy (clamp-radius, first-hit,
    /// clamp-first-hit; parameters from the spec or their defaults) and |difference|.
    #[arg(long, value_name = "MODE")]
    pub compare_edge: Option<String>,
    /// False colour (viridis) instead of grey.
    #[arg(long)]
    pub colormap: bool,
    /// Move the scene's camera: eye position X,Y,Z.
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        value_name = "X,Y,Z"
    )]
    pub eye: Vec<f64>,
    /// Aim the scene's camera at X,Y,Z.
    #[arg(
        long = "look-at",
        value_delimiter = ',',
        allow_negative_numbers = true,
        value_name = "X,Y,Z"
    )]
    pub look_at: Vec<f64>,
    /// The camera's vertical field of view, degrees.
    #[arg(long)]
    pub fov: Option<f64>,
    /// Replace existing files.
    #[arg(long)]
    pub force: bool,
}

/// `raycost run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The experiment spec (TOML).
    pub spec: PathBuf,
    /// Results root.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Override a spec key, e.g. --set grid.cell_width=0.7 (TOML value syntax); repeatable.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Replace existing results (or a partial run).
    #[arg(long)]
    pub force: bool,
    /// No progress bar and no summary.
    #[arg(long)]
    pub quiet: bool,
    /// Run only the points with index ≡ K (mod N); writes NAME.shard-K-of-N.csv.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// Continue a partial run, skipping the points it finished.
    #[arg(long)]
    pub resume: bool,
    /// Separate run R of the spec: sets experiment.run = R (mixed into the seed) and writes
    /// OUT/NAME/runs/R/NAME.csv.
    #[arg(long, value_name = "R")]
    pub run: Option<u64>,
    /// Runs the spec K times, as K separate processes (runs 0 … K−1, each as --run R would run it
    /// alone).
    #[arg(long, value_name = "K", conflicts_with = "run", value_parser = clap::value_parser!(u64).range(1..=1000))]
    pub repeat: Option<u64>,
    /// Trace only photons [K·P/N, (K+1)·P/N) of every point and replica (kinds detp and
    /// quasi-static); writes NAME.photon-shard-K-of-N.json for raycost merge.
    #[arg(long, value_name = "K/N", conflicts_with_all = ["shard", "resume", "run", "repeat"])]
    pub photon_shard: Option<Shard>,
}

/// `raycost merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// A results folder DIR/NAME holding NAME.shard-K-of-N.csv (+ .meta.toml, .hist.csv) or
    /// NAME.photon-shard-K-of-N.json, or those files.
    #[arg(required = true, value_name = "DIR|FILES")]
    pub inputs: Vec<PathBuf>,
    /// The merged table (default: NAME.csv beside the shards; .hist.csv and .meta.toml go beside it).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Replace existing merged files.
    #[arg(long)]
    pub force: bool,
    /// Print nothing on success.
    #[arg(long)]
    pub quiet: bool,
}

/// `raycost check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The experiment spec (TOML).
    pub spec: PathBuf,
    /// Override a spec key; repeatable.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Print JSON instead of text: the points with their parameters, work, memory and warnings.
    #[arg(long)]
    pub json: bool,
}

/// `raycost theory`.
#[derive(Debug, Args)]
pub struct TheoryArgs {
    /// Which theory.
    #[command(subcommand)]
    pub which: TheoryCommand,
}

/// Theories.
#[derive(Debug, Subcommand)]
pub enum TheoryCommand {
    /// Regular grid over Poisson spheres (Márton & Szirmay-Kalos).
    Grid(GridTheoryArgs),
    /// DETP: sphere cache vs disc indexing, rays per level, quasi-static crossover.
    Detp(DetpTheoryArgs),
}

/// `raycost theory detp`.
#[derive(Debug, Args)]
pub struct DetpTheoryArgs {
    /// n_R, rays (photon segments or lines).
    #[arg(long)]
    pub rays: f64,
    /// n_P, irradiance points.
    #[arg(long)]
    pub points: f64,
    /// Q, ratio of consecutive sphere radii.
    #[arg(long, default_value_t = 2.0 / 3.0)]
    pub q: f64,
    /// r_D/r_0, the dynamic object's bounding radius over the root sphere's.
    #[arg(long, default_value_t = 0.1)]
    pub ratio: f64,
    /// Subdivision threshold (rays).
    #[arg(long, default_value_t = 100.0)]
    pub threshold: f64,
    /// Print JSON instead of the table (the same numbers, unrounded).
    #[arg(long)]
    pub json: bool,
}

/// `raycost theory grid`.
#[derive(Debug, Args)]
pub struct GridTheoryArgs {
    /// ρ, sphere centres per unit volume.
    #[arg(long)]
    pub intensity: f64,
    /// r, sphere radius.
    #[arg(long)]
    pub radius: f64,
    /// a, cell width.
    #[arg(long = "cell-width")]
    pub cell_width: f64,
    /// Eye placement in its cell.
    #[arg(long, value_enum, default_value = "uniform")]
    pub eye: EyeArg,
    /// Print JSON instead of the table (the same numbers, unrounded).
    #[arg(long)]
    pub json: bool,
}

/// Eye placement.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum EyeArg {
    /// On a cell corner.
    Corner,
    /// Uniform in its cell.
    Uniform,
}

/// `raycost bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Small sizes only (for CI): n up to 10⁵.
    #[arg(long)]
    pub quick: bool,
    /// Largest thread count measured (default: all cores; at most 8 per CPU).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Results root.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Replace an existing bench table.
    #[arg(long)]
    pub force: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cli_definition_is_consistent() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }
}
