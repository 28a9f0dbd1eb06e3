//! The import graph of `src/` follows the layers `src/lib.rs` states: every `crate::X` path (outside
//! comments and string literals) names a module of a lower layer than the file's own, or its own
//! module. The list is read from lib.rs itself, so the doc and the code cannot drift apart, and a new
//! top-level module must be given a layer there before it compiles into a green test suite.

use std::collections::BTreeMap;
use std::path::Path;

use crate::common::root;

/// `module → layer` from lib.rs's numbered list (`//! 3. `stats`: …`, several names per line).
fn layers(lib: &str) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    for line in lib.lines() {
        let Some(rest) = line.strip_prefix("//! ") else {
            continue;
        };
        let Some((num, names)) = rest.split_once(". ") else {
            continue;
        };
        let Ok(layer) = num.trim().parse::<usize>() else {
            continue;
        };
        let names = names.split(':').next().unwrap_or("");
        for name in names.split(',') {
            if let Some(n) = name
                .trim()
                .strip_prefix('`')
                .and_then(|n| n.strip_suffix('`'))
            {
                out.insert(n.to_string(), layer);
            }
        }
    }
    out
}

/// The code of a Rust file without comments and string or char literals (so that a doc link or a
/// message naming a path is not an import).
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                    i += 1;
                }
                i += 2;
            }
            b'r' if b.get(i + 1) == Some(&b'#') || (b.get(i + 1) == Some(&b'"')) => {
                // A raw string r#"…"# (any number of #), or an identifier ending in r.
                let mut j = i + 1;
                while b.get(j) == Some(&b'#') {
                    j += 1;
                }
                let prev_ident = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
                if b.get(j) == Some(&b'"') && !prev_ident {
                    let hashes = j - i - 1;
                    let close: String = std::iter::once('"')
                        .chain("#".repeat(hashes).chars())
                        .collect();
                    let from = j + 1;
                    i = text[from..]
                        .find(&close)
                        .map_or(b.len(), |k| from + k + close.len());
                    out.push_str("\"\"");
                } else {
                    out.push('r');
                    i += 1;
                }
            }
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("\"\"");
            }
            b'\'' => {
                // A char literal ('x', '\n', '\u{..}') or a lifetime ('a).
                let mut chars = text[i + 1..].char_indices();
                match chars.next() {
                    Some((_, '\\')) => {
                        let close = text[i + 3..].find('\'').map_or(b.len(), |k| i + 3 + k);
                        i = close + 1;
                    }
                    Some((_, c)) if chars.next().map(|(_, q)| q) == Some('\'') => {
                        i += 1 + c.len_utf8() + 1;
                    }
                    _ => {
                        out.push('\'');
                        i += 1;
                    }
                }
            }
            _ => {
                let c = text[i..].chars().next().expect("in bounds");
                out.push(c);
                i += c.len_utf8();
            }
        }
    }
    out
}

/// The top-level modules a file's code names through `crate::` (including `use crate::{a, b::c}`).
fn imports(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(k) = rest.find("crate::") {
        // `$crate::` in a macro is the same path.
        let after = &rest[k + "crate::".len()..];
        let before_ok = k == 0 || {
            let c = rest.as_bytes()[k - 1];
            !(c.is_ascii_alphanumeric() || c == b'_')
        };
        if before_ok {
            if let Some(group) = after.strip_prefix('{') {
                let end = group.find('}').unwrap_or(group.len());
                for part in group[..end].split(',') {
                    let name: String = part
                        .trim()
                        .chars()
                        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                        .collect();
                    if !name.is_empty() {
                        out.push(name);
                    }
                }
            } else {
                let name: String = after
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.push(name);
                }
            }
        }
        rest = after;
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).expect("src is readable").flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Every import that runs up (or sideways across) the layers, as `file: module → imported`.
fn violations() -> Vec<String> {
    let src = root().join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("lib.rs");
    let layer = layers(&lib);
    let mut out = Vec::new();
    for line in code_only(&lib).lines() {
        if let Some(m) = line.trim().strip_prefix("pub mod ") {
            let m = m.trim_end_matches(';');
            if !layer.contains_key(m) {
                out.push(format!(
                    "src/lib.rs: module {m} has no layer in lib.rs's list"
                ));
            }
        }
    }
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    for f in files {
        let rel = f.strip_prefix(&src).expect("below src");
        let top = rel
            .components()
            .next()
            .and_then(|c| c.as_os_str().to_str())
            .map(|s| s.trim_end_matches(".rs").to_string())
            .unwrap_or_default();
        if top == "lib" || top == "main" {
            continue;
        }
        let Some(&mine) = layer.get(&top) else {
            continue;
        };
        let code = code_only(&std::fs::read_to_string(&f).expect("readable"));
        for m in imports(&code) {
            match layer.get(&m) {
                Some(&l) if m == top || l < mine => {}
                Some(&l) => out.push(format!(
                    "src/{}: {top} (layer {mine}) imports {m} (layer {l})",
                    rel.display()
                )),
                // Macros exported at the crate root (`crate::choice!`, `crate::side_tables!`).
                None => {}
            }
        }
        // Within `experiment`: the runner does not import the docs generator.
        if rel == Path::new("experiment/runner.rs")
            && (code.contains("reference::") || code.contains("experiment::reference"))
        {
            out.push(
                "src/experiment/runner.rs: imports the docs generator (experiment::reference)"
                    .into(),
            );
        }
    }
    out
}

#[test]
fn imports_follow_the_layers_lib_rs_states() {
    let v = violations();
    assert!(
        v.is_empty(),
        "{} layer violation(s):\n{}",
        v.len(),
        v.join("\n")
    );
}

#[test]
fn the_checker_sees_paths_and_only_paths() {
    let code = code_only(
        "use crate::{geom::Ray, stats};\n// crate::app in a comment\nlet s = \"crate::cli\";\nlet c = '\"'; let r = r#\"crate::report\"#;\nfn f<'a>(x: &'a str) -> crate::output::Row { $crate::spec::X }\n",
    );
    assert_eq!(imports(&code), ["geom", "stats", "output", "spec"]);
    let lib = "//! 0. `toml_text`, `error`: low\n//! 3. `stats`: means\n//! not a layer\n";
    let l = layers(lib);
    assert_eq!((l["toml_text"], l["error"], l["stats"]), (0, 0, 3));
}
