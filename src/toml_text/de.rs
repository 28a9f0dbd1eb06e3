//! Reading spec tables with serde, so that every bad value is refused where it is read: range-checked
//! field deserializers (`positive`, `count`, `open_unit`, …) that reject NaN, ±∞ and out-of-range
//! values with "got X, expected Y", the [`choice!`] macro for string enums that lists what is
//! allowed, and two entry points that locate errors: [`from_text`] (with the line and column serde
//! reports) and [`from_tree`] (a dotted key, for values placed by a sweep or `--set`).
//!
//! Kinds declare their tables with these (each kind's spec module), so a kind's spec file is read by
//! one serde struct that denies unknown keys and tables.

use serde::de::DeserializeOwned;
use serde::{de::Error as _, Deserialize, Deserializer};

use super::line_col;

/// A problem with one dotted key, before it is located in a file (the spec layer adds file, line
/// and column, or the `--set` flag it came from).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct KeyError {
    /// The dotted key (`grid.cell_width`, `scene.class[1].radius`), or a table name.
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl KeyError {
    /// An error about `key`.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            message: message.into(),
        }
    }
}

/// A serde error located in the text: dotted key path and 1-based line and column.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextError {
    /// The dotted key, when serde knows it.
    pub key: Option<String>,
    /// Line and column, when the parser knows them.
    pub at: Option<(usize, usize)>,
    /// What is wrong.
    pub message: String,
}

/// Deserializes `T` from TOML text, locating a failure by line, column and key.
pub fn from_text<T: DeserializeOwned>(text: &str) -> Result<T, TextError> {
    let de = toml::Deserializer::new(text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        TextError {
            key: (!path.is_empty() && path != ".").then_some(path),
            at: inner.span().map(|s| line_col(text, s.start)),
            message: inner.message().trim().to_string(),
        }
    })
}

/// Deserializes `T` from a TOML tree (a sweep point, the tree after `--set`), naming the dotted key
/// of a failure.
pub fn from_tree<T: DeserializeOwned>(tree: &toml::Table) -> Result<T, KeyError> {
    let v = toml::Value::Table(tree.clone());
    serde_path_to_error::deserialize(v).map_err(|e| {
        let p = e.path().to_string();
        KeyError::new(p, e.into_inner().message().trim().to_string())
    })
}

/// A reader of one key's value: a range-checked function of this module, or a type's own
/// `Deserialize` (what [`crate::spec_table!`] reads each field with).
pub trait Reader {
    /// What it reads.
    type Value;
    /// Reads the value, refusing it with "got …, expected …".
    fn read<'de, D: Deserializer<'de>>(d: D) -> Result<Self::Value, D::Error>;
}

/// A value read by the reader `R` (a field of a [`crate::spec_table!`] struct's shadow).
pub struct Checked<R: Reader>(pub R::Value);

impl<'de, R: Reader> Deserialize<'de> for Checked<R> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        R::read(d).map(Checked)
    }
}

/// `Ok(x)` when x is finite and > 0, else "got x, expected a finite number > 0".
pub fn check_positive(x: f64) -> Result<f64, crate::error::Invalid> {
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(format!("got {x}, expected a finite number > 0").into())
    }
}

/// A number (integer or float).
pub fn number<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    match toml::Value::deserialize(d)? {
        toml::Value::Float(x) => Ok(x),
        toml::Value::Integer(i) => Ok(i as f64),
        other => Err(D::Error::custom(format!(
            "got {}, expected a number",
            shown(&other)
        ))),
    }
}

/// A finite number > 0.
pub fn positive<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    check_positive(number(d)?).map_err(D::Error::custom)
}

/// An optional finite number > 0.
pub fn opt_positive<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    positive(d).map(Some)
}

/// A fraction in (0, 1].
pub fn fraction<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let x = number(d)?;
    if x.is_finite() && x > 0.0 && x <= 1.0 {
        Ok(x)
    } else {
        Err(D::Error::custom(format!(
            "got {x}, expected a fraction in (0, 1]"
        )))
    }
}

/// A ratio in the open interval (0, 1).
pub fn open_unit<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let x = number(d)?;
    if x.is_finite() && x > 0.0 && x < 1.0 {
        Ok(x)
    } else {
        Err(D::Error::custom(format!(
            "got {x}, expected a ratio in (0, 1)"
        )))
    }
}

/// A whole number ≥ 1 (an integral float such as 1e6 is accepted).
pub fn count<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    match toml::Value::deserialize(d)? {
        toml::Value::Integer(i) if i >= 1 => Ok(i as u64),
        toml::Value::Float(x) if x.is_finite() && x >= 1.0 && x.fract() == 0.0 && x < 9.0e18 => {
            Ok(x as u64)
        }
        toml::Value::String(s) => Err(D::Error::custom(format!(
            "got the string {s:?}, expected a whole number ≥ 1 (without quotes)"
        ))),
        other => Err(D::Error::custom(format!(
            "got {}, expected a whole number ≥ 1",
            shown(&other)
        ))),
    }
}

/// An optional whole number ≥ 1.
pub fn opt_count<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    count(d).map(Some)
}

/// A whole number ≥ 0.
pub fn count_or_zero<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    match toml::Value::deserialize(d)? {
        toml::Value::Integer(i) if i >= 0 => Ok(i as u64),
        other => Err(D::Error::custom(format!(
            "got {}, expected an integer ≥ 0",
            shown(&other)
        ))),
    }
}

/// A seed: an integer 0 … 2⁶³ − 1 (TOML integers stop at 2⁶³ − 1; a larger one is refused where
/// the text is parsed, naming the key).
pub fn seed<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    match toml::Value::deserialize(d)? {
        toml::Value::Integer(i) if i >= 0 => Ok(i as u64),
        other => Err(D::Error::custom(format!(
            "got {}, expected an integer 0 … 2⁶³ − 1 = {}",
            shown(&other),
            i64::MAX
        ))),
    }
}

/// An optional whole number ≥ 0.
pub fn opt_count_or_zero<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    count_or_zero(d).map(Some)
}

/// Three finite numbers `[x, y, z]`.
pub fn opt_finite3<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 3]>, D::Error> {
    let v: Vec<toml::Value> = Vec::deserialize(d)?;
    let xs: Vec<f64> = v
        .iter()
        .filter_map(|x| x.as_float().or_else(|| x.as_integer().map(|i| i as f64)))
        .filter(|x| x.is_finite())
        .collect();
    if xs.len() != 3 || v.len() != 3 {
        return Err(D::Error::custom("expected three finite numbers [x, y, z]"));
    }
    Ok(Some([xs[0], xs[1], xs[2]]))
}

/// A TOML value as a user wrote it, short (for "got …" messages).
pub fn shown(v: &toml::Value) -> String {
    let s = v.to_string();
    if s.chars().count() > 60 {
        format!("{}…", s.chars().take(60).collect::<String>())
    } else {
        s
    }
}

/// A string enum for specs: `choice!(/// doc  Name { A => "a", B => "b" } default A)` declares the
/// enum with `as_str`, `ALL`, serde (the error lists every allowed spelling) and `Default`.
#[macro_export]
macro_rules! choice {
    ($(#[$m:meta])* $name:ident { $($(#[$vm:meta])* $v:ident => $s:literal),+ $(,)? } default $d:ident) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum $name { $($(#[$vm])* #[allow(missing_docs)] $v),+ }
        impl $name {
            /// The spelling in specs and CSV columns.
            pub fn as_str(self) -> &'static str { match self { $($name::$v => $s),+ } }
            /// Every value with its spelling, in declaration order.
            pub const ALL: &'static [(&'static str, $name)] = &[$(($s, $name::$v)),+];
        }
        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                use serde::de::Error as _;
                let s = <String as serde::Deserialize>::deserialize(d)?;
                $name::ALL.iter().find(|(k, _)| *k == s).map(|(_, v)| *v).ok_or_else(|| {
                    let allowed: Vec<String> = $name::ALL.iter().map(|(k, _)| format!("\"{k}\"")).collect();
                    D::Error::custom(format!("got \"{s}\", expected one of {}", allowed.join(", ")))
                })
            }
        }
        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> { s.serialize_str(self.as_str()) }
        }
        impl Default for $name { fn default() -> Self { $name::$d } }
        impl $crate::toml_text::keys::Omit for $name {}
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct T {
        #[serde(deserialize_with = "positive")]
        r: f64,
        #[serde(default, deserialize_with = "opt_count")]
        n: Option<u64>,
    }

    #[test]
    fn text_errors_carry_line_column_and_key() {
        let e = from_text::<T>("r = 1.0\nn = 0\n").expect_err("n = 0");
        assert_eq!(e.key.as_deref(), Some("n"));
        assert_eq!(e.at, Some((2, 5)));
        assert!(e.message.contains("expected a whole number ≥ 1"), "{e:?}");
        let e = from_text::<T>("r = nan\n").expect_err("NaN");
        assert!(e.message.contains("got NaN"), "{e:?}");
    }

    #[test]
    fn tree_errors_name_the_key() {
        let t: toml::Table = "r = -1".parse().expect("toml");
        let e = from_tree::<T>(&t).expect_err("negative");
        assert_eq!(e.key, "r");
        let t: toml::Table = "r = 1\nn = \"5\"".parse().expect("toml");
        let e = from_tree::<T>(&t).expect_err("a string");
        assert!(e.message.contains("without quotes"), "{e:?}");
        let t: toml::Table = "r = 2.5\nn = 3".parse().expect("toml");
        let ok = from_tree::<T>(&t).expect("valid");
        assert_eq!((ok.r, ok.n), (2.5, Some(3)));
    }
}
