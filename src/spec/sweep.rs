//! Loading a spec and expanding `[sweep]` (and `--set`) into points.
//!
//! Sweeps and overrides are applied to the TOML tree, and every point is deserialized again from the
//! edited tree: a swept or set key that does not exist, or a value of the wrong type or range, is
//! rejected by the same `deny_unknown_fields` and range checks as the file itself.

use std::path::Path;

use sha2::{Digest, Sha256};

use super::config::PointConfig;
use super::raw::RawSpec;
use crate::error::InputError;
use crate::toml_text::{find_key, line_col};

/// Largest number of points one spec may expand into.
pub const MAX_POINTS: usize = 10_000;

/// One sweep point: its index, the values of the swept or set keys, and its validated config.
#[derive(Clone, Debug)]
pub struct Point {
    /// 0-based index in expansion order (the last swept key varies fastest).
    pub index: usize,
    /// `(dotted key, value)` of every swept or set key, in column order.
    pub params: Vec<(String, toml::Value)>,
    /// The point's full spec after expansion.
    pub raw: RawSpec,
    /// What the engines see.
    pub config: PointConfig,
}

/// A loaded, validated spec and its points.
#[derive(Clone, Debug)]
pub struct Spec {
    /// Path as given.
    pub path: String,
    /// The base spec (with `--set` applied and `[sweep]` removed).
    pub base: RawSpec,
    /// Swept keys and their values, in file order.
    pub sweep: Vec<(String, Vec<toml::Value>)>,
    /// Keys overridden by `--set`.
    pub set_keys: Vec<String>,
    /// Every point.
    pub points: Vec<Point>,
    /// SHA-256 of the normalised spec (base + sweep, as TOML): identifies runs that can be merged.
    pub hash: String,
}

impl Spec {
    /// Loads `path`, applies `--set KEY=VALUE` overrides, validates and expands it.
    pub fn load(path: &Path, sets: &[String]) -> Result<Spec, InputError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| InputError {
            file: name.clone(),
            at: None,
            key: None,
            message: format!("cannot read the spec: {e}"),
        })?;
        Self::from_text(&name, &text, sets)
    }

    /// As [`Spec::load`], from text already read (`name` is used in messages).
    pub fn from_text(name: &str, text: &str, sets: &[String]) -> Result<Spec, InputError> {
        let at =
            |location: Option<(usize, usize)>, key: Option<String>, message: String| InputError {
                file: name.to_string(),
                at: location,
                key,
                message,
            };
        // Level 1: the file as written, with line/column for every bad value.
        let de = toml::Deserializer::new(text);
        let parsed: Result<RawSpec, _> = serde_path_to_error::deserialize(de);
        if let Err(e) = parsed {
            let path = e.path().to_string();
            let inner = e.into_inner();
            let loc = inner.span().map(|s| line_col(text, s.start));
            let key = if path.is_empty() || path == "." {
                None
            } else {
                Some(path)
            };
            return Err(at(loc, key, inner.message().trim().to_string()));
        }
        let mut tree: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            at(
                e.span().map(|s| line_col(text, s.start)),
                None,
                e.message().to_string(),
            )
        })?;

        // The sweep table, flattened to dotted keys.
        let mut sweep = Vec::new();
        if let Some(toml::Value::Table(t)) = tree.remove("sweep") {
            flatten("", &t, &mut sweep);
        }
        for (key, value) in &sweep {
            let values = match value {
                toml::Value::Array(v) if !v.is_empty() => v,
                _ => {
                    return Err(at(
                        find_key(text, key),
                        Some(format!("sweep.{key}")),
                        "expected a non-empty array of values to sweep".into(),
                    ))
                }
            };
            let _ = values;
            if key.starts_with("experiment.") || key == "sweep" {
                return Err(at(
                    find_key(text, key),
                    Some(format!("sweep.{key}")),
                    "only scene, grid, histogram, scaling and detp keys can be swept".into(),
                ));
            }
            if key == "detp.engines" {
                return Err(at(
                    find_key(text, key),
                    Some(format!("sweep.{key}")),
                    "cannot be swept: the engines decide the table's columns, which must be the same for every point".into(),
                ));
            }
        }
        let mut sweep: Vec<(String, Vec<toml::Value>)> = sweep
            .into_iter()
            .map(|(k, v)| (k, v.as_array().cloned().unwrap_or_default()))
            .collect();

        // --set overrides: a set key is no longer swept.
        let mut set_keys = Vec::new();
        let mut set_flags = Vec::new();
        for s in sets {
            let flag = || format!("--set {s}");
            let (key, value) = s.split_once('=').ok_or_else(|| InputError {
                file: flag(),
                at: None,
                key: None,
                message: "expected KEY=VALUE".into(),
            })?;
            let key = key.trim().to_string();
            let value = parse_value(value.trim()).map_err(|m| InputError {
                file: flag(),
                at: None,
                key: Some(key.clone()),
                message: m,
            })?;
            set_path(&mut tree, &key, value).map_err(|m| InputError {
                file: flag(),
                at: None,
                key: Some(key.clone()),
                message: m,
            })?;
            sweep.retain(|(k, _)| *k != key);
            set_flags.push(flag());
            set_keys.push(key);
        }

        let n_points: usize = sweep
            .iter()
            .map(|(_, v)| v.len())
            .try_fold(1usize, |acc, n| acc.checked_mul(n))
            .unwrap_or(usize::MAX);
        if n_points > MAX_POINTS {
            return Err(at(
                find_key(text, "sweep").or(Some((1, 1))),
                Some("sweep".into()),
                format!("expands into {n_points} points (at most {MAX_POINTS})"),
            ));
        }

        let base: RawSpec = deserialize_tree(&tree).map_err(|(k, m)| {
            let from_set = set_keys
                .iter()
                .position(|s| k.starts_with(s.as_str()) || s.starts_with(&k));
            match from_set {
                Some(i) => InputError {
                    file: set_flags[i].clone(),
                    at: None,
                    key: Some(k),
                    message: m,
                },
                None => at(find_key(text, &k), Some(k), m),
            }
        })?;

        let mut points = Vec::with_capacity(n_points);
        for index in 0..n_points {
            let mut t = tree.clone();
            let mut params = Vec::new();
            let mut rest = index;
            let mut chosen = vec![0usize; sweep.len()];
            for (i, (_, values)) in sweep.iter().enumerate().rev() {
                chosen[i] = rest % values.len();
                rest /= values.len();
            }
            for (i, (key, values)) in sweep.iter().enumerate() {
                let v = values[chosen[i]].clone();
                set_path(&mut t, key, v.clone())
                    .map_err(|m| at(find_key(text, key), Some(format!("sweep.{key}")), m))?;
                params.push((key.clone(), v));
            }
            for k in &set_keys {
                params.push((
                    k.clone(),
                    get_path(&t, k).expect("a set key exists in the tree"),
                ));
            }
            let raw: RawSpec = deserialize_tree(&t).map_err(|(k, m)| {
                let swept = sweep
                    .iter()
                    .find(|(s, _)| k.starts_with(s.as_str()) || s.starts_with(&k))
                    .map(|(s, _)| s.clone());
                match swept {
                    Some(s) => at(
                        find_key(text, &s),
                        Some(format!("sweep.{s}")),
                        format!("{k}: {m} (at sweep point {index})"),
                    ),
                    None => at(find_key(text, &k), Some(k), m),
                }
            })?;
            let base_dir = Path::new(name).parent().unwrap_or(Path::new(""));
            let config = PointConfig::from_raw(&raw, base_dir).map_err(|(k, m)| {
                let swept = sweep.iter().find(|(s, _)| *s == k).map(|(s, _)| s.clone());
                if let Some(i) = set_keys.iter().position(|s| *s == k) {
                    return InputError {
                        file: set_flags[i].clone(),
                        at: None,
                        key: Some(k.clone()),
                        message: m.clone(),
                    };
                }
                let suffix = if n_points > 1 {
                    format!(" (at sweep point {index}: {})", describe(&params))
                } else {
                    String::new()
                };
                match swept {
                    Some(s) => at(find_key(text, &s), Some(k), format!("{m}{suffix}")),
                    None => at(find_key(text, &k), Some(k), format!("{m}{suffix}")),
                }
            })?;
            points.push(Point {
                index,
                params,
                raw,
                config,
            });
        }

        let mut normal = toml::Table::new();
        normal.insert(
            "base".into(),
            toml::Value::try_from(&base).expect("a RawSpec serializes"),
        );
        let mut sw = toml::Table::new();
        for (k, v) in &sweep {
            sw.insert(k.clone(), toml::Value::Array(v.clone()));
        }
        normal.insert("sweep".into(), toml::Value::Table(sw));
        let hash = format!(
            "{:x}",
            Sha256::digest(toml::to_string(&normal).expect("serializable").as_bytes())
        );
        Ok(Spec {
            path: name.to_string(),
            base,
            sweep,
            set_keys,
            points,
            hash,
        })
    }
}

fn describe(params: &[(String, toml::Value)]) -> String {
    params
        .iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect::<Vec<_>>()
        .join(", ")
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

/// Reads a `--set` value with TOML value syntax; a bare word is taken as a string.
fn parse_value(s: &str) -> Result<toml::Value, String> {
    let doc = format!("v = {s}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => Ok(t.remove("v").expect("the key v was written")),
        Err(_)
            if !s.is_empty()
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_".contains(c)) =>
        {
            Ok(toml::Value::String(s.into()))
        }
        Err(e) => Err(format!("not a TOML value: {}", e.message())),
    }
}

/// Sets a dotted key (array elements by index, `scene.class.0.fraction`), creating tables as needed.
fn set_path(tree: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err("empty segment in the dotted key".into());
    }
    let mut cur = tree;
    for (i, p) in parts.iter().enumerate() {
        let last = i + 1 == parts.len();
        if last {
            cur.insert((*p).to_string(), value);
            return Ok(());
        }
        let next = cur
            .entry((*p).to_string())
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
                let rest = parts[i + 2..].join(".");
                return match el {
                    toml::Value::Table(t) if !rest.is_empty() => set_path(t, &rest, value),
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

fn deserialize_tree(t: &toml::Table) -> Result<RawSpec, (String, String)> {
    let v = toml::Value::Table(t.clone());
    serde_path_to_error::deserialize(v).map_err(|e| {
        let p = e.path().to_string();
        (p, e.into_inner().message().trim().to_string())
    })
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

    #[test]
    fn sweep_expands_as_a_cartesian_product_last_key_fastest() {
        let s = Spec::from_text("t.toml", BASE, &[]).expect("valid");
        assert_eq!(s.points.len(), 6);
        assert_eq!(s.points[1].params[0].1.as_float(), Some(0.25));
        assert_eq!(s.points[1].params[1].1.as_float(), Some(2.0));
        assert_eq!(s.points[5].config.grid().unwrap().cell_width, 1.0);
    }

    #[test]
    fn set_overrides_and_unsweeps() {
        let s = Spec::from_text("t.toml", BASE, &["grid.cell_width=0.7".into()]).expect("valid");
        assert_eq!(s.points.len(), 2);
        assert!(s
            .points
            .iter()
            .all(|p| p.config.grid().unwrap().cell_width == 0.7));
        assert_eq!(
            s.points[0].params.last().map(|p| p.0.as_str()),
            Some("grid.cell_width")
        );
    }

    #[test]
    fn unknown_sweep_key_is_an_error_naming_it() {
        let bad = BASE.replace("\"scene.intensity\"", "\"scene.intensty\"");
        let e = Spec::from_text("t.toml", &bad, &[]).expect_err("unknown key");
        assert!(e.to_string().contains("scene.intensty"), "{e}");
        assert!(e.at.is_some());
    }

    #[test]
    fn bad_set_names_the_flag() {
        let e = Spec::from_text("t.toml", BASE, &["grid.cel_width=1".into()]).expect_err("unknown");
        assert!(e.to_string().starts_with("--set grid.cel_width=1"), "{e}");
        let e = Spec::from_text("t.toml", BASE, &["scene.radius=-1".into()]).expect_err("negative");
        assert!(e.to_string().contains("scene.radius"), "{e}");
    }

    #[test]
    fn hash_is_stable_and_sensitive() {
        let a = Spec::from_text("t.toml", BASE, &[]).expect("valid").hash;
        let b = Spec::from_text("other.toml", BASE, &[])
            .expect("valid")
            .hash;
        let c = Spec::from_text("t.toml", &BASE.replace("rays = 1000", "rays = 1001"), &[])
            .expect("valid")
            .hash;
        assert_eq!(a, b);
        assert_ne!(a, c);
    }
}
