//! A TOML text read once: its tree, and where each key and value sits in the text, so that a
//! problem found later on the tree (a serde error of a kind's spec, a value of the wrong range) is
//! located as if serde had read the text itself: a bad value at the value, an unknown key at the
//! key, a missing key at its table. A spec is parsed once; every later reading works on
//! the tree.

use std::collections::HashMap;
use std::ops::Range;

use serde::de::{Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use toml::Spanned;

use super::de::TextError;
use super::line_col;

/// A TOML text's tree and the places of its keys and values.
#[derive(Clone, Debug, Default)]
pub struct Document {
    /// The tree.
    pub tree: toml::Table,
    /// Dotted path (`scene.class[0].radius`, as serde names it) → (key span, value span).
    places: HashMap<String, (Option<Range<usize>>, Range<usize>)>,
}

impl Document {
    /// Parses `text` (a syntax error comes back located by line and column). No key of a spec or
    /// scene takes a date or time, so one is refused here, where it is.
    pub fn parse(text: &str) -> Result<Document, TextError> {
        let root: Spanned<Node> = toml::from_str(text).map_err(|e: toml::de::Error| {
            let at = e.span().map(|s| line_col(text, s.start));
            let message = e.message().trim().to_string();
            match e.span().filter(|_| message.starts_with("number too large")) {
                // Name the key and TOML's range rather than serde's "target type".
                Some(span) => {
                    let (key, number) = key_and_value_at(text, span.start);
                    TextError {
                        key,
                        at,
                        message: format!(
                            "{number} is larger than TOML's largest integer, 2⁶³ − 1 = {}",
                            i64::MAX
                        ),
                    }
                }
                None => TextError {
                    key: None,
                    at,
                    message: if message.contains(DATETIME) {
                        "a date or time is not a value any key takes".to_string()
                    } else {
                        message
                    },
                },
            }
        })?;
        let mut places = HashMap::new();
        places.insert(String::new(), (None, root.span()));
        let tree = match into_value(root, "", &mut places) {
            toml::Value::Table(t) => t,
            _ => toml::Table::new(),
        };
        Ok(Document { tree, places })
    }

    /// Where a problem with `path` sits in `text`: for an unknown key its key, else its value
    /// (or, for a path that is not in the text, the nearest table that is).
    pub fn place(&self, text: &str, path: &str, message: &str) -> Option<(usize, usize)> {
        let unknown =
            message.starts_with("unknown field") || message.starts_with("unknown variant");
        let mut p = path;
        loop {
            if let Some((key, value)) = self.places.get(p) {
                let span = match key {
                    Some(k) if unknown && p == path => k,
                    _ => value,
                };
                return Some(line_col(text, span.start));
            }
            // The parent path: drop the last `.name` or `[i]`.
            let cut = p.rfind(['.', '[']).unwrap_or(0);
            if cut == 0 && p.is_empty() {
                return None;
            }
            p = &p[..cut];
        }
    }
}

/// A TOML value with the spans of its keys and values.
enum Node {
    Table(Vec<(Spanned<String>, Spanned<Node>)>),
    Array(Vec<Spanned<Node>>),
    Leaf(toml::Value),
}

/// The key toml uses for a datetime inside its serde data model (a key that cannot carry a span).
const DATETIME: &str = "$__toml_private_datetime";

/// Converts `node` (at `path`) into a plain value, recording every place below it.
fn into_value(
    node: Spanned<Node>,
    path: &str,
    places: &mut HashMap<String, (Option<Range<usize>>, Range<usize>)>,
) -> toml::Value {
    match node.into_inner() {
        Node::Leaf(v) => v,
        // An element is placed at its array, as toml places a bad element (the keys of a table in
        // an array have places of their own).
        Node::Array(items) => toml::Value::Array(
            items
                .into_iter()
                .enumerate()
                .map(|(i, item)| into_value(item, &format!("{path}[{i}]"), places))
                .collect(),
        ),
        Node::Table(entries) => {
            let mut t = toml::Table::new();
            for (k, v) in entries {
                let p = super::keys::join(path, k.get_ref());
                places.insert(p.clone(), (Some(k.span()), v.span()));
                let value = into_value(v, &p, places);
                t.insert(k.into_inner(), value);
            }
            toml::Value::Table(t)
        }
    }
}

impl<'de> Deserialize<'de> for Node {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Node, D::Error> {
        d.deserialize_any(NodeVisitor)
    }
}

struct NodeVisitor;

impl<'de> Visitor<'de> for NodeVisitor {
    type Value = Node;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a TOML value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Node, E> {
        Ok(Node::Leaf(toml::Value::Boolean(v)))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Node, E> {
        Ok(Node::Leaf(toml::Value::Integer(v)))
    }
    fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Node, E> {
        i64::try_from(v)
            .map(|i| Node::Leaf(toml::Value::Integer(i)))
            .map_err(|_| E::custom(format!("{v} does not fit a TOML integer")))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Node, E> {
        Ok(Node::Leaf(toml::Value::Float(v)))
    }
    fn visit_str<E>(self, v: &str) -> Result<Node, E> {
        Ok(Node::Leaf(toml::Value::String(v.to_string())))
    }
    fn visit_string<E>(self, v: String) -> Result<Node, E> {
        Ok(Node::Leaf(toml::Value::String(v)))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut a: A) -> Result<Node, A::Error> {
        let mut items = Vec::new();
        while let Some(x) = a.next_element::<Spanned<Node>>()? {
            items.push(x);
        }
        Ok(Node::Array(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut a: A) -> Result<Node, A::Error> {
        let mut entries = Vec::new();
        while let Some(k) = a.next_key::<Spanned<String>>()? {
            let v = a.next_value::<Spanned<Node>>()?;
            entries.push((k, v));
        }
        Ok(Node::Table(entries))
    }
}

/// The dotted key assigned on the line holding byte `at` of a TOML text (its `[table]` header
/// prefixed), and the value text from `at` to the end of that token.
fn key_and_value_at(text: &str, at: usize) -> (Option<String>, String) {
    let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line = &text[line_start..];
    let line = &line[..line.find('\n').unwrap_or(line.len())];
    let number: String = text[at..]
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '+' | '-' | '.'))
        .collect();
    let Some((key, _)) = line.split_once('=') else {
        return (None, number);
    };
    let table = text[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('[') && !l.starts_with("[["))
        .map(|l| l.trim_matches(|c| c == '[' || c == ']').trim().to_string());
    let key = key.trim().trim_matches('"');
    let key = match table {
        Some(t) if !t.is_empty() => format!("{t}.{key}"),
        _ => key.to_string(),
    };
    (Some(key), number)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "[experiment]\nname = \"x\"\n\n[scene]\nintensity = 1.0\nclass = [{ fraction = 0.5, radius = { dist = \"uniform\", lo = 1 } }]\nwhen = 1979\n[sweep]\n\"grid.cell_width\" = [0.1, 0.2]\n";

    /// The tree is the text's, and every value, key and array element has its place: a bad value
    /// at the value, an unknown key at the key, a missing key at its table, as serde reading the
    /// text itself would say.
    #[test]
    fn one_parse_gives_the_tree_and_every_place() {
        let d = Document::parse(TEXT).expect("valid");
        assert_eq!(d.tree, TEXT.parse::<toml::Table>().expect("toml"));
        assert_eq!(d.place(TEXT, "scene.intensity", "got -1"), Some((5, 13)));
        assert_eq!(
            d.place(TEXT, "scene.intensity", "unknown field `intensity`"),
            Some((5, 1))
        );
        assert_eq!(d.place(TEXT, "scene.class[0].radius", "bad"), Some((6, 37)));
        assert_eq!(
            d.place(TEXT, "scene.class[0].radius.hi", "missing"),
            Some((6, 37))
        );
        assert_eq!(
            d.place(TEXT, "scene", "missing field `radius`"),
            Some((4, 1))
        );
        assert_eq!(d.place(TEXT, "sweep.grid.cell_width", "x"), Some((9, 21)));
        assert_eq!(
            d.place(TEXT, "sweep.grid.cell_width[1]", "x"),
            Some((9, 21))
        );
        let e = Document::parse("a = \n").expect_err("syntax");
        assert_eq!(e.at.map(|a| a.0), Some(1));
        let e = Document::parse("a = 1\nb = 1979-05-27\n").expect_err("a date");
        assert_eq!(
            (e.at, e.message.as_str()),
            (Some((2, 5)), "a date or time is not a value any key takes")
        );
    }
}
