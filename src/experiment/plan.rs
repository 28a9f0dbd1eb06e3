//! A spec validated by its kind: every point configured, the input files loaded and hashed, the
//! memory each point needs checked against the spec's budget and the machine — all before anything
//! is written. `raycost check` prints a plan; `raycost run` runs one.

use std::fmt::Write as _;
use std::path::Path;

use sha2::{Digest, Sha256};

use super::inputs::Inputs;
use super::kind::{ConfigError, DynKind, DynPoint, Kind, PointOf};
use super::photon_batches::{self, Split};
use super::registry;
use crate::error::InputError;
use crate::output::meta::{available_memory, InputFile};
use crate::output::row::Value;
use crate::spec::{KeyError, Spec};
use crate::toml_text::find_key;
use crate::toml_text::keys::KeyDoc;

const GIB: f64 = (1u64 << 30) as f64;

/// A validated spec, ready to run.
pub struct Plan {
    /// The spec as read and expanded.
    pub spec: Spec,
    /// Its kind.
    pub kind: &'static dyn DynKind,
    /// Every point, configured (index = point index).
    pub points: Vec<Box<dyn DynPoint>>,
    /// Every point's parameter columns (see [`parameters`]).
    pub params: Vec<Vec<Param>>,
    /// The unit every point's spec lengths are in (see [`lengths_in_force`]).
    pub lengths: Vec<&'static str>,
    /// Every file the points read, with content hashes.
    pub inputs: Vec<InputFile>,
    /// The normalised spec (`base`: the kind's struct with defaults, `sweep`).
    pub normalized: toml::Table,
    /// SHA-256 of the normalised spec: identifies runs that can be resumed and merged.
    pub hash: String,
    /// Worker threads the points will run on (their memory is checked for that many).
    pub threads: usize,
    /// Every point's photon batches (1: traced whole; see [`super::photon_batches`]).
    pub batches: Vec<u64>,
}

impl std::fmt::Debug for Plan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Plan")
            .field("spec", &self.spec.path)
            .field("kind", &self.kind.name())
            .field("points", &self.points.len())
            .field("hash", &self.hash)
            .finish()
    }
}

impl Plan {
    /// Reads `path` with the `--set` overrides and validates every point, to run on `threads`
    /// worker threads.
    pub fn load(path: &Path, sets: &[String], threads: usize) -> Result<Plan, InputError> {
        Self::from_spec(Spec::read(path, sets)?, threads)
    }

    /// Validates an expanded spec.
    pub fn from_spec(spec: Spec, threads: usize) -> Result<Plan, InputError> {
        let name = spec.experiment.kind.clone();
        let kind = registry::find(&name).ok_or_else(|| InputError {
            file: spec.path.clone(),
            at: find_key(&spec.text, "experiment.kind"),
            key: Some("experiment.kind".into()),
            message: format!(
                "unknown kind \"{name}\", expected one of {}",
                registry::names()
            ),
        })?;
        Self::with_kind(spec, kind, threads)
    }

    /// Validates an expanded spec as kind `kind` (the registry's, or a test's own). The spec was
    /// parsed once ([`Spec`]); here its base tree is read once by the kind's struct, and each
    /// point's tree once more only where a sweep changed it, each reading then configured.
    pub(crate) fn with_kind(
        spec: Spec,
        kind: &'static dyn DynKind,
        threads: usize,
    ) -> Result<Plan, InputError> {
        // The file with --set, by the kind's own struct: unknown keys and tables, wrong types and
        // out-of-range values, located where they are in the text.
        let base = kind
            .read(&spec.tree)
            .map_err(|e| not_this_kinds_table(&spec, kind, spec.locate_read(None, e)))?;
        for (key, why) in kind.fixed() {
            if spec.sweep.iter().any(|(k, _)| k == key) {
                return Err(spec.locate_axis(key, format!("cannot be swept: {why}")));
            }
        }
        let keys = kind.keys();
        let mut inputs = Inputs::new(&spec.dir);
        let mut points = Vec::with_capacity(spec.points.len());
        let mut params = Vec::with_capacity(spec.points.len());
        let mut lengths = Vec::with_capacity(spec.points.len());
        let mut batches = Vec::with_capacity(spec.points.len());
        for p in &spec.points {
            crate::spec::magnitude::check_point(&p.tree)
                .map_err(|k| spec.locate(Some(p.index), k))?;
            // A point nothing was swept into is the base tree: its reading is the base's.
            let own = if p.tree == spec.tree {
                None
            } else {
                let r = kind.read(&p.tree);
                Some(r.map_err(|e| spec.locate_read(Some(p.index), e))?)
            };
            let reading = own.as_ref().unwrap_or(&base);
            let point = kind.configure(reading, &mut inputs).map_err(|e| match e {
                ConfigError::Key(k) => spec.locate(Some(p.index), k),
                ConfigError::Input(i) => i,
            })?;
            batches.push(check_memory(&spec, p.index, kind, point.as_ref(), threads)?);
            params.push(parameters(&keys, &p.params, &reading.normalized));
            lengths.push(lengths_in_force(&reading.normalized));
            points.push(point);
        }
        let mut normalized = toml::Table::new();
        normalized.insert("base".into(), base.normalized);
        let mut sw = toml::Table::new();
        for (k, v) in &spec.sweep {
            sw.insert(k.clone(), toml::Value::Array(v.clone()));
        }
        normalized.insert("sweep".into(), toml::Value::Table(sw));
        let hash = format!(
            "{:x}",
            Sha256::digest(
                toml::to_string(&normalized)
                    .expect("serializable")
                    .as_bytes()
            )
        );
        Ok(Plan {
            spec,
            kind,
            points,
            params,
            lengths,
            inputs: inputs.files(),
            normalized,
            hash,
            threads,
            batches,
        })
    }

    /// Point `index` as kind `K`'s own type (None if the plan is of another kind).
    pub fn point<K: Kind>(&self, index: usize) -> Option<&K::Point> {
        self.points
            .get(index)
            .and_then(|p| p.as_any().downcast_ref::<PointOf<K>>())
            .map(|p| &p.0)
    }

    /// `raycost check`'s text: the kind, the points with their parameters and what each runs, the
    /// input files and the warnings.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "{}: kind {}, {} point(s), spec hash {}\n",
            self.spec.path,
            self.kind.name(),
            self.points.len(),
            &self.hash[..16]
        );
        for (p, point) in self.spec.points.iter().zip(&self.points) {
            let params = p
                .params
                .iter()
                .map(|(k, v)| format!("{k} = {}", crate::spec::sweep::show(v)))
                .collect::<Vec<_>>()
                .join(", ");
            let _ = writeln!(
                s,
                "  point {:>4}: {params}{}{}",
                p.index,
                if params.is_empty() { "" } else { "; " },
                point.describe()
            );
            if let Some(line) = self.memory_line(p.index) {
                let _ = writeln!(s, "      {line}");
            }
            for w in point.warnings() {
                let _ = writeln!(s, "      warning: {w}");
            }
        }
        let works: Vec<_> = self.points.iter().map(|p| p.work()).collect();
        let (lines, warning) = crate::output::work::total(
            &works
                .iter()
                .map(|w| (w.units, w.unit, w.points))
                .collect::<Vec<_>>(),
        );
        let warning = warning.map(|w| format!("warning: {w}"));
        for l in lines.iter().chain(warning.iter()) {
            let _ = writeln!(s, "  {l}");
        }
        for f in &self.inputs {
            let _ = writeln!(
                s,
                "  input {} ({}, sha256 {})",
                f.path,
                f.role,
                &f.sha256[..16]
            );
        }
        s
    }
}

impl Plan {
    /// Point `i`'s memory for `check`: the model's bytes (a batch's, when batched) beside the
    /// budget, and its photon batches (None for a kind without a budget).
    fn memory_line(&self, i: usize) -> Option<String> {
        let m = self.points[i].memory(self.threads);
        let (key, gib) = m.budget?;
        let split = Split::of(&m.needs);
        let b = self.batches[i];
        Some(match m.batching {
            Some(bt) if b > 1 => format!(
                "memory: {} photon batches of about {:.3} GiB each (about {:.3} GiB in one pass), {key} = {gib} GiB",
                b,
                split.per_batch(bt.photons, b) / GIB,
                (split.fixed + split.per_photon) / GIB
            ),
            Some(_) => format!(
                "memory: about {:.3} GiB, 1 photon batch (one pass), {key} = {gib} GiB",
                (split.fixed + split.per_photon) / GIB
            ),
            None => format!(
                "memory: about {:.3} GiB, {key} = {gib} GiB",
                (split.fixed + split.per_photon) / GIB
            ),
        })
    }

    /// `raycost check --json`: what [`Plan::describe`] prints, as data: the kind, every point with
    /// its parameters (values as in the spec), its description, work (units and what they count),
    /// memory needs (bytes, the spec key driving each, the budget) and warnings, and the input files.
    pub fn describe_json(&self) -> serde_json::Value {
        use serde_json::json;
        let points: Vec<serde_json::Value> = self
            .spec
            .points
            .iter()
            .zip(&self.points)
            .map(|(p, point)| {
                let params: serde_json::Map<String, serde_json::Value> = p
                    .params
                    .iter()
                    .map(|(k, v)| {
                        let v = serde_json::to_value(v).unwrap_or(serde_json::Value::Null);
                        (k.clone(), v)
                    })
                    .collect();
                let work = point.work();
                let memory = point.memory(self.threads);
                let needs: Vec<serde_json::Value> = memory
                    .needs
                    .iter()
                    .map(|n| json!({ "what": n.what, "key": n.key, "bytes": n.bytes, "per_photon": n.per_photon }))
                    .collect();
                let b = self.batches[p.index];
                let batch_bytes = memory.batching.map_or(f64::NAN, |bt| {
                    Split::of(&memory.needs).per_batch(bt.photons, b)
                });
                json!({
                    "point": p.index,
                    "params": params,
                    "describe": point.describe(),
                    "work": { "units": work.units, "unit": work.unit, "points": work.points },
                    "memory": {
                        "bytes": memory.needs.iter().map(|n| n.bytes).sum::<f64>(),
                        "needs": needs,
                        "budget": memory.budget.map(|(key, gib)| json!({ "key": key, "gib": gib })),
                        "batches": b,
                        "batch_bytes": if batch_bytes.is_nan() { serde_json::Value::Null } else { json!(batch_bytes) },
                    },
                    "warnings": point.warnings(),
                })
            })
            .collect();
        let inputs: Vec<serde_json::Value> = self
            .inputs
            .iter()
            .map(
                |f| json!({ "path": f.path, "role": f.role, "sha256": f.sha256, "bytes": f.bytes }),
            )
            .collect();
        let works: Vec<_> = self.points.iter().map(|p| p.work()).collect();
        let (total, warning) = crate::output::work::total(
            &works
                .iter()
                .map(|w| (w.units, w.unit, w.points))
                .collect::<Vec<_>>(),
        );
        json!({
            "spec": self.spec.path,
            "kind": self.kind.name(),
            "spec_hash": self.hash,
            "points": points,
            "total_work": { "lines": total, "warning": warning },
            "inputs": inputs,
        })
    }
}

/// A table of another kind: said so, rather than serde's "unknown field".
fn not_this_kinds_table(spec: &Spec, kind: &dyn DynKind, mut e: InputError) -> InputError {
    if let Some(table) = e.key.clone().filter(|k| !k.contains('.')) {
        if e.message.starts_with("unknown field") {
            e.at = find_key(&spec.text, &table).or(e.at);
            e.message = format!(
                "the [{table}] table does not belong to kind {} (its tables: {})",
                kind.name(),
                e.message
                    .split_once("expected one of ")
                    .map_or("see raycost doc", |(_, t)| t)
            );
        }
    }
    e
}

/// A point's parameter value as a CSV cell: integers stay integers.
fn param_value(v: &toml::Value) -> Value {
    match v {
        toml::Value::Float(x) => Value::F(*x),
        toml::Value::Integer(i) if *i >= 0 => Value::U(*i as u64),
        toml::Value::Integer(i) => Value::F(*i as f64),
        toml::Value::String(s) => Value::S(s.clone()),
        other => Value::S(other.to_string()),
    }
}

/// Keys of the spec that are not parameters of a point: names, free text, the sweep itself, and
/// how a point's photons are split in memory (photon batches leave every measured column as a
/// single pass writes it; a swept value is still a column, as every swept key is).
const NOT_PARAMETERS: &[&str] = &[
    "experiment.name",
    "experiment.kind",
    "experiment.description",
    "sweep",
    "detp.photon_batches",
];

/// One parameter column of a point: the spec key, the unit its value is in, and the value.
#[derive(Debug, Clone)]
pub struct Param {
    /// The spec key (the column's name).
    pub key: String,
    /// The unit the value is in: the key's declared unit, a length resolved by
    /// [`unit_in_force`].
    pub unit: &'static str,
    /// The value in force.
    pub value: Value,
}

/// Every parameter of a point, in column order: the swept or `--set` keys first (as `check`
/// lists them), then every other key the kind declares (`keys`), in declaration order, with the
/// value in force (`normalized`: the point's reading, defaults filled in) and the unit that value
/// is in (a length in the unit its table's `length_unit` names); a key without a value (an
/// optional key left out) is missing (NaN). An array of tables (`scene.class`) is one column with
/// its TOML text.
pub fn parameters(
    keys: &[KeyDoc],
    swept: &[(String, toml::Value)],
    normalized: &toml::Value,
) -> Vec<Param> {
    // `scene.class[].radius` → the column `scene.class`.
    let column = |key: &str| -> String {
        match key.split_once('[') {
            Some((head, _)) => head.to_string(),
            None => key.to_string(),
        }
    };
    let unit = |name: &str| -> &'static str {
        let declared = keys.iter().find(|k| k.key == name).map_or("", |k| k.unit);
        unit_in_force(name, declared, normalized)
    };
    let mut out: Vec<Param> = swept
        .iter()
        .map(|(k, v)| Param {
            unit: unit(k),
            key: k.clone(),
            value: param_value(v),
        })
        .collect();
    for key in keys {
        let name = column(&key.key);
        if NOT_PARAMETERS.contains(&name.as_str()) || out.iter().any(|p| p.key == name) {
            continue;
        }
        let value = name
            .split('.')
            .try_fold(normalized, |v, seg| v.get(seg))
            .map_or(Value::F(f64::NAN), param_value);
        out.push(Param {
            unit: if name == key.key { unit(&name) } else { "" },
            key: name,
            value,
        });
    }
    out
}

/// The unit a point's lengths are in: a table with a `length_unit` key (`[detp]`) writes its
/// lengths in that unit, so with `length_unit = "root"` they are in r_s (the radius of the sphere
/// around the scene's bounds), `"r_s"`; otherwise in the scene's own, `"length"`.
pub fn lengths_in_force(normalized: &toml::Value) -> &'static str {
    let root = normalized.as_table().is_some_and(|t| {
        t.values()
            .any(|table| table.get("length_unit").and_then(toml::Value::as_str) == Some("root"))
    });
    if root {
        "r_s"
    } else {
        "length"
    }
}

/// The unit a key declared in `declared` is in at this point: a length (`"length"`) of a table
/// with a `length_unit` key in the unit that key names ([`lengths_in_force`]), every other unit
/// as declared.
fn unit_in_force(key: &str, declared: &'static str, normalized: &toml::Value) -> &'static str {
    let table = key.split_once('.').map_or("", |(t, _)| t);
    let has_unit_key = normalized
        .get(table)
        .and_then(|t| t.get("length_unit"))
        .is_some();
    if declared == "length" && has_unit_key {
        lengths_in_force(normalized)
    } else {
        declared
    }
}

/// Refuses a point whose structures would not fit: over the spec's budget key (unless its photons
/// can be traced in batches that fit: [`super::photon_batches`]), or a batch over the memory this
/// machine has available (the error names the spec key that drives the largest need). Returns
/// the point's photon batches (1: one pass).
fn check_memory(
    spec: &Spec,
    index: usize,
    kind: &dyn DynKind,
    point: &dyn DynPoint,
    threads: usize,
) -> Result<u64, InputError> {
    let m = point.memory(threads);
    let Some(largest) = m.needs.iter().max_by(|a, b| a.bytes.total_cmp(&b.bytes)) else {
        return Ok(1);
    };
    let split = Split::of(&m.needs);
    let total = split.fixed + split.per_photon;
    let listing = m
        .needs
        .iter()
        .map(|n| format!("{} {:.3} GiB", n.what, n.bytes / GIB))
        .collect::<Vec<_>>()
        .join(", ");
    let at = |key: &str, message: String| spec.locate(Some(index), KeyError::new(key, message));
    let refuse = |bytes: f64, limit: String| {
        at(
            largest.key,
            format!(
                "would need about {:.3} GiB ({listing}), over {limit}; reduce {}",
                bytes / GIB,
                largest.key
            ),
        )
    };
    let unsplittable = m.batching.and_then(|_| kind.photon_refusal(point));
    let batches = match (m.budget, &m.batching) {
        (Some((key, gib)), Some(batching)) => photon_batches::batches(
            split,
            batching,
            (key, gib * GIB),
            largest.key,
            unsplittable.clone(),
        )
        .map_err(|r| at(r.key, format!("{} (needs: {listing})", r.message)))?,
        (Some((key, gib)), None) if total.is_nan() || total > gib * GIB => {
            return Err(refuse(total, format!("{key} = {gib} GiB")))
        }
        _ => 1,
    };
    let each = m
        .batching
        .map_or(total, |b| split.per_batch(b.photons, batches));
    if let Some(avail) = available_memory() {
        if each.is_nan() || each > 0.9 * avail as f64 {
            let lower = match (m.budget, &m.batching, &unsplittable) {
                (Some((key, _)), Some(_), None) => {
                    format!(" (or lower {key}: more photon batches, each smaller)")
                }
                _ => String::new(),
            };
            return Err(refuse(
                each,
                format!(
                    "the {:.2} GiB this machine has available{lower}",
                    avail as f64 / GIB
                ),
            ));
        }
    }
    Ok(batches)
}
