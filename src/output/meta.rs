//! `NAME.meta.toml`: provenance of a result table (what ran, where, when, how long).

use serde::Serialize;

/// Provenance of one run.
#[derive(Clone, Debug, Serialize)]
pub struct Meta {
    /// raycost version and build commit.
    pub raycost: Build,
    /// How the run went.
    pub run: RunInfo,
    /// Machine constants of the cost model, if measured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine: Option<MachineInfo>,
    /// Columns allowed to differ between two runs of the same spec and seed.
    pub timing_columns: Vec<String>,
    /// The normalised spec (defaults filled in) and its sweep.
    pub spec: toml::Table,
}

/// Build identity.
#[derive(Clone, Debug, Serialize)]
pub struct Build {
    /// Crate version.
    pub version: String,
    /// Git commit the binary was built from, when known.
    pub git_commit: String,
}

impl Build {
    /// This binary.
    pub fn current() -> Self {
        Self {
            version: env!("CARGO_PKG_VERSION").into(),
            git_commit: option_env!("RAYCOST_GIT_COMMIT")
                .unwrap_or("unknown")
                .into(),
        }
    }
}

/// Run facts.
#[derive(Clone, Debug, Serialize)]
pub struct RunInfo {
    /// Spec path as given.
    pub spec_path: String,
    /// SHA-256 of the normalised spec.
    pub spec_hash: String,
    /// Master seed.
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
    /// `K/N`, or `all`.
    pub shard: String,
    /// `--set` overrides.
    pub set: Vec<String>,
    /// Host name.
    pub host: String,
    /// Start, RFC 3339 UTC.
    pub started: String,
    /// End, RFC 3339 UTC.
    pub finished: String,
    /// Wall seconds of the whole run.
    pub wall_s: f64,
    /// Points of the whole sweep (all shards); `raycost merge` checks coverage against it.
    pub points_total: usize,
    /// Points in this file.
    pub points: Vec<usize>,
    /// Wall seconds of each point, in the order of `points`.
    pub point_wall_s: Vec<f64>,
    /// Points carried over from a resumed partial run (no wall time recorded here).
    pub resumed_points: Vec<usize>,
}

/// Measured T_I, T_S.
#[derive(Clone, Debug, Serialize)]
pub struct MachineInfo {
    /// One ray–sphere test, s.
    pub t_i_s: f64,
    /// One cell step, s.
    pub t_s_s: f64,
}

/// Host name from the kernel (no extra dependency).
pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .or_else(|_| std::env::var("HOSTNAME"))
        .unwrap_or_else(|_| "unknown".into())
}

impl Meta {
    /// TOML text.
    pub fn render(&self) -> String {
        toml::to_string(self).expect("metadata serializes")
    }
}
