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
}
