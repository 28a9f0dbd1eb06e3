//! The keys a user writes (spec files and scene files), each declared once: [`spec_table!`] declares
//! a table's struct, and every field's declaration gives at once its serde reading (unknown keys
//! refused, the value range-checked where it is read), its default, and its reference entry (type,
//! unit, allowed values, meaning: a [`KeyDoc`]). The key lists of `raycost doc spec|scene`, the
//! parameter columns of a run and the kinds that accept a key all come from [`SpecTable::keys`]:
//! no list beside the struct, no key recovered from an error message.
//!
//! ```ignore
//! crate::spec_table! {
//!     /// `[lines]`.
//!     pub struct RawLines {
//!         /// Lines drawn per point.
//!         count: u64 = {required} read count, "integer", "lines", "≥ 1";
//!         /// Photons per line.
//!         power: f64 = {default 1.0} read positive, "number", "W", "> 0";
//!         /// A note.
//!         note: Option<String> = {absent "none"}, "string", "", "any text";
//!         /// A sub-table, an optional one, an array of tables.
//!         grid: RawGrid = {table};
//!         histogram: Option<RawHistogram> = {optional_table};
//!         class: Vec<RawClass> = {tables};
//!     }
//! }
//! ```
//!
//! A field is `{required}`, `{default EXPR}` (EXPR is the value when the key is left out; the docs
//! show it as TOML), `{absent "what that means"}` (an `Option`), `{empty "what that means"}` (a
//! list, empty when left out), or a sub-table: `{table}`,
//! `{optional_table}`, `{tables}` (an array of tables, `[[name]]`). `read F` reads the value with
//! `F` (a range-checked reader of [`super::de`] returning the field's type); without it the type's
//! own `Deserialize` reads it. `struct NAME with Default` also gives the table a `Default` (every
//! field must then have a default).
//!
//! How it works (kept simple on purpose): the struct derives `Serialize` (a left-out `Option` or an
//! empty array is not written, [`omit`]); its `Deserialize` reads a private shadow struct in which
//! every field is optional and read by its own reader type (a module named after the field, inside
//! the `deserialize` function), then fills defaults and refuses a missing required key with serde's
//! own "missing field" error, so errors keep their dotted path and their place in the text.

/// One key of a spec or scene file.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyDoc {
    /// Dotted path; `[]` marks an array of tables (`scene.class[].radius`, `surface[].kind`).
    pub key: String,
    /// Value type as a user writes it (`number`, `integer`, `string`, `bool`, `[x, y, z]`, …).
    pub ty: &'static str,
    /// Unit (empty: a pure number or not a quantity).
    pub unit: &'static str,
    /// What happens when the key is left out.
    pub default: IfAbsent,
    /// Allowed values.
    pub range: &'static str,
    /// What it means (the field's doc comment).
    pub doc: String,
}

/// What a left-out key means.
#[derive(Clone, Debug, PartialEq)]
pub enum IfAbsent {
    /// The key must be given.
    Required,
    /// This value (the declared default, as TOML; `None` if it has no TOML form).
    Value(Option<toml::Value>),
    /// No value; the text says what that means.
    Absent(&'static str),
}

impl IfAbsent {
    /// As shown in the reference tables.
    pub fn shown(&self) -> String {
        match self {
            IfAbsent::Required => "required".into(),
            IfAbsent::Value(Some(v)) => format!("`{v}`"),
            IfAbsent::Value(None) => "a default".into(),
            IfAbsent::Absent(t) => t.to_string(),
        }
    }
}

/// A table declared with [`spec_table!`] (or a wrapper of one): its keys.
pub trait SpecTable {
    /// Appends the table's keys, their paths below `prefix`, in declaration order.
    fn keys(prefix: &str, out: &mut Vec<KeyDoc>);
}

impl<T: SpecTable> SpecTable for Option<T> {
    fn keys(prefix: &str, out: &mut Vec<KeyDoc>) {
        T::keys(prefix, out);
    }
}

impl<T: SpecTable> SpecTable for Vec<T> {
    fn keys(prefix: &str, out: &mut Vec<KeyDoc>) {
        T::keys(&format!("{prefix}[]"), out);
    }
}

/// Every key of the table `T`, in declaration order.
pub fn keys_of<T: SpecTable>() -> Vec<KeyDoc> {
    let mut out = Vec::new();
    T::keys("", &mut out);
    out
}

/// `prefix.field` (or `field` at the top).
pub fn join(prefix: &str, field: &str) -> String {
    if prefix.is_empty() {
        field.to_string()
    } else {
        format!("{prefix}.{field}")
    }
}

/// A doc comment's lines as one sentence.
pub fn doc_text(lines: &[&str]) -> String {
    lines
        .iter()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Whether a field is left out when a table is written back (the normalised spec, the parameter
/// columns): an absent `Option` and an empty array; every other value is written.
pub trait Omit {
    /// Leave it out?
    fn omit(&self) -> bool {
        false
    }
}

impl<T> Omit for Option<T> {
    fn omit(&self) -> bool {
        self.is_none()
    }
}

impl<T> Omit for Vec<T> {
    fn omit(&self) -> bool {
        self.is_empty()
    }
}

impl Omit for f64 {}
impl Omit for u64 {}
impl Omit for u32 {}
impl Omit for bool {}
impl Omit for String {}
impl Omit for [f64; 3] {}
impl Omit for toml::Table {}

/// [`Omit::omit`], as serde's `skip_serializing_if` names it.
pub fn omit<T: Omit>(v: &T) -> bool {
    v.omit()
}

/// Declares a table of a spec or scene file (see the module doc).
#[macro_export]
macro_rules! spec_table {
    (
        $(#[$m:meta])*
        pub struct $name:ident $(with $dflt:ident)? {
            $(
                $(#[doc = $doc:literal])*
                $field:ident : $ty:ty = $how:tt $(read $reader:path)? $(, $kty:literal, $unit:literal, $range:expr)?;
            )*
        }
    ) => {
        $(#[$m])*
        #[derive(Clone, Debug, PartialEq, serde::Serialize)]
        pub struct $name {
            $(
                $(#[doc = $doc])*
                #[serde(skip_serializing_if = "crate::toml_text::keys::omit")]
                pub $field: $ty,
            )*
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                $( $crate::spec_table!(@reader $field, $ty $(, $reader)?); )*
                #[derive(serde::Deserialize)]
                #[serde(deny_unknown_fields)]
                struct Shadow {
                    $(
                        #[serde(default)]
                        $field: Option<$crate::toml_text::de::Checked<$field::R>>,
                    )*
                }
                let s = <Shadow as serde::Deserialize>::deserialize(d)?;
                Ok($name {
                    $( $field: $crate::spec_table!(@value s, $field, $how), )*
                })
            }
        }

        impl $crate::toml_text::keys::SpecTable for $name {
            fn keys(prefix: &str, out: &mut Vec<$crate::toml_text::keys::KeyDoc>) {
                $(
                    $crate::spec_table!(
                        @key out, prefix, $field, $ty, $how, [$($doc),*] $(, $kty, $unit, $range)?
                    );
                )*
            }
        }

        impl $crate::toml_text::keys::Omit for $name {}

        $( $crate::spec_table!(@default $name, $dflt); )?
    };

    // The reader of one field: its own reader function, or the type's `Deserialize`.
    (@reader $field:ident, $ty:ty, $reader:path) => {
        #[allow(non_snake_case, unused_imports)]
        mod $field {
            use super::*;
            pub struct R;
            impl $crate::toml_text::de::Reader for R {
                type Value = $ty;
                fn read<'de, D: serde::Deserializer<'de>>(d: D) -> Result<$ty, D::Error> {
                    $reader(d)
                }
            }
        }
    };
    (@reader $field:ident, $ty:ty) => {
        #[allow(non_snake_case, unused_imports)]
        mod $field {
            use super::*;
            pub struct R;
            impl $crate::toml_text::de::Reader for R {
                type Value = $ty;
                fn read<'de, D: serde::Deserializer<'de>>(d: D) -> Result<$ty, D::Error> {
                    <$ty as serde::Deserialize>::deserialize(d)
                }
            }
        }
    };

    // A field's value from the shadow: its default, or serde's own error for a missing key.
    (@value $s:ident, $field:ident, {required}) => {
        match $s.$field {
            Some(v) => v.0,
            None => return Err(serde::de::Error::missing_field(stringify!($field))),
        }
    };
    (@value $s:ident, $field:ident, {table}) => {
        $crate::spec_table!(@value $s, $field, {required})
    };
    (@value $s:ident, $field:ident, {default $e:expr}) => {
        match $s.$field {
            Some(v) => v.0,
            None => $e,
        }
    };
    (@value $s:ident, $field:ident, {absent $t:literal}) => {
        $s.$field.and_then(|v| v.0)
    };
    (@value $s:ident, $field:ident, {optional_table}) => {
        $s.$field.and_then(|v| v.0)
    };
    (@value $s:ident, $field:ident, {tables}) => {
        $s.$field.map_or_else(Vec::new, |v| v.0)
    };
    (@value $s:ident, $field:ident, {empty $t:literal}) => {
        $s.$field.map_or_else(Vec::new, |v| v.0)
    };

    // A field's reference entry: a sub-table's keys below it, or the key itself.
    (@key $out:ident, $prefix:ident, $field:ident, $ty:ty, {table}, [$($doc:literal),*]) => {
        <$ty as $crate::toml_text::keys::SpecTable>::keys(
            &$crate::toml_text::keys::join($prefix, stringify!($field)),
            $out,
        )
    };
    (@key $out:ident, $prefix:ident, $field:ident, $ty:ty, {optional_table}, [$($doc:literal),*]) => {
        $crate::spec_table!(@key $out, $prefix, $field, $ty, {table}, [])
    };
    (@key $out:ident, $prefix:ident, $field:ident, $ty:ty, {tables}, [$($doc:literal),*]) => {
        $crate::spec_table!(@key $out, $prefix, $field, $ty, {table}, [])
    };
    (@key $out:ident, $prefix:ident, $field:ident, $ty:ty, $how:tt, [$($doc:literal),*], $kty:literal, $unit:literal, $range:expr) => {
        $out.push($crate::toml_text::keys::KeyDoc {
            key: $crate::toml_text::keys::join($prefix, stringify!($field)),
            ty: $kty,
            unit: $unit,
            default: $crate::spec_table!(@if_absent $ty, $how),
            range: $range,
            doc: $crate::toml_text::keys::doc_text(&[$($doc),*]),
        })
    };

    (@if_absent $ty:ty, {required}) => {
        $crate::toml_text::keys::IfAbsent::Required
    };
    (@if_absent $ty:ty, {default $e:expr}) => {
        $crate::toml_text::keys::IfAbsent::Value(toml::Value::try_from::<$ty>($e).ok())
    };
    (@if_absent $ty:ty, {absent $t:literal}) => {
        $crate::toml_text::keys::IfAbsent::Absent($t)
    };
    (@if_absent $ty:ty, {empty $t:literal}) => {
        $crate::toml_text::keys::IfAbsent::Absent($t)
    };

    // A table whose every key has a default: its `Default` is the table left empty.
    (@default $name:ident, Default) => {
        impl Default for $name {
            fn default() -> Self {
                <$name as serde::Deserialize>::deserialize(toml::Value::Table(toml::Table::new()))
                    .expect(concat!("every key of ", stringify!($name), " has a default"))
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::toml_text::de::{count, from_text, from_tree, opt_positive, positive};

    crate::spec_table! {
        /// An inner table.
        pub struct Inner with Default {
            /// X, once.
            x: f64 = {default 0.5} read positive, "number", "length", "> 0";
        }
    }

    crate::spec_table! {
        /// A test table.
        pub struct Outer {
            /// A count.
            /// On two lines.
            n: u64 = {required} read count, "integer", "rays", "≥ 1";
            /// A ratio.
            q: f64 = {default 2.0 / 3.0} read positive, "number", "", "> 0";
            /// Maybe.
            r: Option<f64> = {absent "none"} read opt_positive, "number", "", "> 0";
            /// A name.
            name: String = {default "x".to_string()}, "string", "", "any";
            /// A sub-table.
            inner: Inner = {table};
            /// Another.
            more: Option<Inner> = {optional_table};
            /// Many.
            each: Vec<Inner> = {tables};
        }
    }

    /// One declaration gives the key list (paths, docs, defaults as TOML), the serde reading
    /// (defaults filled in, errors with their key and place) and what is written back.
    #[test]
    fn one_declaration_gives_keys_defaults_and_reading() {
        let keys = keys_of::<Outer>();
        let names: Vec<&str> = keys.iter().map(|k| k.key.as_str()).collect();
        assert_eq!(
            names,
            ["n", "q", "r", "name", "inner.x", "more.x", "each[].x"]
        );
        assert_eq!(keys[0].doc, "A count. On two lines.");
        assert_eq!(keys[0].default, IfAbsent::Required);
        assert_eq!(keys[1].default.shown(), "`0.6666666666666666`");
        assert_eq!(keys[2].default.shown(), "none");
        assert_eq!(keys[3].default.shown(), "`\"x\"`");
        assert_eq!((keys[4].ty, keys[4].unit), ("number", "length"));

        let o: Outer = from_text("n = 3\n[inner]\n[[each]]\nx = 2\n").expect("valid");
        assert_eq!((o.n, o.q, o.r, o.name.as_str()), (3, 2.0 / 3.0, None, "x"));
        assert_eq!((o.inner.x, o.more.clone(), o.each.len()), (0.5, None, 1));
        assert_eq!(Inner::default().x, 0.5);
        let back = toml::Value::try_from(&o).expect("serializes");
        assert_eq!(back.get("r"), None, "an absent key stays absent");
        assert_eq!(back.get("more"), None);
        assert_eq!(back.get("q").and_then(|q| q.as_float()), Some(2.0 / 3.0));

        let e = from_text::<Outer>("n = 3\nq = -1\n[inner]\n").expect_err("range");
        assert_eq!((e.key.as_deref(), e.at), (Some("q"), Some((2, 5))));
        let e = from_text::<Outer>("n = 3\n[inner]\nx = 1\ny = 2\n").expect_err("unknown");
        assert_eq!(e.key.as_deref(), Some("inner.y"));
        assert!(
            e.message.starts_with("unknown field `y`, expected `x`"),
            "{e:?}"
        );
        let e = from_text::<Outer>("q = 0.5\n[inner]\n").expect_err("missing");
        assert_eq!(e.message, "missing field `n`");
        let t: toml::Table = "n = 1\ninner = {}\neach = [{ x = 0 }]"
            .parse()
            .expect("toml");
        assert_eq!(from_tree::<Outer>(&t).expect_err("range").key, "each[0].x");
    }
}
