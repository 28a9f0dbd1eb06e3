//! The experiment kinds raycost knows. The list itself is one line per kind module in
//! `experiment/mod.rs` ([`kinds!`](crate::kinds) declares the module and registers its kinds);
//! `experiment.kind` is looked up here, and the runner, `check`, `merge` and `raycost doc` see kinds
//! only through [`DynKind`].

use super::kind::DynKind;
pub use super::KINDS;

/// Declares the kind modules and registers their kinds, one line per module:
/// `module => [Kind, …]` declares `pub mod module;` and adds each kind to `KINDS`, in the order
/// `raycost doc` lists them. Invoked once, in `experiment/mod.rs`.
#[macro_export]
macro_rules! kinds {
    ($($(#[$m:meta])* $module:ident => [$($kind:ty),+ $(,)?]),* $(,)?) => {
        $($(#[$m])* pub mod $module;)*
        /// Every kind, in the order `raycost doc` lists them.
        pub static KINDS: &[&dyn $crate::experiment::kind::DynKind] = &[
            $($(&$crate::experiment::kind::Registered::<$kind>::NEW),+),*
        ];
    };
}

/// The kind named `name`.
pub fn find(name: &str) -> Option<&'static dyn DynKind> {
    KINDS.iter().copied().find(|k| k.name() == name)
}

/// The names of every kind, quoted and joined, for messages.
pub fn names() -> String {
    KINDS
        .iter()
        .map(|k| format!("\"{}\"", k.name()))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    /// Declarations a run relies on: unique kind names, unique table names, and no column declared
    /// twice within a table.
    #[test]
    fn the_registry_is_consistent() {
        let names: BTreeSet<&str> = KINDS.iter().map(|k| k.name()).collect();
        assert_eq!(names.len(), KINDS.len(), "a kind name is registered twice");
        for k in KINDS {
            let tables: BTreeSet<&str> = k.table_names().iter().copied().collect();
            assert_eq!(tables.len(), k.table_names().len(), "{}", k.name());
            let declared: Vec<&str> = k.columns().iter().map(|(t, _)| *t).collect();
            assert_eq!(
                declared[0],
                "main",
                "{}: the main table comes first",
                k.name()
            );
            for t in k.table_names() {
                assert!(
                    declared.contains(t),
                    "{}: table {t} has no columns",
                    k.name()
                );
            }
            for (t, cols) in k.columns() {
                let mut seen = BTreeSet::new();
                for c in cols {
                    assert!(seen.insert(c.name), "{}: {t}.{} twice", k.name(), c.name);
                }
            }
            assert!(!k.about().is_empty());
        }
    }

    /// One name, one meaning: wherever kinds declare the same column name, it carries the same
    /// unit and class, and the same shape, with one exception that writes different CSV names: a
    /// per-row value and its estimate over those rows ([`Column::mean_over`]: a frame's `frame_s`
    /// in the frames table, `frame_s_mean`/`_se` over frames in the main table). A kind may write
    /// such an estimate only of a value it writes itself in another table, so `X_mean` is always
    /// the mean of the rows that say `X`.
    #[test]
    fn a_column_name_means_one_thing_across_kinds_and_tables() {
        use crate::output::column::Shape;
        use std::collections::BTreeMap;
        struct Seen {
            kind: &'static str,
            table: String,
            unit: &'static str,
            class: &'static str,
            shape: Shape,
        }
        let mut by: BTreeMap<&str, Vec<Seen>> = BTreeMap::new();
        for k in KINDS {
            for (t, cols) in k.columns() {
                for c in cols {
                    by.entry(c.name).or_default().push(Seen {
                        kind: k.name(),
                        table: t.to_string(),
                        unit: c.unit,
                        class: c.class.as_str(),
                        shape: c.shape,
                    });
                }
            }
        }
        let mut two = Vec::new();
        for (name, seen) in &by {
            let where_ = |s: &Seen| format!("{}.{}", s.kind, s.table);
            let units: BTreeSet<_> = seen.iter().map(|s| (s.unit, s.class)).collect();
            if units.len() > 1 {
                two.push(format!("{name}: unit and class {units:?}"));
            }
            let estimates: BTreeSet<String> = seen
                .iter()
                .filter(|s| s.shape != Shape::Value)
                .map(|s| format!("{:?}", s.shape))
                .collect();
            if estimates.len() > 1 {
                two.push(format!("{name}: estimated as {estimates:?}"));
            }
            for e in seen.iter().filter(|s| s.shape != Shape::Value) {
                let of_its_own = seen
                    .iter()
                    .any(|v| v.shape == Shape::Value && v.kind == e.kind && v.table != e.table);
                let values: Vec<String> = seen
                    .iter()
                    .filter(|v| v.shape == Shape::Value)
                    .map(where_)
                    .collect();
                if !values.is_empty() && !of_its_own {
                    two.push(format!(
                        "{name}: an estimate in {} but a value in {values:?}, none of them {}'s own rows",
                        where_(e),
                        e.kind
                    ));
                }
            }
        }
        assert!(
            two.is_empty(),
            "names with two meanings:\n{}",
            two.join("\n")
        );
    }

    #[test]
    fn every_header_change_names_a_column_its_kind_no_longer_writes_and_a_kept_one_it_does() {
        use crate::output::header_changes::{changes, Change};
        for c in changes() {
            let kind = find(&c.kind).unwrap_or_else(|| panic!("{}: no such kind", c.kind));
            let names: Vec<String> = kind
                .columns()
                .into_iter()
                .filter(|(t, _)| *t == c.table)
                .flat_map(|(_, cols)| cols.into_iter().flat_map(|col| col.expand(col.name)))
                .map(|i| i.name)
                .collect();
            assert!(!names.is_empty(), "{}: no table {}", c.kind, c.table);
            assert!(
                !names.contains(&c.old),
                "{}.{}: {} is still written",
                c.kind,
                c.table,
                c.old
            );
            match &c.change {
                Change::Renamed(new) => assert!(
                    names.iter().any(|n| n == new),
                    "{}.{}: {new} is not written",
                    c.kind,
                    c.table
                ),
                // A kept parameter column comes from the spec's keys, not the declarations.
                Change::Duplicate(kept) => assert!(
                    kept.contains('.') || names.iter().any(|n| n == kept),
                    "{}.{}: {kept} is not written",
                    c.kind,
                    c.table
                ),
            }
        }
    }
}
