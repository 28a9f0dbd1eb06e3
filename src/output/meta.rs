//! `STEM.meta.toml`: the provenance of a result table, as one typed schema ([`Meta`], versioned by
//! [`SCHEMA`]) read and written by one codec ([`Meta::read`], [`Meta::render`]). The runner writes it
//! (a partial one when a run starts, the whole one when it ends), `--resume` and `raycost merge` read
//! it back, and `raycost bench` writes the same schema.
//!
//! It pins everything a number depends on: the tool (version, git commit and whether the tree was
//! dirty, rustc), the machine (CPU, its vector extensions and the SIMD paths the kernels took,
//! memory, load average at start and end), the run (spec and its hash, seed, threads, shard, `--set`
//! flags, points and their wall times), and a SHA-256 of every file the run read (scene, OBJ, AFF and
//! its includes, points CSV), so a resume or merge over changed inputs is refused naming the file.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::column::ColumnInfo;
use crate::error::OutputError;

/// Version of the metadata schema; readers refuse other versions by name.
pub const SCHEMA: u32 = 2;

/// Provenance of one run.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Meta {
    /// [`SCHEMA`].
    pub schema: u32,
    /// What built the binary.
    pub raycost: Build,
    /// The machine the run took place on.
    pub machine: Machine,
    /// How the run went.
    pub run: RunInfo,
    /// Every file the run read, with its content hash.
    #[serde(default)]
    pub inputs: Vec<InputFile>,
    /// Counted warnings (scene, points, physics sanity, a busy machine), one line each.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// The columns of each table (`main` for `STEM.csv`, else the side table's name), with classes.
    #[serde(default)]
    pub columns: BTreeMap<String, Vec<ColumnInfo>>,
    /// Kind-specific facts measured once per run (the cost model's T_I and T_S; bench calibration).
    #[serde(default, skip_serializing_if = "toml::Table::is_empty")]
    pub extra: toml::Table,
    /// The normalised spec (defaults filled in) and its sweep.
    #[serde(default)]
    pub spec: toml::Table,
    /// For a merged table: each shard's own build, machine and run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shards: Vec<ShardRecord>,
}

/// One shard of a merged table.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ShardRecord {
    /// The shard's CSV file name.
    pub file: String,
    /// What built it.
    pub raycost: Build,
    /// Where it ran.
    pub machine: Machine,
    /// How it ran.
    pub run: RunInfo,
}

/// Build identity.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Build {
    /// Crate version.
    pub version: String,
    /// Git commit the binary was built from ("unknown" without git).
    pub git_commit: String,
    /// Whether tracked files differed from that commit ("true", "false" or "unknown").
    pub git_dirty: String,
    /// `rustc --version` of the compiler.
    pub rustc: String,
}

impl Build {
    /// This binary.
    pub fn current() -> Self {
        Self {
            version: env!("CARGO_PKG_VERSION").into(),
            git_commit: env!("RAYCOST_GIT_COMMIT").into(),
            git_dirty: env!("RAYCOST_GIT_DIRTY").into(),
            rustc: env!("RAYCOST_RUSTC").into(),
        }
    }

    /// `VERSION (COMMIT[, dirty])`, for `--version`.
    pub fn describe(&self) -> String {
        let short = &self.git_commit[..self.git_commit.len().min(12)];
        let dirty = if self.git_dirty == "true" {
            ", dirty tree"
        } else {
            ""
        };
        format!("{} (commit {short}{dirty}; {})", self.version, self.rustc)
    }
}

/// The machine.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Machine {
    /// Host name.
    pub host: String,
    /// CPU model with family and model numbers (a VM's generic "AMD EPYC" needs them).
    pub cpu: String,
    /// Vector extensions the kernels dispatch on that this CPU has.
    pub isa: Vec<String>,
    /// The path each SIMD kernel takes here (kernel → path), chosen at run time.
    #[serde(default)]
    pub simd: BTreeMap<String, String>,
    /// Logical CPUs.
    pub cores: usize,
    /// Memory available to this process when the run started, bytes.
    pub memory_available_bytes: u64,
    /// Transparent huge page mode (the query grid asks for huge pages).
    pub transparent_hugepages: String,
}

impl Machine {
    /// This machine; `simd` names the path each kernel takes (filled by the engines' layers).
    pub fn current(simd: BTreeMap<String, String>) -> Self {
        Self {
            host: host_name(),
            cpu: cpu_model(),
            isa: isa_features(),
            simd,
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            memory_available_bytes: available_memory().unwrap_or(0),
            transparent_hugepages: std::fs::read_to_string(
                "/sys/kernel/mm/transparent_hugepage/enabled",
            )
            .map(|s| s.trim().to_string())
            .unwrap_or_else(|_| "unavailable".into()),
        }
    }
}

/// How a run went.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RunInfo {
    /// `run`, `bench` or `merge`.
    pub command: String,
    /// Spec path as given (empty for bench).
    #[serde(default)]
    pub spec_path: String,
    /// SHA-256 of the normalised spec (empty for bench).
    #[serde(default)]
    pub spec_hash: String,
    /// Master seed.
    #[serde(default)]
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
    /// `K/N`, or `all`.
    #[serde(default = "all")]
    pub shard: String,
    /// `--set` overrides.
    #[serde(default)]
    pub set: Vec<String>,
    /// Start, RFC 3339 UTC.
    pub started: String,
    /// End, RFC 3339 UTC (absent while the run goes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub finished: Option<String>,
    /// Wall seconds of the whole run (absent while the run goes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall_s: Option<f64>,
    /// 1-, 5- and 15-minute load averages when the run started.
    #[serde(default)]
    pub load_start: Vec<f64>,
    /// The same when it ended.
    #[serde(default)]
    pub load_end: Vec<f64>,
    /// Cores' worth of CPU that *other* processes used on average while the run went (the machine's
    /// busy time from `/proc/stat` less this process's own): 0 on a quiet machine. Above
    /// [`BUSY_CORES`] the run's timing columns are unreliable and a warning says so.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub other_cores: Option<f64>,
    /// CPU ticks (machine busy, this process) at the start, for `other_cores`.
    #[serde(skip)]
    pub cpu_start: Option<(u64, u64)>,
    /// Points of the whole sweep (all shards); `raycost merge` checks coverage against it.
    #[serde(default)]
    pub points_total: usize,
    /// Points in this file.
    #[serde(default)]
    pub points: Vec<usize>,
    /// Wall seconds of each point, in the order of `points`.
    #[serde(default)]
    pub point_wall_s: Vec<f64>,
    /// Points carried over from a resumed partial run (no wall time recorded here).
    #[serde(default)]
    pub resumed_points: Vec<usize>,
    /// Each point's memory, in the order of `points` (kinds with a memory budget).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub point_memory: Vec<PointMemory>,
}

/// One point's memory: its photon batches and the model's bytes beside the budget, and the
/// process's measured peak.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PointMemory {
    /// The point.
    pub point: usize,
    /// Photon batches it was traced in (1: one pass).
    pub batches: u64,
    /// The memory model's bytes for one batch (the whole point when `batches` is 1).
    pub model_bytes: f64,
    /// The budget key.
    pub budget_key: String,
    /// Its value, GiB.
    pub budget_gib: f64,
    /// The process's peak resident memory so far (`VmHWM` of `/proc/self/status`, bytes), read when
    /// the point finished: the largest over this point and every point before it in this process
    /// (absent where the system does not say).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_rss_bytes: Option<u64>,
}

fn all() -> String {
    "all".into()
}

/// A file the run read. It is identified by its `role` and its `location` (its place relative to
/// the spec's folder), and compared by its content hash: never by how its path was spelled, so
/// runs started from different working folders, or a result folder moved elsewhere, still resume
/// and merge (see [`changed_input`]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
pub struct InputFile {
    /// Its path as the run resolved it, from the folder it was started in (information only).
    pub path: String,
    /// Its place relative to the folder of the spec that names it, `/`-separated, both resolved
    /// through the file system (`scenes/cornell.toml`, `../meshes/a.obj`); for `raycost crossover`
    /// relative to the input result folder. Empty in metadata written before it was recorded:
    /// [`Meta::parse`] fills it in from `path` and the spec's path.
    #[serde(default)]
    pub location: String,
    /// What it is: `scene`, `obj`, `aff`, `points`.
    pub role: String,
    /// SHA-256 of its content.
    pub sha256: String,
    /// Its size.
    pub bytes: u64,
}

impl InputFile {
    /// Hashes `path` now; `base` is the folder its location is relative to (the spec's folder).
    pub fn hash(path: &Path, role: &str, base: &Path) -> std::io::Result<Self> {
        use sha2::{Digest, Sha256};
        let bytes = std::fs::read(path)?;
        Ok(Self {
            path: path.display().to_string(),
            location: super::location::relative_location(base, path),
            role: role.into(),
            sha256: format!("{:x}", Sha256::digest(&bytes)),
            bytes: bytes.len() as u64,
        })
    }

    /// The location of a record written before locations were: `path` was the spec's folder (as
    /// `spec_path` spells it, from the same working folder) joined with the spec's relative path,
    /// so taking that folder off gives the location; else `path` normalised.
    fn old_location(path: &str, spec_path: &str) -> String {
        use super::location::{normalise, slashed};
        let path = normalise(Path::new(path));
        let spec_dir = normalise(Path::new(spec_path).parent().unwrap_or(Path::new("")));
        let rel = if spec_path.is_empty() {
            path.file_name().map(Into::into).unwrap_or(path.clone())
        } else {
            path.strip_prefix(&spec_dir)
                .map(Path::to_path_buf)
                .unwrap_or_else(|_| super::location::relative(&spec_dir, &path))
        };
        slashed(&rel)
    }

    /// How a message names it: its role and location (`scene file cornell.toml`).
    fn named(&self) -> String {
        let at = if self.location.is_empty() {
            &self.path
        } else {
            &self.location
        };
        format!("{} file {at}", self.role)
    }

    /// Whether `other` is the same input: the same role and location, or, when either record has
    /// no location (an old photon shard file), the same role and content.
    fn same_input(&self, other: &InputFile) -> bool {
        self.role == other.role
            && if self.location.is_empty() || other.location.is_empty() {
                self.sha256 == other.sha256
            } else {
                self.location == other.location
            }
    }
}

/// Warnings of sweep points, each text once: `point 3: W`, or `points 0, 1, 2: W` when several
/// points have the same warning (the same points file or scene warns at every point that reads it).
pub fn point_warnings(warnings: &[(usize, String)]) -> Vec<String> {
    let mut grouped: Vec<(&str, Vec<usize>)> = Vec::new();
    for (point, w) in warnings {
        match grouped.iter_mut().find(|(t, _)| *t == w.as_str()) {
            Some((_, points)) if !points.contains(point) => points.push(*point),
            Some(_) => {}
            None => grouped.push((w.as_str(), vec![*point])),
        }
    }
    grouped
        .into_iter()
        .map(|(w, points)| match points.as_slice() {
            [p] => format!("point {p}: {w}"),
            ps if ps.len() <= 10 => format!(
                "points {}: {w}",
                ps.iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            ps => format!(
                "points {} … {} ({} points): {w}",
                ps[0],
                ps[ps.len() - 1],
                ps.len()
            ),
        })
        .collect()
}

/// The first input of `now` whose content differs from what `then` recorded (or that is new or
/// gone): the file a resume or merge must name when it refuses. Inputs are matched by role and
/// location relative to the spec ([`InputFile::location`]), whatever folder either run was started
/// from and however it spelled the path, and compared by content hash.
pub fn changed_input(then: &[InputFile], now: &[InputFile]) -> Option<String> {
    for t in then {
        let same_place = now
            .iter()
            .find(|n| n.role == t.role && n.location == t.location && !t.location.is_empty());
        match same_place.or_else(|| now.iter().find(|n| t.same_input(n))) {
            None => {
                return Some(format!(
                    "{} (read by the earlier run, not by this one)",
                    t.named()
                ))
            }
            Some(n) if n.sha256 != t.sha256 => {
                return Some(format!(
                    "{} (content changed: SHA-256 {} then, {} now)",
                    t.named(),
                    &t.sha256[..12.min(t.sha256.len())],
                    &n.sha256[..12.min(n.sha256.len())]
                ))
            }
            Some(_) => {}
        }
    }
    now.iter()
        .find(|n| !then.iter().any(|t| t.same_input(n)))
        .map(|n| format!("{} (not read by the earlier run)", n.named()))
}

impl Meta {
    /// The run's `experiment.kind`, as the spec it records says (`None` for a crossover's
    /// metadata, which records no spec).
    pub fn kind(&self) -> Option<&str> {
        self.spec
            .get("base")?
            .get("experiment")?
            .get("kind")?
            .as_str()
    }

    /// The column names this metadata records for `table` (`main` or a side table's name), in
    /// header order; `None` for a table it does not declare (results written before tables were
    /// declared), which readers then check on their own terms.
    pub fn declared(&self, table: &str) -> Option<Vec<String>> {
        self.columns
            .get(table)
            .map(|c| c.iter().map(|c| c.name.clone()).collect())
    }

    /// The metadata of a `command` starting now on this machine with this build: the run's own
    /// facts (spec, points, inputs, columns) are filled in by the caller.
    pub fn begin(command: &str, simd: BTreeMap<String, String>) -> Meta {
        Meta {
            schema: SCHEMA,
            raycost: Build::current(),
            machine: Machine::current(simd),
            run: RunInfo {
                command: command.into(),
                spec_path: String::new(),
                spec_hash: String::new(),
                seed: 0,
                threads: rayon::current_num_threads(),
                shard: all(),
                set: Vec::new(),
                started: crate::output::time::now_rfc3339(),
                finished: None,
                wall_s: None,
                load_start: load_average(),
                load_end: Vec::new(),
                other_cores: None,
                cpu_start: cpu_ticks(),
                points_total: 0,
                points: Vec::new(),
                point_wall_s: Vec::new(),
                resumed_points: Vec::new(),
                point_memory: Vec::new(),
            },
            inputs: Vec::new(),
            warnings: Vec::new(),
            columns: BTreeMap::new(),
            extra: toml::Table::new(),
            spec: toml::Table::new(),
            shards: Vec::new(),
        }
    }

    /// Marks the run finished now, `wall_s` after it started.
    pub fn end(&mut self, wall_s: f64) {
        self.run.finished = Some(crate::output::time::now_rfc3339());
        self.run.wall_s = Some(wall_s);
        self.run.load_end = load_average();
        if let (Some((busy0, own0)), Some((busy1, own1))) = (self.run.cpu_start, cpu_ticks()) {
            let others = busy1
                .saturating_sub(busy0)
                .saturating_sub(own1.saturating_sub(own0));
            let cores = others as f64 / CLOCK_TICKS / wall_s.max(1e-3);
            self.run.other_cores = Some((cores * 1000.0).round() / 1000.0);
            // Sub-second runs are too short for the kernel's tick accounting to say anything.
            if cores > BUSY_CORES && wall_s >= 1.0 {
                let w = format!(
                    "the machine was busy: other processes used {cores:.2} cores on average during this run, so its timing columns are unreliable (counts are not affected)"
                );
                if !self.warnings.contains(&w) {
                    self.warnings.push(w);
                }
            }
        }
    }

    /// Whether the run's timings were taken on a busy machine (see [`RunInfo::other_cores`]).
    /// Judged only for runs of a second or more (as [`Meta::end`] does: shorter ones are below the
    /// kernel's tick accounting), so that it is true exactly when `end` recorded the warning.
    pub fn busy(&self) -> bool {
        self.run.other_cores.is_some_and(|c| c > BUSY_CORES)
            && self.run.wall_s.is_some_and(|w| w >= 1.0)
    }

    /// TOML text (the one writer).
    pub fn render(&self) -> String {
        toml::to_string(self).expect("metadata serializes")
    }

    /// Reads and checks a metadata file (the one reader). A missing file, text that is not this
    /// schema, or another schema version is an [`OutputError`] naming the file.
    pub fn read(path: &Path) -> Result<Meta, OutputError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| OutputError::new(path, format!("cannot read the metadata: {e}")))?;
        Self::parse(&text).map_err(|m| OutputError::new(path, m.0))
    }

    /// Parses metadata text.
    pub fn parse(text: &str) -> Result<Meta, crate::error::Invalid> {
        let table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| format!("not TOML: {}", e.message()))?;
        match table.get("schema").and_then(toml::Value::as_integer) {
            Some(v) if v == i64::from(SCHEMA) => {}
            Some(v) => {
                return Err(format!(
                    "metadata schema {v}, this raycost reads schema {SCHEMA} (written by another version; rerun)"
                )
                .into())
            }
            None => {
                return Err(format!(
                    "no metadata schema (written by a raycost older than schema {SCHEMA}; rerun)"
                )
                .into())
            }
        }
        let mut meta: Meta = toml::Value::Table(table)
            .try_into()
            .map_err(|e: toml::de::Error| format!("unreadable metadata: {}", e.message()))?;
        for f in meta.inputs.iter_mut().filter(|f| f.location.is_empty()) {
            f.location = InputFile::old_location(&f.path, &meta.run.spec_path);
        }
        Ok(meta)
    }

    /// The names of the columns of `table` that must agree between runs (everything but timings).
    pub fn reproducible_columns(&self, table: &str) -> Vec<String> {
        self.columns
            .get(table)
            .map(|cols| {
                cols.iter()
                    .filter(|c| c.class.is_reproducible())
                    .map(|c| c.name.clone())
                    .collect()
            })
            .unwrap_or_default()
    }
}

/// Host name from the kernel (no extra dependency).
pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .or_else(|_| std::env::var("HOSTNAME"))
        .unwrap_or_else(|_| "unknown".into())
}

/// Other processes' mean CPU use, in cores, above which a run's timings are called unreliable.
pub const BUSY_CORES: f64 = 0.25;

/// Linux's `USER_HZ`, the unit of `/proc/stat` and `/proc/self/stat` (100 on every Linux ABI).
const CLOCK_TICKS: f64 = 100.0;

/// (ticks the whole machine spent busy, ticks this process spent on CPU), from `/proc/stat`'s `cpu`
/// line (user + nice + system + irq + softirq + steal) and `/proc/self/stat` (utime + stime);
/// `None` off Linux.
pub fn cpu_ticks() -> Option<(u64, u64)> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    let cpu: Vec<u64> = stat
        .lines()
        .next()?
        .split_whitespace()
        .skip(1)
        .filter_map(|x| x.parse().ok())
        .collect();
    // user nice system idle iowait irq softirq steal
    let busy = [0, 1, 2, 5, 6, 7]
        .iter()
        .map(|&i| cpu.get(i).copied().unwrap_or(0))
        .sum();
    let me = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name: state is field 3, utime 14, stime 15.
    let rest: Vec<&str> = me.rsplit_once(')')?.1.split_whitespace().collect();
    let own = rest.get(11)?.parse::<u64>().ok()? + rest.get(12)?.parse::<u64>().ok()?;
    Some((busy, own))
}

/// The 1-, 5- and 15-minute load averages (Linux `/proc/loadavg`; empty elsewhere).
pub fn load_average() -> Vec<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| {
            s.split_whitespace()
                .take(3)
                .filter_map(|x| x.parse().ok())
                .collect()
        })
        .unwrap_or_default()
}

/// A `KEY:  N kB` field of a `/proc` file (`/proc/meminfo`, `/proc/self/status`), in bytes.
fn proc_kib(file: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(file).ok()?;
    let kib: u64 = text
        .lines()
        .find_map(|l| l.strip_prefix(key)?.strip_prefix(':'))?
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    Some(kib * 1024)
}

/// This process's peak resident memory so far (`VmHWM` of `/proc/self/status`), in bytes.
pub fn peak_memory() -> Option<u64> {
    proc_kib("/proc/self/status", "VmHWM")
}

/// Memory this process can still allocate: the smaller of Linux's `MemAvailable` and the cgroup's
/// limit minus its usage (a container or Slurm job may allow far less than the machine has).
pub fn available_memory() -> Option<u64> {
    let mut avail = proc_kib("/proc/meminfo", "MemAvailable")?;
    let read = |p: &str| {
        std::fs::read_to_string(p)
            .ok()
            .map(|s| s.trim().to_string())
    };
    if let (Some(max), Some(cur)) = (
        read("/sys/fs/cgroup/memory.max"),
        read("/sys/fs/cgroup/memory.current"),
    ) {
        if let (Ok(max), Ok(cur)) = (max.parse::<u64>(), cur.parse::<u64>()) {
            avail = avail.min(max.saturating_sub(cur));
        }
    }
    // An address-space limit (`ulimit -v`, a batch system's): what is left of it.
    #[cfg(target_os = "linux")]
    {
        let mut lim = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: getrlimit writes the struct it is given and nothing else.
        let ok = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut lim) } == 0;
        if ok && lim.rlim_cur != libc::RLIM_INFINITY {
            let used = proc_kib("/proc/self/status", "VmSize").unwrap_or(0);
            avail = avail.min(lim.rlim_cur.saturating_sub(used));
        }
    }
    Some(avail)
}

/// The CPU model (Linux `/proc/cpuinfo`) with its family and model numbers: virtual machines often
/// report only a generic name ("AMD EPYC"), and the numbers tell a Zen 3 (family 25, model 1) from
/// a Zen 4 (family 25, model 17).
pub fn cpu_model() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let field = |key: &str| {
        info.lines()
            .find(|l| l.split(':').next().map(str::trim) == Some(key))
            .and_then(|l| l.split(':').nth(1))
            .map(|m| m.trim().to_string())
    };
    let name = field("model name").unwrap_or_else(|| "unknown".into());
    match (field("cpu family"), field("model")) {
        (Some(f), Some(m)) => format!("{name} (family {f}, model {m})"),
        _ => name,
    }
}

/// The vector extensions this CPU offers that raycost's kernels dispatch on.
pub fn isa_features() -> Vec<String> {
    #[cfg(target_arch = "x86_64")]
    {
        let mut found = Vec::new();
        macro_rules! probe {
            ($($f:tt),*) => {$(if is_x86_feature_detected!($f) { found.push($f.to_string()); })*};
        }
        probe!("avx512f", "avx512vl", "avx2", "fma", "bmi2");
        found
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::column::Class;

    fn sample() -> Meta {
        let mut columns = BTreeMap::new();
        columns.insert(
            "main".to_string(),
            vec![
                ColumnInfo {
                    name: "n_s_mean".into(),
                    class: Class::Measured,
                    unit: "steps".into(),
                },
                ColumnInfo {
                    name: "trace_s".into(),
                    class: Class::Timing,
                    unit: "s".into(),
                },
            ],
        );
        Meta {
            schema: SCHEMA,
            raycost: Build::current(),
            machine: Machine::current(BTreeMap::new()),
            run: RunInfo {
                command: "run".into(),
                spec_path: "x.toml".into(),
                spec_hash: "ab".repeat(32),
                seed: 1,
                threads: 2,
                shard: "all".into(),
                set: vec![],
                started: "2026-01-01T00:00:00Z".into(),
                finished: None,
                wall_s: None,
                load_start: vec![0.1, 0.2, 0.3],
                load_end: vec![],
                other_cores: None,
                cpu_start: None,
                points_total: 2,
                points: vec![0, 1],
                point_wall_s: vec![0.5, 0.25],
                resumed_points: vec![],
                point_memory: vec![PointMemory {
                    point: 1,
                    batches: 3,
                    model_bytes: 1.5e9,
                    budget_key: "detp.memory_budget_gib".into(),
                    budget_gib: 1.0,
                    peak_rss_bytes: Some(1 << 30),
                }],
            },
            inputs: vec![InputFile {
                path: "scene.toml".into(),
                location: "scene.toml".into(),
                role: "scene".into(),
                sha256: "0".repeat(64),
                bytes: 10,
            }],
            warnings: vec![],
            columns,
            extra: toml::Table::new(),
            spec: toml::Table::new(),
            shards: Vec::new(),
        }
    }

    #[test]
    fn the_codec_round_trips_and_refuses_other_schemas() {
        let m = sample();
        let text = m.render();
        assert_eq!(Meta::parse(&text).expect("round trip"), m);
        let old = text.replace("schema = 2", "schema = 1");
        assert!(Meta::parse(&old)
            .expect_err("schema 1")
            .0
            .contains("schema 1"));
        let none = text.replace("schema = 2\n", "");
        assert!(Meta::parse(&none)
            .expect_err("no schema")
            .0
            .contains("older"));
        assert_eq!(m.reproducible_columns("main"), ["n_s_mean"]);
    }

    #[test]
    fn a_changed_input_is_named() {
        let a = sample().inputs;
        let mut b = a.clone();
        assert_eq!(changed_input(&a, &b), None);
        b[0].sha256 = "1".repeat(64);
        let msg = changed_input(&a, &b).expect("changed");
        assert!(
            msg.starts_with("scene file scene.toml (content changed"),
            "{msg}"
        );
        assert!(changed_input(&a, &[])
            .expect("gone")
            .contains("not by this one"));
        // Another spelling of the same place is the same input; another place is not.
        let mut c = a.clone();
        c[0].path = "/elsewhere/sub/../scene.toml".into();
        assert_eq!(changed_input(&a, &c), None);
        c[0].location = "other/scene.toml".into();
        let msg = changed_input(&a, &c).expect("moved");
        assert!(
            msg.contains("scene file scene.toml (read by the earlier run"),
            "{msg}"
        );
        // A record without a location (an old photon shard) matches by role and content.
        let mut old = a.clone();
        old[0].location.clear();
        assert_eq!(changed_input(&old, &a), None);
        assert_eq!(changed_input(&a, &old), None);
        old[0].sha256 = "2".repeat(64);
        assert!(changed_input(&old, &a).is_some());
    }

    /// Metadata written before locations were recorded (paths spelled from the working folder the
    /// run started in, like the committed `results/*/*.meta.toml`) reads with the location taken
    /// relative to the spec's folder as the same run spelled it.
    #[test]
    fn old_records_get_their_location_from_the_spec_path() {
        let mut m = sample();
        m.run.spec_path = "experiments/cornell-levels.toml".into();
        m.inputs[0].path = "experiments/scenes/cornell.toml".into();
        m.inputs[0].location.clear();
        let text = m.render().replace("location = \"\"\n", "");
        assert!(!text.contains("location"), "{text}");
        let read = Meta::parse(&text).expect("old record");
        assert_eq!(read.inputs[0].location, "scenes/cornell.toml");
        let cases = [
            (
                "/abs/x/a.toml",
                "/abs/x/../scenes/c.toml",
                "../scenes/c.toml",
            ),
            ("a.toml", "c.toml", "c.toml"),
            ("sub/a.toml", "sub/../c.toml", "../c.toml"),
            ("", "results/x/x.csv", "x.csv"),
        ];
        for (spec, path, want) in cases {
            assert_eq!(InputFile::old_location(path, spec), want, "{spec} {path}");
        }
    }

    /// Another process spinning on a core while a run goes is measured (about one core) and makes
    /// the run's metadata carry the busy-machine warning; the run's own CPU is not counted.
    #[test]
    #[cfg(target_os = "linux")]
    fn another_process_spinning_makes_the_run_busy() {
        let (b0, o0) = cpu_ticks().expect("Linux has /proc/stat");
        assert!(b0 >= o0, "the machine's busy ticks include this process's");
        let mut m = Meta::begin("run", BTreeMap::new());
        let mut spinner = std::process::Command::new("sh")
            .args([
                "-c",
                "end=$(( $(date +%s) + 3 )); while [ $(date +%s) -lt $end ]; do :; done",
            ])
            .spawn()
            .expect("sh");
        std::thread::sleep(std::time::Duration::from_millis(1500));
        m.end(1.5);
        spinner.kill().ok();
        spinner.wait().ok();
        let others = m.run.other_cores.expect("measured on Linux");
        assert!(
            others > 0.5,
            "a spinning shell is about one core, got {others}"
        );
        assert!(m.busy());
        assert!(
            m.warnings
                .iter()
                .any(|w| w.contains("the machine was busy")),
            "{:?}",
            m.warnings
        );
        // The figure is written to the metadata; the start sample is not.
        let text = m.render();
        assert!(text.contains("other_cores"), "{text}");
        assert!(!text.contains("cpu_start"), "{text}");
    }
}
