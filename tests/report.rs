//! `raycost report` end to end: a real run's results (current metadata schema) become a page that
//! names the experiment, its provenance and its verdicts; an existing page is refused without
//! `--force` and a missing results folder is refused, both with exit 2.

use crate::common::{raycost, run_quiet, write_spec};

const TINY: &str = r#"
[experiment]
name = "tiny"
kind = "grid"
seed = 3
rays = 2000
description = "a <tiny> run"

[scene]
intensity = 1.0
radius = 0.2

[grid]
cell_width = 0.5

[sweep]
"grid.cell_width" = [0.4, 0.8]
"#;

#[test]
fn a_real_run_becomes_a_page_and_existing_pages_are_kept() {
    let tmp = tempfile::tempdir().expect("temp");
    let spec = write_spec(tmp.path(), "tiny", TINY);
    let results = tmp.path().join("results");
    run_quiet(&spec, &results).assert().success();
    let out = results.join("report");
    let o = raycost()
        .arg("report")
        .arg(&results)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).starts_with("wrote "));
    let page = std::fs::read_to_string(out.join("index.html")).expect("page");
    assert!(page.contains("<section id=\"exp-tiny\">"));
    assert!(page.contains("a &lt;tiny&gt; run"));
    assert!(page.contains("<dd>schema 2</dd>"));
    // Both points, each with its swept cell width and the grid's metrics judged.
    assert!(page.contains("grid.cell_width=0.4000") && page.contains("grid.cell_width=0.8000"));
    for metric in ["n_i", "n_s", "t_hit"] {
        assert!(
            page.contains(&format!("<td class=\"mono\">{metric}</td>")),
            "{metric}"
        );
    }

    let again = raycost()
        .arg("report")
        .arg(&results)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    raycost()
        .arg("report")
        .arg(&results)
        .arg("--out")
        .arg(&out)
        .arg("--force")
        .assert()
        .success();

    let missing = raycost()
        .arg("report")
        .arg(tmp.path().join("nope"))
        .arg("--out")
        .arg(tmp.path().join("o"))
        .output()
        .expect("runs");
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no such results folder"));
}
