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
    /// unit and class. The shapes may differ only as one observation against its estimate (a
    /// frame's `frame_s` in the frames table, `frame_s_mean`/`_se` over frames in the main table),
    /// which write different CSV names.
    #[test]
    fn a_column_name_means_one_thing_across_kinds_and_tables() {
        use std::collections::BTreeMap;
        let mut by: BTreeMap<&str, Vec<(String, &str, crate::output::column::Class)>> =
            BTreeMap::new();
        for k in KINDS {
            for (t, cols) in k.columns() {
                for c in cols {
                    by.entry(c.name).or_default().push((
                        format!("{}.{t}", k.name()),
                        c.unit,
                        c.class,
                    ));
                }
            }
        }
        let two: Vec<String> = by
            .iter()
            .filter(|(_, v)| {
                v.iter()
                    .map(|(_, u, c)| (*u, c.as_str()))
                    .collect::<BTreeSet<_>>()
                    .len()
                    > 1
            })
            .map(|(n, v)| format!("{n}: {v:?}"))
            .collect();
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
