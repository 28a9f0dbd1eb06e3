//! Reading a spec file and expanding `[sweep]` and `--set` into points, on the TOML tree.
//!
//! Every point is the file's tree with its swept values (and the `--set` values) written in; the
//! experiment kind then deserializes each point with the same `deny_unknown_fields` and range checks
//! as the file itself, so a swept or set key that does not exist, or a value of the wrong type or
//! range, is refused like one written in the file. Errors found on a point are located here
//! ([`Spec::locate`]): at the `[sweep]` entry that produced the value (with the point named), at the
//! key's line in the file, or at the `--set` flag that set it.
//!
//! `--set KEY=VALUE` reads KEY with TOML's own key grammar and VALUE as a TOML value (a bare word is a
//! string). A key under `sweep` sets a whole sweep axis: `--set 'sweep."grid.cell_width"=[0.3, 0.6]'`
//! replaces that axis, or adds it as the last (fastest-varying) axis if the file does not sweep it;
//! any other key sets that value for every point and stops it being swept.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::InputError;
use crate::toml_text::de::{from_tree, opt_count, seed, KeyError};
use crate::toml_text::document::Document;
use crate::toml_text::find_key;

/// Largest number of points one spec may expand into.
pub const MAX_POINTS: usize = 10_000;

crate::spec_table! {
    /// `[experiment]`: what every spec names, whatever its kind.
    pub struct RawExperiment {
        /// Names the results: `DIR/NAME/NAME.csv`, `NAME.meta.toml`, `NAME.TABLE.csv`.
        name: String = {required} read name, "string", "", "1–100 letters, digits, `-`, `_`";
        /// What the experiment measures; decides which tables below the spec may have.
        kind: String = {required}, "string", "", "a kind of `raycost doc kinds`";
        /// Master seed of every random stream: the same spec and seed give the same measured
        /// columns on any machine, thread count or shard split.
        seed: u64 = {default 1} read seed, "integer", "", "0 … 2⁶³ − 1 (TOML's largest integer)";
        /// Which separate run of the spec this is (`raycost run --run R` or `--repeat K` set it):
        /// mixed into the seed, so runs are independent samples (run 0 keeps the seed as given).
        run: u64 = {default 0}, "integer", "", "0 … 2⁶³ − 1 (TOML's largest integer)";
        /// Common random numbers: every sweep point draws the same lines, photons, points and
        /// scenes (random streams keyed by the seed, run and replica, not by the sweep point), so
        /// points that differ only in an engine, a list mode or Q are compared on the same samples.
        /// The quasi-static kind shares its streams across points either way.
        common_random_numbers: bool = {default false}, "bool", "", "`true`, `false`";
        /// Rays traced per sweep point (DETP kinds count their rays in `detp.photons`, lines in
        /// `lines.count`).
        rays: Option<u64> = {absent "required by the grid kinds, unused by others"}
            read opt_count, "integer", "rays", "≥ 1 (grid: ≤ 10¹⁰)";
        /// Free text copied into `NAME.meta.toml`.
        description: Option<String> = {absent "none"}, "string", "", "any text";
    }
}

/// A value as a message shows it: floats in their shortest form, in scientific notation when very
/// large or small (`1e-200`, not 200 zeros), everything else as TOML writes it.
pub fn show(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(x) => format!("{x:?}"),
        toml::Value::Array(a) => format!("[{}]", a.iter().map(show).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
}

/// Declares the spec file of a kind: `[experiment]` ([`RawExperiment`]), the kind's own tables as
/// given, and `[sweep]` (declared here, once for every kind), with [`crate::spec_table!`]'s
/// field syntax.
#[macro_export]
macro_rules! spec_file {
    (
        $(#[$m:meta])*
        pub struct $name:ident { $($fields:tt)* }
    ) => {
        $crate::spec_table! {
            $(#[$m])*
            pub struct $name {
                /// `[experiment]`.
                experiment: $crate::spec::RawExperiment = {table};
                $($fields)*
                /// The sweep: every combination of the arrays is one point (the first key varies
                /// slowest, the last fastest; at most 10 000 points). Each swept key becomes a
                /// column; `--set` on a swept key stops it being swept.
                sweep: Option<toml::Table> = {absent "one point"}, "table", "",
                    "dotted spec key = array of values";
            }
        }
    };
}

impl RawExperiment {
    /// The seed every random stream of this run is keyed by: `experiment.seed` for run 0, the seed
    /// and the run index hashed together for the others (so runs are independent samples).
    pub fn stream_seed(&self) -> u64 {
        if self.run == 0 {
            self.seed
        } else {
            crate::sample::rng::hash_key(&[crate::sample::rng::domain::RUN, self.seed, self.run])
        }
    }

    /// The sweep point's part of every random stream's key: its index, or 0 for every point under
    /// common random numbers.
    pub fn stream_point(&self, index: usize) -> u64 {
        if self.common_random_numbers {
            0
        } else {
            index as u64
        }
    }
}

fn name<'de, D: serde::Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    use serde::de::Error as _;
    let s = String::deserialize(d)?;
    if !s.is_empty()
        && s.len() <= 100
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        Ok(s)
    } else {
        Err(D::Error::custom(format!(
            "got {s:?}, expected 1–100 letters, digits, '-' or '_' (it names files)"
        )))
    }
}

/// The header every spec has; the rest of the file is the kind's.
#[derive(Deserialize)]
struct Header {
    experiment: RawExperiment,
}

/// One sweep point: its index, the values of its swept or set keys, and its tree.
#[derive(Clone, Debug, PartialEq)]
pub struct PointSpec {
    /// 0-based index in expansion order (the last swept key varies fastest).
    pub index: usize,
    /// `(dotted key, value)` of every swept or set key, in column order.
    pub params: Vec<(String, toml::Value)>,
    /// The point's spec tree (the file's, with `--set` and its swept values written in).
    pub tree: toml::Table,
}

/// A `--set` flag as given, and the key it sets.
#[derive(Clone, Debug, PartialEq)]
pub struct SetFlag {
    /// `--set KEY=VALUE` as given.
    pub flag: String,
    /// The dotted key (`grid.cell_width`, or `sweep.grid.cell_width` for an axis).
    pub key: String,
}

/// A spec file read and expanded into points (not yet validated by its kind).
#[derive(Clone, Debug)]
pub struct Spec {
    /// The path as given (names the file in errors and metadata).
    pub path: String,
    /// Its folder: paths in the spec are relative to it.
    pub dir: PathBuf,
    /// Its text.
    pub text: String,
    /// Where each key and value of the text sits (its one parse).
    pub doc: Document,
    /// `[experiment]`, after `--set`.
    pub experiment: RawExperiment,
    /// The file's tree with `--set` applied and `[sweep]` removed.
    pub tree: toml::Table,
    /// Sweep axes, in file order (axes added by `--set` last): dotted key → values.
    pub sweep: Vec<(String, Vec<toml::Value>)>,
    /// The `--set` flags.
    pub sets: Vec<SetFlag>,
    /// Every point.
    pub points: Vec<PointSpec>,
}

impl Spec {
    /// Reads `path` and expands it with the `--set KEY=VALUE` overrides `sets`.
    pub fn read(path: &Path, sets: &[String]) -> Result<Spec, InputError> {
        let name = path.display().to_string();
        if path.is_dir() {
            return Err(InputError::new(
                name,
                "is a directory; give the spec file (a .toml)",
            ));
        }
        let text = std::fs::read_to_string(path)
            .map_err(|e| InputError::new(&name, format!("cannot read the spec: {e}")))?;
        Self::parse(&name, &text, sets)
    }

    /// As [`Spec::read`], from text already read (`name` is the path in messages; its folder anchors
    /// relative paths).
    pub fn parse(name: &str, text: &str, sets: &[String]) -> Result<Spec, InputError> {
        let file_err =
            |at: Option<(usize, usize)>, key: Option<String>, message: String| InputError {
                file: name.to_string(),
                at,
                key,
                message,
            };
        // The one parse of the text: its tree, and where every key and value sits.
        let doc = Document::parse(text).map_err(|e| file_err(e.at, e.key, e.message))?;
        let mut tree = doc.tree.clone();
        // The header as written, before any --set.
        from_tree::<Header>(&tree).map_err(|e| {
            file_err(
                doc.place(text, &e.key, &e.message),
                (!e.key.is_empty()).then(|| e.key.clone()),
                e.message,
            )
        })?;

        // The sweep axes, flattened to dotted keys.
        let mut flat = Vec::new();
        match tree.remove("sweep") {
            Some(toml::Value::Table(t)) => flatten("", &t, &mut flat),
            Some(_) => {
                return Err(file_err(
                    find_key(text, "sweep"),
                    Some("sweep".into()),
                    "expected a table of dotted keys, each with a list of values".into(),
                ))
            }
            None => {}
        }
        let mut sweep = Vec::new();
        for (key, value) in flat {
            check_axis(&key, &value)
                .map_err(|m| file_err(find_key(text, &key), Some(format!("sweep.{key}")), m))?;
            sweep.push((key, value.as_array().cloned().unwrap_or_default()));
        }

        // --set overrides: an axis under `sweep`, or a value (which is then no longer swept).
        let flags = apply_sets(sets, &mut tree, &mut sweep)?;

        // The header again, after --set (experiment.seed or .kind may have been set).
        let header: Header = from_tree(&tree).map_err(|e| locate_key(name, text, &flags, e))?;

        let n_points: usize = sweep
            .iter()
            .map(|(_, v)| v.len())
            .try_fold(1usize, |acc, n| acc.checked_mul(n))
            .unwrap_or(usize::MAX);
        if n_points > MAX_POINTS {
            return Err(file_err(
                find_key(text, "sweep").or(Some((1, 1))),
                Some("sweep".into()),
                format!("expands into {n_points} points (at most {MAX_POINTS})"),
            ));
        }
        let mut spec = Spec {
            path: name.to_string(),
            dir: Path::new(name)
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_default(),
            text: text.to_string(),
            doc,
            experiment: header.experiment,
            tree,
            sweep,
            sets: flags,
            points: Vec::with_capacity(n_points),
        };
        for index in 0..n_points {
            let point = spec.expand(index)?;
            spec.points.push(point);
        }
        Ok(spec)
    }

    /// Point `index`: the tree with its swept values written in.
    fn expand(&self, index: usize) -> Result<PointSpec, InputError> {
        let mut t = self.tree.clone();
        let mut params = Vec::new();
        let mut rest = index;
        let mut chosen = vec![0usize; self.sweep.len()];
        for (i, (_, values)) in self.sweep.iter().enumerate().rev() {
            chosen[i] = rest % values.len();
            rest /= values.len();
        }
        for (i, (key, values)) in self.sweep.iter().enumerate() {
            let v = values[chosen[i]].clone();
            let path: Vec<String> = key.split('.').map(str::to_string).collect();
            set_path(&mut t, &path, v.clone()).map_err(|m| self.locate_axis(key, m))?;
            params.push((key.clone(), v));
        }
        for f in self.sets.iter().filter(|f| !f.key.starts_with("sweep.")) {
            if let Some(v) = get_path(&t, &f.key) {
                params.push((f.key.clone(), v));
            }
        }
        Ok(PointSpec {
            index,
            params,
            tree: t,
        })
    }

    /// Locates a problem with key `e.key` found while validating point `point` (or the base tree,
    /// `None`): at the `--set` flag that set it, at the `[sweep]` entry that produced it (naming the
    /// point), or at the key in the file.
    pub fn locate(&self, point: Option<usize>, e: KeyError) -> InputError {
        self.locate_as(point, e, false)
    }

    /// As [`Spec::locate`], for an error found reading the tree with a kind's serde struct: in the
    /// file it is placed as serde reading the text would place it (a bad value at the value, an
    /// unknown key at the key, a missing key at its table), not at the key's line.
    pub fn locate_read(&self, point: Option<usize>, e: KeyError) -> InputError {
        self.locate_as(point, e, true)
    }

    fn locate_as(&self, point: Option<usize>, e: KeyError, read: bool) -> InputError {
        let KeyError { key, message } = e;
        let related = |s: &str| {
            key == s || key.starts_with(&format!("{s}.")) || s.starts_with(&format!("{key}."))
        };
        if let Some(f) = self.sets.iter().find(|f| related(&f.key)) {
            return InputError::new(&f.flag, message).key(key);
        }
        let point = point.and_then(|i| self.points.get(i));
        let axis = self
            .sweep
            .iter()
            .map(|(k, _)| k)
            .find(|k| related(k))
            .filter(|_| point.is_some());
        let suffix = match point {
            Some(p) if self.points.len() > 1 => format!(
                " (at sweep point {}: {})",
                p.index,
                p.params
                    .iter()
                    .map(|(k, v)| format!("{k} = {}", show(v)))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            _ => String::new(),
        };
        match axis {
            // The value came from a sweep axis: blame the axis, and say which key it set.
            Some(a) => InputError {
                file: self.path.clone(),
                at: find_key(&self.text, a),
                key: Some(format!("sweep.{a}")),
                message: format!("{key}: {message}{suffix}"),
            },
            None => InputError {
                file: self.path.clone(),
                at: if read {
                    self.doc.place(&self.text, &key, &message)
                } else {
                    find_key(&self.text, &key).filter(|_| !key.is_empty())
                },
                key: (!key.is_empty()).then_some(key),
                message: format!("{message}{suffix}"),
            },
        }
    }

    /// Locates a problem with the sweep axis `axis` (its `[sweep]` entry, or the flag that set it).
    pub fn locate_axis(&self, axis: &str, message: String) -> InputError {
        let flag_key = format!("sweep.{axis}");
        if let Some(f) = self.sets.iter().find(|f| f.key == flag_key) {
            return InputError::new(&f.flag, message).key(flag_key);
        }
        InputError {
            file: self.path.clone(),
            at: find_key(&self.text, axis),
            key: Some(flag_key),
            message,
        }
    }

    /// A path named in the spec, resolved against the spec's folder.
    pub fn resolve(&self, relative: &str) -> PathBuf {
        self.dir.join(relative)
    }
}

/// Applies the `--set` flags to the tree and the sweep axes: a key under `sweep` replaces (or adds)
/// that axis, any other key sets the value and stops it being swept; a key set both ways is refused.
fn apply_sets(
    sets: &[String],
    tree: &mut toml::Table,
    sweep: &mut Vec<(String, Vec<toml::Value>)>,
) -> Result<Vec<SetFlag>, InputError> {
    let mut flags: Vec<SetFlag> = Vec::new();
    for s in sets {
        let flag = format!("--set {s}");
        let flag_err = |key: Option<String>, m: String| InputError {
            file: flag.clone(),
            at: None,
            key,
            message: m,
        };
        let (path, value) = parse_set(s).map_err(|m| flag_err(None, m))?;
        let key = path.join(".");
        if path.first().map(String::as_str) == Some("sweep") {
            let axis = path[1..].join(".");
            if axis.is_empty() {
                return Err(flag_err(
                    Some(key),
                    "name the swept key: sweep.\"grid.cell_width\"=[…]".into(),
                ));
            }
            check_axis(&axis, &value).map_err(|m| flag_err(Some(key.clone()), m))?;
            let values = value.as_array().cloned().unwrap_or_default();
            match sweep.iter_mut().find(|(k, _)| *k == axis) {
                Some(existing) => existing.1 = values,
                None => sweep.push((axis.clone(), values)),
            }
        } else {
            set_path(tree, &path, value).map_err(|m| flag_err(Some(key.clone()), m))?;
            sweep.retain(|(k, _)| *k != key);
        }
        flags.push(SetFlag { flag, key });
    }
    for f in &flags {
        if let Some(axis) = f.key.strip_prefix("sweep.") {
            if let Some(other) = flags.iter().find(|g| g.key == axis) {
                return Err(InputError::new(
                    &f.flag,
                    format!(
                        "{} sets the same key to one value; give one or the other",
                        other.flag
                    ),
                )
                .key(&f.key));
            }
        }
    }
    Ok(flags)
}

/// A `[sweep]` axis must be a non-empty array and may not sweep `[experiment]` (the name and kind
/// decide the result files; the seed has `--set experiment.seed` for replicas).
fn check_axis(key: &str, value: &toml::Value) -> Result<(), String> {
    match value {
        toml::Value::Array(v) if !v.is_empty() => {}
        _ => return Err("expected a non-empty array of values to sweep".into()),
    }
    if key.starts_with("experiment.") || key == "experiment" || key == "sweep" {
        return Err(
            "[experiment] keys cannot be swept (run the spec again with --set experiment.seed=N for another seed)"
                .into(),
        );
    }
    Ok(())
}

/// A problem with key `e.key` of the base tree: at the `--set` flag that set it, else in the file.
fn locate_key(name: &str, text: &str, flags: &[SetFlag], e: KeyError) -> InputError {
    let related = |s: &str| {
        e.key == s || e.key.starts_with(&format!("{s}.")) || s.starts_with(&format!("{}.", e.key))
    };
    if let Some(f) = flags.iter().find(|f| related(&f.key)) {
        return InputError::new(&f.flag, e.message).key(e.key);
    }
    InputError {
        file: name.to_string(),
        at: find_key(text, &e.key),
        key: (!e.key.is_empty()).then_some(e.key),
        message: e.message,
    }
}

fn flatten(prefix: &str, t: &toml::Table, out: &mut Vec<(String, toml::Value)>) {
    for (k, v) in t {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(inner) => flatten(&key, inner, out),
            _ => out.push((key, v.clone())),
        }
    }
}

/// Splits `KEY=VALUE` at the first `=` outside quotes, reads KEY with TOML's key grammar (bare or
/// quoted parts joined by dots) and VALUE as a TOML value (a bare word is taken as a string).
fn parse_set(s: &str) -> Result<(Vec<String>, toml::Value), String> {
    let mut quote: Option<char> = None;
    let mut split = None;
    for (i, c) in s.char_indices() {
        match (quote, c) {
            (None, '"' | '\'') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            (None, '=') => {
                split = Some(i);
                break;
            }
            _ => {}
        }
    }
    let i = split.ok_or("expected KEY=VALUE")?;
    let (key, value) = (s[..i].trim(), s[i + 1..].trim());
    if key.is_empty() {
        return Err("expected KEY=VALUE: the key is empty".into());
    }
    // The key: TOML's grammar, read from `KEY = 0` (whose one leaf is not a table).
    let keyed: toml::Table = format!("{key} = 0")
        .parse()
        .map_err(|e: toml::de::Error| format!("not a TOML key: {}", e.message().trim()))?;
    let mut path = Vec::new();
    let mut cur = toml::Value::Table(keyed);
    while let toml::Value::Table(t) = cur {
        let (k, v) = t
            .into_iter()
            .next()
            .ok_or("expected KEY=VALUE: the key is empty")?;
        path.push(k);
        cur = v;
    }
    // The value: TOML value syntax; a bare word is a string.
    let value = match format!("v = {value}").parse::<toml::Table>() {
        Ok(mut t) => t.remove("v").expect("the key v was written"),
        Err(_)
            if !value.is_empty()
                && value
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_".contains(c)) =>
        {
            toml::Value::String(value.to_string())
        }
        Err(e) => return Err(format!("not a TOML value: {}", e.message().trim())),
    };
    Ok((path, value))
}

/// Sets a dotted key (array elements by index: `scene.class.0.fraction`), creating tables as needed.
fn set_path(tree: &mut toml::Table, parts: &[String], value: toml::Value) -> Result<(), String> {
    if parts.is_empty() || parts.iter().any(String::is_empty) {
        return Err("empty segment in the dotted key".into());
    }
    let mut cur = tree;
    for (i, p) in parts.iter().enumerate() {
        if i + 1 == parts.len() {
            cur.insert(p.clone(), value);
            return Ok(());
        }
        let next = cur
            .entry(p.clone())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match next {
            toml::Value::Table(t) => t,
            toml::Value::Array(a) => {
                let idx: usize = parts[i + 1].parse().map_err(|_| {
                    format!(
                        "'{}' is an array: index it with a number",
                        parts[..=i].join(".")
                    )
                })?;
                let len = a.len();
                let el = a.get_mut(idx).ok_or_else(|| {
                    format!(
                        "'{}' has {len} elements, no index {idx}",
                        parts[..=i].join(".")
                    )
                })?;
                let rest = &parts[i + 2..];
                return match el {
                    toml::Value::Table(t) if !rest.is_empty() => set_path(t, rest, value),
                    _ if rest.is_empty() => {
                        *el = value;
                        Ok(())
                    }
                    _ => Err(format!("'{}' is not a table", parts[..=i + 1].join("."))),
                };
            }
            _ => {
                return Err(format!(
                    "'{}' is a value, not a table",
                    parts[..=i].join(".")
                ))
            }
        };
    }
    Ok(())
}

fn get_path(tree: &toml::Table, key: &str) -> Option<toml::Value> {
    let mut v = toml::Value::Table(tree.clone());
    for p in key.split('.') {
        v = match v {
            toml::Value::Table(mut t) => t.remove(p)?,
            toml::Value::Array(a) => a.into_iter().nth(p.parse().ok()?)?,
            _ => return None,
        };
    }
    Some(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
[experiment]
name = "t"
kind = "grid"
rays = 1000

[scene]
intensity = 1.0
radius = 0.1

[grid]
cell_width = 0.5

[sweep]
"grid.cell_width" = [0.25, 0.5, 1.0]
"scene.intensity" = [1.0, 2.0]
"#;

    fn sets(s: &[&str]) -> Vec<String> {
        s.iter().map(|x| x.to_string()).collect()
    }

    #[test]
    fn sweep_expands_as_a_cartesian_product_last_key_fastest() {
        let s = Spec::parse("t.toml", BASE, &[]).expect("valid");
        assert_eq!(s.points.len(), 6);
        assert_eq!(s.points[1].params[0].1.as_float(), Some(0.25));
        assert_eq!(s.points[1].params[1].1.as_float(), Some(2.0));
        assert_eq!(
            get_path(&s.points[5].tree, "grid.cell_width").and_then(|v| v.as_float()),
            Some(1.0)
        );
    }

    #[test]
    fn set_overrides_and_unsweeps() {
        let s = Spec::parse("t.toml", BASE, &sets(&["grid.cell_width=0.7"])).expect("valid");
        assert_eq!(s.points.len(), 2);
        assert!(s
            .points
            .iter()
            .all(|p| get_path(&p.tree, "grid.cell_width").and_then(|v| v.as_float()) == Some(0.7)));
        assert_eq!(
            s.points[0].params.last().map(|p| p.0.as_str()),
            Some("grid.cell_width")
        );
    }

    /// A past defect: `--set 'sweep."grid.cell_width"=[0.3, 0.6]'` was accepted and ignored (the spec's
    /// own four widths ran, plus a constant column named after the flag).
    #[test]
    fn set_on_a_sweep_axis_replaces_or_adds_it() {
        for flag in [
            "sweep.\"grid.cell_width\"=[0.3, 0.6]",
            "sweep.grid.cell_width=[0.3, 0.6]",
        ] {
            let s = Spec::parse("t.toml", BASE, &sets(&[flag])).expect("valid");
            assert_eq!(s.points.len(), 4, "{flag}");
            let widths: Vec<f64> = s
                .points
                .iter()
                .map(|p| p.params[0].1.as_float().expect("a width"))
                .collect();
            assert_eq!(widths, [0.3, 0.3, 0.6, 0.6], "{flag}");
            assert!(s
                .points
                .iter()
                .all(|p| p.params.iter().all(|(k, _)| !k.starts_with("sweep"))));
        }
        let s = Spec::parse(
            "t.toml",
            BASE,
            &sets(&["sweep.\"grid.mailbox\"=[true, false]"]),
        )
        .expect("valid");
        assert_eq!(s.points.len(), 12);
        assert_eq!(s.sweep.last().map(|a| a.0.as_str()), Some("grid.mailbox"));
        let e = Spec::parse("t.toml", BASE, &sets(&["sweep.\"grid.cell_width\"=0.3"]))
            .expect_err("not an array");
        assert!(e.to_string().contains("non-empty array"), "{e}");
        let e = Spec::parse(
            "t.toml",
            BASE,
            &sets(&["sweep.\"grid.cell_width\"=[0.3]", "grid.cell_width=0.4"]),
        )
        .expect_err("both");
        assert!(e.to_string().contains("one or the other"), "{e}");
    }

    #[test]
    fn set_keys_and_values_are_read_as_toml() {
        assert_eq!(
            parse_set("detp.order=hilbert").expect("bare word"),
            (
                vec!["detp".to_string(), "order".into()],
                toml::Value::String("hilbert".into())
            )
        );
        assert!(parse_set("a.b").expect_err("no =").contains("KEY=VALUE"));
        assert!(parse_set("a..b=1")
            .expect_err("bad key")
            .contains("TOML key"));
        assert!(parse_set("a.b=[1,")
            .expect_err("bad value")
            .contains("TOML value"));
        assert_eq!(
            parse_set("scene.class.0.fraction=0.5").expect("indexed").0,
            ["scene", "class", "0", "fraction"]
        );
    }

    #[test]
    fn unknown_sweep_key_is_located_at_its_entry() {
        let s = Spec::parse("t.toml", BASE, &[]).expect("valid");
        let e = s.locate(Some(1), KeyError::new("scene.intensity", "bad"));
        assert_eq!(e.at, find_key(BASE, "scene.intensity"));
        assert!(e.message.contains("at sweep point 1"), "{e}");
    }

    #[test]
    fn errors_about_set_keys_name_the_flag() {
        let s = Spec::parse("t.toml", BASE, &sets(&["scene.radius=-1"])).expect("parses");
        let e = s.locate(Some(0), KeyError::new("scene.radius", "negative"));
        assert!(e.to_string().starts_with("--set scene.radius=-1"), "{e}");
    }

    #[test]
    fn experiment_keys_cannot_be_swept() {
        let bad = BASE.replace("\"scene.intensity\"", "\"experiment.seed\"");
        let e = Spec::parse("t.toml", &bad, &[]).expect_err("seed swept");
        assert!(e.to_string().contains("experiment.seed"), "{e}");
    }
}
