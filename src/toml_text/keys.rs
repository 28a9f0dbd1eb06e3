//! Declarations of the keys a user writes (spec files and scene files), kept beside the serde
//! structs that read them, for `raycost doc spec|scene`.
//!
//! They cannot drift silently from the structs: [`fields`] asks serde itself which keys a struct
//! accepts (a probe key is refused with the list of the struct's fields, as `deny_unknown_fields`
//! reports it), and the tests of `experiment::reference` compare that set with the declarations, and
//! check every declared default against what the struct fills in when the key is left out.

/// One key of a spec or scene file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyDoc {
    /// Dotted path; `[]` marks an array of tables (`scene.class[].radius`, `surface[].kind`).
    pub key: &'static str,
    /// Value type as a user writes it (`number`, `integer`, `string`, `bool`, `[x, y, z]`, …).
    pub ty: &'static str,
    /// Unit (empty: a pure number or not a quantity).
    pub unit: &'static str,
    /// What happens when the key is left out.
    pub default: IfAbsent,
    /// Allowed values.
    pub range: &'static str,
    /// What it means.
    pub doc: &'static str,
}

/// A declaration (shorter to read in the tables beside the structs).
pub const fn key(
    key: &'static str,
    ty: &'static str,
    unit: &'static str,
    default: IfAbsent,
    range: &'static str,
    doc: &'static str,
) -> KeyDoc {
    KeyDoc {
        key,
        ty,
        unit,
        default,
        range,
        doc,
    }
}

/// What a left-out key means.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IfAbsent {
    /// The key must be given.
    Required,
    /// This value (TOML syntax; checked against the struct's own default by a test).
    Value(&'static str),
    /// No value; the text says what that means (checked: the key stays absent).
    Absent(&'static str),
}

impl IfAbsent {
    /// As shown in the reference tables.
    pub fn shown(&self) -> String {
        match self {
            IfAbsent::Required => "required".into(),
            IfAbsent::Value(v) => format!("`{v}`"),
            IfAbsent::Absent(t) => t.to_string(),
        }
    }
}

/// The probe key: no struct declares it.
const PROBE: &str = "__raycost_probe__";

/// A tree holding the probe at `path` (segments; `"[]"` after a name wraps it in an array).
fn probe_tree(path: &[String]) -> toml::Table {
    let mut v = toml::Value::Table(toml::Table::from_iter([(
        PROBE.to_string(),
        toml::Value::Integer(0),
    )]));
    for seg in path.iter().rev() {
        let (name, array) = match seg.strip_suffix("[]") {
            Some(n) => (n, true),
            None => (seg.as_str(), false),
        };
        if array {
            v = toml::Value::Array(vec![v]);
        }
        v = toml::Value::Table(toml::Table::from_iter([(name.to_string(), v)]));
    }
    match v {
        toml::Value::Table(t) => t,
        _ => unreachable!("the probe tree is a table"),
    }
}

/// The field names of the struct at `path`, as serde reports them for an unknown key; `None` when
/// the value there is not a struct that denies unknown keys.
fn struct_fields(
    de: &dyn Fn(&toml::Table) -> Result<(), String>,
    path: &[String],
) -> Option<Vec<String>> {
    let msg = de(&probe_tree(path)).err()?;
    let rest = msg.strip_prefix(&format!("unknown field `{PROBE}`"))?;
    Some(
        rest.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect(),
    )
}

/// Every key a struct accepts, as dotted paths (`[]` after an array of tables), found by probing
/// the deserializer `de` (which reads a whole tree, e.g. a kind's spec struct): tables are
/// descended into, other values are keys.
pub fn fields(de: &dyn Fn(&toml::Table) -> Result<(), String>) -> Vec<String> {
    let mut out = Vec::new();
    walk(de, &[], &mut out);
    out
}

fn walk(de: &dyn Fn(&toml::Table) -> Result<(), String>, path: &[String], out: &mut Vec<String>) {
    let Some(names) = struct_fields(de, path) else {
        return;
    };
    for name in names {
        let table = [path, std::slice::from_ref(&name)].concat();
        let array = [path, &[format!("{name}[]")]].concat();
        if struct_fields(de, &table).is_some() {
            walk(de, &table, out);
        } else if struct_fields(de, &array).is_some() {
            walk(de, &array, out);
        } else {
            out.push(table.join("."));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Outer {
        a: Inner,
        b: Option<u32>,
        #[serde(default)]
        c: Vec<Inner>,
        d: Option<toml::Table>,
    }

    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Inner {
        x: f64,
        y: f64,
    }

    /// Tables, arrays of tables and plain values are told apart.
    #[test]
    fn probing_finds_every_field() {
        let de = |t: &toml::Table| {
            crate::toml_text::de::from_tree::<Outer>(t)
                .map(|_| ())
                .map_err(|e| e.message)
        };
        assert_eq!(fields(&de), ["a.x", "a.y", "b", "c[].x", "c[].y", "d"]);
    }
}
