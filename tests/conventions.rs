//! The conventions of a real CLI: completions, man page, examples in every `--help`, exit codes in
//! the top-level help, and JSON from `check` and `theory` that carries the same numbers as the text.

use crate::common::{raycost, root};

fn stdout_of(args: &[&str]) -> String {
    let o = raycost().args(args).output().expect("runs");
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).expect("UTF-8")
}

/// Every subcommand, from the clap definition itself (a new one is checked without editing this
/// file).
fn subcommands() -> Vec<String> {
    use clap::CommandFactory;
    let names: Vec<String> = raycost::cli::Cli::command()
        .get_subcommands()
        .map(|c| c.get_name().to_string())
        .filter(|n| n != "help")
        .collect();
    // The list is not empty and holds the commands users rely on (a broken definition fails here).
    for must in ["run", "check", "merge", "report", "crossover", "reproduce"] {
        assert!(names.iter().any(|n| n == must), "no {must} in {names:?}");
    }
    names
}

#[test]
fn completions_name_every_subcommand() {
    let bash = stdout_of(&["completions", "bash"]);
    for sub in subcommands() {
        assert!(bash.contains(&format!("raycost,{sub})")), "bash: no {sub}");
    }
    for shell in ["zsh", "fish", "elvish", "powershell"] {
        assert!(
            stdout_of(&["completions", shell]).contains("render"),
            "{shell}"
        );
    }
    raycost().args(["completions", "tcsh"]).assert().code(2);
}

#[test]
fn man_page_is_roff_with_every_subcommand() {
    let man = stdout_of(&["man"]);
    assert!(
        man.contains(".TH raycost 1"),
        "{}",
        &man[..200.min(man.len())]
    );
    for sub in subcommands() {
        assert!(man.contains(&sub), "man: no {sub}");
    }
}

#[test]
fn every_help_has_examples_and_the_top_level_lists_exit_codes() {
    let top = stdout_of(&["--help"]);
    for code in ["0 ", "1 ", "2 ", "130", "101"] {
        assert!(
            top.contains(&format!("\n  {code}")),
            "exit code {code}: {top}"
        );
    }
    for sub in subcommands() {
        let help = stdout_of(&[&sub, "--help"]);
        assert!(
            help.contains("Examples:\n  raycost "),
            "{sub} --help: {help}"
        );
    }
}

#[test]
fn check_json_carries_what_check_prints() {
    let spec = root().join("experiments/quickstart.toml");
    let spec = spec.to_str().unwrap();
    let text = stdout_of(&["check", spec]);
    let json: serde_json::Value =
        serde_json::from_str(&stdout_of(&["check", spec, "--json"])).expect("JSON");
    assert_eq!(json["kind"], "grid");
    let points = json["points"].as_array().expect("points");
    let lines: Vec<&str> = text.lines().filter(|l| l.contains("point ")).collect();
    assert_eq!(points.len(), lines.len());
    for (p, line) in points.iter().zip(&lines) {
        let (k, v) = p["params"].as_object().unwrap().iter().next().unwrap();
        assert!(line.contains(&format!("{k} = {v}")), "{line} vs {p}");
        assert!(line.ends_with(p["describe"].as_str().unwrap()), "{line}");
        assert_eq!(p["work"]["unit"], "rays");
        assert!(
            line.contains(&format!("{} rays", p["work"]["units"])),
            "{line}"
        );
        assert!(p["memory"]["bytes"].as_f64().unwrap() > 0.0);
        assert_eq!(p["memory"]["budget"]["key"], "grid.memory_budget_gib");
        assert!(p["warnings"].as_array().unwrap().is_empty());
    }
}

/// The value printed after each label of a theory table, as text.
fn table_values(text: &str, label: &str) -> String {
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with(label))
        .unwrap_or_else(|| panic!("no row {label}: {text}"));
    line.split_whitespace().last().unwrap().to_string()
}

#[test]
fn theory_json_has_the_table_numbers() {
    let grid = [
        "theory",
        "grid",
        "--intensity",
        "1",
        "--radius",
        "0.2",
        "--cell-width",
        "0.5",
    ];
    let text = stdout_of(&grid);
    let json: serde_json::Value =
        serde_json::from_str(&stdout_of(&[&grid[..], &["--json"]].concat())).expect("JSON");
    assert_eq!(json["inputs"]["cell_width"], 0.5);
    let values = json["values"].as_object().unwrap();
    assert_eq!(values.len(), 11);
    for v in values.values() {
        let label = v["label"].as_str().unwrap();
        let x = v["value"].as_f64().unwrap();
        assert_eq!(format!("{x:.6}"), table_values(&text, label), "{label}");
    }
    // E[t*] = 1/(ρπr²) at ρ = 1, r = 0.2.
    let t = values["t_hit"]["value"].as_f64().unwrap();
    assert!((t - 1.0 / (std::f64::consts::PI * 0.04)).abs() < 1e-12);

    let detp = ["theory", "detp", "--rays", "1e6", "--points", "1e5"];
    let text = stdout_of(&detp);
    let json: serde_json::Value =
        serde_json::from_str(&stdout_of(&[&detp[..], &["--json"]].concat())).expect("JSON");
    let values = json["values"].as_object().unwrap();
    assert_eq!(values.len(), 13);
    for v in values.values() {
        let label = v["label"].as_str().unwrap();
        let x = v["value"].as_f64().unwrap();
        assert_eq!(format!("{x:.6e}"), table_values(&text, label), "{label}");
    }
    // 1/(Q²(1 − Q)) = 6.75 at Q = 2/3 (up to the rounding of 2/3).
    let factor = values["rebuild_factor"]["value"].as_f64().unwrap();
    assert!((factor - 6.75).abs() < 1e-12, "{factor}");
    let levels = json["levels"].as_array().unwrap();
    assert_eq!(
        levels.len(),
        text.lines()
            .filter(|l| l.trim_start().starts_with("level"))
            .count()
    );
    assert_eq!(levels[0]["rays"], 1e6);
}

/// A DETP run on the closed sphere (exact E = 2π) with one replica: the mean irradiance gets a
/// Poisson SE and a verdict against 2π (not "n/a"), the rays per level of photons are shown
/// against the uniform-line law without a verdict (the law is for lines), and without a terminal
/// progress comes as plain lines while the point runs, counting photons.
#[test]
fn one_replica_is_judged_against_the_exact_value_and_progress_ticks() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = root().join("experiments/detp-accuracy.toml");
    let o = raycost()
        .arg("run")
        .arg(&spec)
        .arg("--out")
        .arg(tmp.path())
        .args([
            "--set",
            "detp.scene=\"scenes/closed-sphere.toml\"",
            "--set",
            "detp.photons=300000",
            "--set",
            "detp.disc_radius=0.05",
            "--set",
            "detp.photon_map_k=16",
            "--set",
            "detp.replicas=1",
            "--set",
            "detp.engines=[\"sphere-cache\"]",
        ])
        .output()
        .expect("runs");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{stderr}");
    let irr = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("irradiance"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(irr.contains("6.2832"), "{irr}");
    assert!(!irr.contains("n/a") && irr.contains(" ± "), "{irr}");
    assert!(irr.contains("ok (99% CI)") || irr.contains(" SE"), "{irr}");
    for l in stdout.lines().filter(|l| l.contains("rays L")) {
        assert!(
            l.contains("(photons: not judged)") && !l.contains(" SE"),
            "{l}"
        );
    }
    // The CSV's SE is the summary's.
    let (header, rows) =
        crate::common::read_csv(&tmp.path().join("detp-accuracy/detp-accuracy.csv"));
    let se = header.iter().position(|h| h == "irradiance_se").unwrap();
    let se: f64 = rows[0][se].parse().unwrap();
    assert!(se.is_finite() && se > 0.0, "{se}");
    // Every parameter of the point is in its row, swept or not.
    for key in ["detp.q", "detp.threshold", "experiment.seed", "detp.scene"] {
        assert!(header.iter().any(|h| h == key), "{key}: {header:?}");
    }
    let ticks: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("progress:"))
        .collect();
    // A line at the start, one at the end, and one for every whole second in between: the count
    // follows the run's own elapsed time (how fast the machine is decides that, not the test).
    let elapsed: u64 = ticks
        .last()
        .and_then(|l| l.rsplit("elapsed ").next())
        .and_then(|t| t.trim_end_matches(" s").trim().parse().ok())
        .unwrap_or_else(|| panic!("no elapsed time: {stderr}"));
    assert!(
        ticks.len() as u64 >= 2 + elapsed.saturating_sub(1),
        "start, a tick for each second while running, end ({elapsed} s): {stderr}"
    );
    assert!(ticks
        .iter()
        .all(|l| l.contains("photons") && l.contains("eta")));
    assert!(ticks.last().unwrap().contains("300000/300000 photons"));
}

/// The repository explains itself: no source, doc, script or spec names a document that a clone
/// does not have (the project's working notes beside the repository), and no command's help names
/// an issue number (a user has no issue tracker to look it up in).
#[test]
fn nothing_refers_outside_the_repository() {
    use crate::common::files_below;
    let outside = [
        concat!("..", "/shared"),
        "THEORY.md",
        "PERFORMANCE.md",
        "CONTRACT.md",
        "DESIGN.md",
        "STYLE.md",
    ];
    let mut found = Vec::new();
    let mut read = 0;
    for dir in [
        "src",
        "docs",
        "scripts",
        "tests",
        "examples",
        "experiments",
        "claims",
        ".ci",
    ] {
        for f in files_below(&root().join(dir)) {
            let ext = f.extension().and_then(|e| e.to_str()).unwrap_or("");
            // `.ci/run` has no extension.
            if !["rs", "md", "py", "sh", "toml", "sbatch", ""].contains(&ext) {
                continue;
            }
            // This test names the documents it looks for.
            if f.ends_with("tests/conventions.rs") {
                continue;
            }
            let text = std::fs::read_to_string(&f).unwrap_or_default();
            read += 1;
            for o in outside {
                if text.contains(o) {
                    found.push(format!("{} names {o}", f.display()));
                }
            }
        }
    }
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README");
    for o in outside {
        if readme.contains(o) {
            found.push(format!("README.md names {o}"));
        }
    }
    assert!(read > 100, "only {read} files read: the walk is broken");
    assert!(found.is_empty(), "{found:#?}");

    let issue = |text: &str| {
        let lower = text.to_lowercase();
        lower.match_indices("issue").any(|(i, _)| {
            let rest = lower[i + 5..].trim_start_matches([' ', '#']);
            rest.starts_with(|c: char| c.is_ascii_digit())
        })
    };
    assert!(issue("see issue 27") && issue("Issue #3") && !issue("an issue"));
    assert!(!issue(&readme), "README.md names an issue number");
    assert!(!issue(&readme), "README.md names an issue number");
    for sub in subcommands() {
        let help = stdout_of(&[&sub, "--help"]);
        assert!(!issue(&help), "{sub} --help names an issue number:\n{help}");
    }
    assert!(
        !issue(&stdout_of(&["--help"])),
        "--help names an issue number"
    );
}
