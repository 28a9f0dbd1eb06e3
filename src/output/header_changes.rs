//! Columns a kind renamed or stopped writing since a committed result was written, so that a result
//! written before the change still compares with a rerun after it (`raycost reproduce`): the old
//! side's header is brought up to date *before* the comparison, never the cells.
//!
//! Why a list rather than rewriting old tables: a committed table is what a build of a commit
//! wrote (its metadata says which); editing its header would make it something no build wrote. The
//! list is also the CHANGELOG's record of what a reader of old tables must map.
//!
//! Each change is one of:
//! - **renamed**: the same values under a name that means one thing across kinds (e.g. detp's
//!   engine speed counts segments, the grid kinds' `rays_per_s` counts rays);
//! - **dropped as a duplicate**: a column that repeated another column of the same row (a
//!   parameter written twice). The old table's cells must equal the kept column's, row by row; a
//!   row where they differ is reported, so dropping never hides a difference.

//!
//! The list itself is data, `header_changes.toml` beside this file, compiled in and read by
//! `scripts/compare_tables.py` too: one list for both comparers.

use super::column::ColumnInfo;
use serde::Deserialize;
use std::sync::OnceLock;

/// What became of an old column.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Change {
    /// Written under this name now.
    Renamed(String),
    /// No longer written: it repeated this column of the same table.
    Duplicate(String),
}

/// One column of one kind's table that changed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HeaderChange {
    /// `experiment.kind`.
    pub kind: String,
    /// Table (`main` or a side table's name).
    pub table: String,
    /// The CSV name old results carry.
    pub old: String,
    /// What it is now.
    pub change: Change,
    /// Why, one sentence (the CHANGELOG says the same).
    pub why: String,
}

/// The list as written in `header_changes.toml`.
const LIST: &str = include_str!("header_changes.toml");

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ListFile {
    change: Vec<Entry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    kind: String,
    table: String,
    old: String,
    why: String,
    renamed: Option<String>,
    duplicate_of: Option<String>,
}

/// Parses a list in `header_changes.toml`'s format; an entry must say exactly one of `renamed`
/// and `duplicate_of`.
fn parse(text: &str) -> Result<Vec<HeaderChange>, String> {
    let file: ListFile = toml::from_str(text).map_err(|e| e.to_string())?;
    file.change
        .into_iter()
        .map(|e| {
            let change = match (e.renamed, e.duplicate_of) {
                (Some(new), None) => Change::Renamed(new),
                (None, Some(kept)) => Change::Duplicate(kept),
                _ => {
                    return Err(format!(
                        "{}.{}: {}: give exactly one of renamed and duplicate_of",
                        e.kind, e.table, e.old
                    ))
                }
            };
            Ok(HeaderChange {
                kind: e.kind,
                table: e.table,
                old: e.old,
                change,
                why: e.why,
            })
        })
        .collect()
}

/// Every change, oldest first (the compiled-in list; its test parses it).
pub fn changes() -> &'static [HeaderChange] {
    static CHANGES: OnceLock<Vec<HeaderChange>> = OnceLock::new();
    CHANGES.get_or_init(|| parse(LIST).expect("src/output/header_changes.toml"))
}

/// The changes that apply to `kind`'s `table`.
pub fn of<'a>(kind: &'a str, table: &'a str) -> impl Iterator<Item = &'static HeaderChange> + 'a {
    changes()
        .iter()
        .filter(move |c| c.kind == kind && c.table == table)
}

/// Brings an old table's header (and its declared classes) up to date with `kind`'s current
/// columns: renamed columns take their new name, duplicates are removed from `header`, every row
/// and `classes`. Returns one line per change applied (what a comparison reports), and one per row
/// where a dropped duplicate differed from the column it repeated.
pub fn upgrade(
    kind: &str,
    table: &str,
    header: &mut Vec<String>,
    rows: &mut [Vec<String>],
    classes: &mut Vec<ColumnInfo>,
) -> (Vec<String>, Vec<String>) {
    let (mut applied, mut differences) = (Vec::new(), Vec::new());
    for c in of(kind, table) {
        let Some(at) = header.iter().position(|h| *h == c.old) else {
            continue;
        };
        match &c.change {
            Change::Renamed(new) => {
                if header.iter().any(|h| h == new) {
                    differences.push(format!(
                        "both {} and its new name {new} in one header",
                        c.old
                    ));
                    continue;
                }
                header[at] = new.clone();
                for info in classes.iter_mut().filter(|i| i.name == c.old) {
                    info.name = new.clone();
                }
                applied.push(format!("{} read as {new} ({})", c.old, c.why));
            }
            Change::Duplicate(kept) => {
                let Some(k) = header.iter().position(|h| h == kept) else {
                    differences.push(format!(
                        "{} dropped as a duplicate of {kept}, which the table lacks",
                        c.old
                    ));
                    continue;
                };
                for (r, row) in rows.iter().enumerate() {
                    if row.get(at) != row.get(k) {
                        differences.push(format!(
                            "row {r}: {} = {:?} but {kept} = {:?}",
                            c.old,
                            row.get(at).map_or("", String::as_str),
                            row.get(k).map_or("", String::as_str)
                        ));
                    }
                }
                header.remove(at);
                for row in rows.iter_mut() {
                    if at < row.len() {
                        row.remove(at);
                    }
                }
                classes.retain(|i| i.name != c.old);
                applied.push(format!("{} dropped ({})", c.old, c.why));
            }
        }
    }
    (applied, differences)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::column::Class;

    fn info(name: &str) -> ColumnInfo {
        ColumnInfo {
            name: name.into(),
            class: Class::Parameter,
            unit: "1".into(),
        }
    }

    fn strings(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn the_compiled_in_list_parses_and_a_malformed_entry_is_refused() {
        assert!(!changes().is_empty());
        let both = "[[change]]\nkind = \"k\"\ntable = \"main\"\nold = \"a\"\nwhy = \"w\"\n";
        assert!(parse(both).unwrap_err().contains("exactly one"));
        let two = format!("{both}renamed = \"b\"\nduplicate_of = \"c\"\n");
        assert!(parse(&two).unwrap_err().contains("exactly one"));
        let odd = format!("{both}renamed = \"b\"\nnote = \"x\"\n");
        assert!(parse(&odd).is_err(), "an unknown key is refused");
        let one = parse(&format!("{both}renamed = \"b\"\n")).unwrap();
        assert_eq!(one[0].change, Change::Renamed("b".into()));
    }

    #[test]
    fn a_renamed_column_takes_its_new_name_in_the_header_and_the_classes() {
        let mut header = strings(&["point", "rays_per_s"]);
        let mut rows = vec![strings(&["0", "1e6"])];
        let mut classes = vec![info("point"), info("rays_per_s")];
        let (applied, diff) = upgrade("detp", "main", &mut header, &mut rows, &mut classes);
        assert_eq!(header, strings(&["point", "segments_per_s"]));
        assert_eq!(rows, vec![strings(&["0", "1e6"])]);
        assert_eq!(classes[1].name, "segments_per_s");
        assert_eq!(applied.len(), 1);
        assert!(diff.is_empty());
        // Another kind's column of the same name is left alone.
        let mut header = strings(&["point", "rays_per_s"]);
        let (applied, _) = upgrade("grid", "main", &mut header, &mut rows, &mut classes);
        assert_eq!(header, strings(&["point", "rays_per_s"]));
        assert!(applied.is_empty());
    }

    #[test]
    fn a_dropped_duplicate_is_removed_and_a_row_where_it_differed_is_reported() {
        let mut header = strings(&["point", "detp.photons", "photons", "segments"]);
        let mut rows = vec![
            strings(&["0", "100", "100", "7"]),
            strings(&["1", "200", "300", "9"]),
        ];
        let mut classes = header.iter().map(|h| info(h)).collect::<Vec<_>>();
        let (applied, diff) = upgrade("quasi-static", "main", &mut header, &mut rows, &mut classes);
        assert_eq!(header, strings(&["point", "detp.photons", "segments"]));
        assert_eq!(rows[1], strings(&["1", "200", "9"]));
        assert_eq!(classes.len(), 3);
        assert_eq!(applied.len(), 1);
        assert_eq!(diff.len(), 1, "{diff:?}");
        assert!(diff[0].starts_with("row 1: photons"), "{diff:?}");
    }
}
