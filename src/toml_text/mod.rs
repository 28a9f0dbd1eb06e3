//! TOML text as every input file reads it, below every layer that reads one (specs, scene files,
//! the claims file): where a key or a byte offset sits in the text, for error messages that name the
//! line and column (`FILE:LINE:COL: KEY: …`); serde readers that locate a bad value and check its
//! range where it is read ([`de`]); a text read once into its tree and the places of its keys and
//! values ([`document`]); and the declarations of the keys a user writes, from which the key lists
//! and the reference docs come ([`keys`]). Knows nothing of specs or scenes.

pub mod de;
pub mod document;
pub mod keys;

/// 1-based (line, column) of byte offset `at` in `text`.
pub fn line_col(text: &str, at: usize) -> (usize, usize) {
    let at = at.min(text.len());
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Best-effort location of a dotted key's definition in the text: the `[sweep]` entry `"key" =`, or
/// the line `leaf =` inside its table. Used for errors found after expansion, where serde has no span.
pub fn find_key(text: &str, key: &str) -> Option<(usize, usize)> {
    let quoted = format!("\"{key}\"");
    if let Some(i) = find_line_start(text, &quoted) {
        return Some(line_col(text, i));
    }
    let Some((table, leaf)) = key.rsplit_once('.') else {
        // A whole table: its header line.
        return [format!("[[{key}]]"), format!("[{key}]")]
            .iter()
            .find_map(|h| find_line_start(text, h))
            .map(|i| line_col(text, i));
    };
    let header = format!("[{table}]");
    let Some(start) = find_line_start(text, &header) else {
        return find_key(text, table);
    };
    let mut offset = start;
    for line in text[start..].split_inclusive('\n').skip(1) {
        offset += 0;
        let trimmed = line.trim_start();
        if trimmed.starts_with('[') {
            break;
        }
        if let Some(rest) = trimmed.strip_prefix(leaf) {
            if rest.trim_start().starts_with('=') {
                let pos = text[start..]
                    .find(line)
                    .map(|p| start + p + (line.len() - trimmed.len()))?;
                return Some(line_col(text, pos));
            }
        }
    }
    let _ = offset;
    // The key is not written in its table (a default or a cross-key rule): point at the table.
    Some(line_col(text, start))
}

/// Byte offset of the first line that starts (after indentation) with `needle`: a key or header as
/// written, never a mention of it in a comment or a string.
fn find_line_start(text: &str, needle: &str) -> Option<usize> {
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let trimmed = line.trim_start();
        if trimmed.starts_with(needle) {
            return Some(offset + line.len() - trimmed.len());
        }
        offset += line.len();
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locations_are_one_based() {
        let t = "a = 1\n[grid]\ncell_width = 2\n";
        assert_eq!(line_col(t, 0), (1, 1));
        assert_eq!(line_col(t, 13), (3, 1));
        assert_eq!(find_key(t, "grid.cell_width"), Some((3, 1)));
        assert_eq!(
            find_key("[sweep]\n\"grid.cell_width\" = [1]\n", "grid.cell_width"),
            Some((2, 1))
        );
    }

    #[test]
    fn comments_that_mention_a_key_are_not_its_location() {
        let t = "# the [grid] table and \"grid.cell_width\"\n[grid]\ncell_width = 2\n";
        assert_eq!(find_key(t, "grid"), Some((2, 1)));
        assert_eq!(find_key(t, "grid.cell_width"), Some((3, 1)));
    }
}
