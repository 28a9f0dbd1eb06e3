//! Spec errors in the contract's form: `FILE:LINE:COL: KEY: what is wrong (what is allowed)`.

use std::fmt;

/// One bad-input error, located as precisely as the input allows.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct SpecError {
    /// Where: the spec path, or the `--set` flag.
    pub source_name: String,
    /// 1-based line and column in the file, when known.
    pub location: Option<(usize, usize)>,
    /// The dotted key at fault, when known.
    pub key: Option<String>,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.source_name)?;
        if let Some((l, c)) = self.location {
            write!(f, ":{l}:{c}")?;
        }
        if let Some(k) = &self.key {
            write!(f, ": {k}")?;
        }
        write!(f, ": {}", self.message)
    }
}

pub use crate::toml_text::{find_key, line_col};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_follows_the_contract() {
        let e = SpecError {
            source_name: "x.toml".into(),
            location: Some((3, 14)),
            key: Some("scene.radius".into()),
            message: "got -1, expected > 0".into(),
        };
        assert_eq!(
            e.to_string(),
            "x.toml:3:14: scene.radius: got -1, expected > 0"
        );
    }
}
