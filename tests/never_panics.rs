//! No input can make raycost panic: random mutations of every shipped spec, of the TOML
//! scenes, of AFF text and of points CSVs go through the readers and the whole validation (`raycost
//! check`'s path: every point configured, input files loaded, memory estimated). Each must come
//! back as `Ok` or a located error; a panic fails the test and proptest shrinks it to a minimal
//! input. The number of cases is bounded so CI stays fast (`PROPTEST_CASES` raises it).

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use proptest::test_runner::Config;

use crate::common::root;

/// Values that have broken parsers before: non-finite and extreme numbers, wrong types, empty and
/// nested arrays, huge integers.
const NASTY: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "4e9",
    "18446744073709551615",
    "9223372036854775807",
    "-9223372036854775808",
    "0.9999999999",
    "1.0000001",
    "\"\"",
    "\"x\"",
    "\"../\"",
    "[]",
    "[[]]",
    "[1, 2]",
    "[\"a\", 1]",
    "true",
    "{}",
    "{ a = 1 }",
    "1979-05-27",
    "2",
    "3",
    "0.5",
    "1e6",
    "\"spacing\"",
    "\"grid\"",
    "\"file\"",
    "\"scene\"",
];

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|c| c.parse().ok())
        .unwrap_or(256)
}

/// `text` with the value of its `line`-th `key = value` line replaced by `value` (or the line
/// deleted, or duplicated).
fn mutate(text: &str, line: usize, value: &str, how: u8) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let assigns: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].contains('=') && !lines[i].trim_start().starts_with('#'))
        .collect();
    if assigns.is_empty() {
        return format!("{text}\n{value}\n");
    }
    let target = assigns[line % assigns.len()];
    let mut out = Vec::with_capacity(lines.len() + 1);
    for (i, l) in lines.iter().enumerate() {
        if i != target {
            out.push(l.to_string());
            continue;
        }
        let key = l.split('=').next().unwrap_or("");
        match how % 4 {
            0 | 1 => out.push(format!("{key}= {value}")),
            2 => {}
            _ => {
                out.push(l.to_string());
                out.push(l.to_string());
            }
        }
    }
    out.join("\n")
}

fn toml_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

/// Every file of `paths` with its text.
fn read_all(paths: Vec<PathBuf>) -> Vec<(PathBuf, String)> {
    paths
        .into_iter()
        .map(|p| {
            let t = std::fs::read_to_string(&p).unwrap();
            (p, t)
        })
        .collect()
}

/// Validates spec text as `raycost check` does (the spec named as if it sat at `path`).
fn check_spec(path: &Path, text: &str) {
    if let Ok(spec) = raycost::spec::Spec::parse(&path.display().to_string(), text, &[]) {
        let _ = raycost::experiment::plan::Plan::from_spec(spec, 1);
    }
}

#[test]
fn mutated_specs_never_panic() {
    let mut specs = toml_files(&root().join("experiments"));
    specs.extend(toml_files(&root().join("tests/specs")));
    let texts = read_all(specs);
    let n = texts.len();
    proptest!(Config { cases: cases(), failure_persistence: None, ..Config::default() },
    |(which in 0..n, line in 0usize..64, value in proptest::sample::select(NASTY), how in 0u8..4)| {
        let (path, text) = &texts[which];
        check_spec(path, &mutate(text, line, value, how));
    });
}

#[test]
fn mutated_scenes_never_panic() {
    let texts = read_all(toml_files(&root().join("experiments/scenes")));
    let n = texts.len();
    proptest!(Config { cases: cases(), failure_persistence: None, ..Config::default() },
    |(which in 0..n, line in 0usize..256, value in proptest::sample::select(NASTY), how in 0u8..4)| {
        let (path, text) = &texts[which];
        let _ = raycost::lt::Scene::parse(&mutate(text, line, value, how), path);
    });
}

/// AFF tokens, valid and not, in random order: the reader must refuse, never panic.
const AFF_TOKENS: &[&str] = &[
    "v",
    "from",
    "at",
    "up",
    "angle",
    "hither",
    "resolution",
    "b",
    "l",
    "f",
    "fm",
    "p",
    "pp",
    "s",
    "c",
    "m",
    "tt",
    "ttp",
    "tpa",
    "xs",
    "x",
    "k",
    "a",
    "i",
    "{",
    "}",
    "vertices",
    "normals",
    "triangles",
    "texturecoords",
    "transl",
    "rot",
    "scale",
    "visibility",
    "0",
    "1",
    "2",
    "3",
    "-1",
    "1e308",
    "nan",
    "inf",
    "0.5",
    "4294967296",
    "1e9",
    "name",
    "%",
    "#",
    "\n",
];

#[test]
fn random_aff_never_panics() {
    let path = root().join("experiments/scenes/bart/museum/fuzz.aff");
    proptest!(Config { cases: cases() * 4, failure_persistence: None, ..Config::default() },
    |(tokens in proptest::collection::vec(proptest::sample::select(AFF_TOKENS), 0..80))| {
        let _ = raycost::lt::aff::parse_aff(&tokens.join(" "), &path);
    });
}

#[test]
fn random_points_csv_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("pts.csv");
    let cells = proptest::sample::select(NASTY);
    proptest!(Config { cases: cases(), failure_persistence: None, ..Config::default() },
    |(rows in proptest::collection::vec(proptest::collection::vec(cells, 0..8), 0..6), header in any::<bool>())| {
        let mut text = if header { "x,y,z,nx,ny,nz\n".to_string() } else { String::new() };
        for r in rows {
            text.push_str(&r.join(","));
            text.push('\n');
        }
        std::fs::write(&p, text).unwrap();
        let _ = raycost::detp::surface_points::read_points_csv(&p);
    });
}
