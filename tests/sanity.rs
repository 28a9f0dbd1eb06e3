//! Physics sanity: answers that would be meaningless come with a counted warning on
//! stderr and in `meta.toml`, however `--quiet` the run.

use crate::common::{run_quiet, write_spec};

fn meta_warnings(path: &std::path::Path) -> Vec<String> {
    raycost::output::meta::Meta::read(path)
        .expect("meta")
        .warnings
}

#[test]
fn a_light_that_reaches_no_point_is_a_counted_warning() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = crate::common::root().join("tests/scenes/sanity/light-below.toml");
    let spec = write_spec(
        tmp.path(),
        "dark",
        &format!(
            "[experiment]\nname = \"dark\"\nkind = \"detp\"\n[detp]\nsource = \"scene\"\nscene = {:?}\nphotons = 2000\ndisc_radius = 0.5\n",
            scene.display().to_string()
        ),
    );
    let out = tmp.path().join("out");
    let o = run_quiet(&spec, &out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no photon crossed any of the"), "{err}");
    let w = meta_warnings(&out.join("dark/dark.meta.toml"));
    assert!(w.iter().any(|w| w.contains("no photon crossed")), "{w:?}");
}

#[test]
fn points_off_their_surface_or_facing_into_it_are_counted_warnings() {
    let tmp = tempfile::tempdir().unwrap();
    let root = crate::common::root();
    let spec = write_spec(
        tmp.path(),
        "pts",
        &format!(
            "[experiment]\nname = \"pts\"\nkind = \"detp\"\n[detp]\nsource = \"scene\"\nscene = {:?}\nphotons = 2000\ndisc_radius = 0.05\npoint_source = \"file\"\npoints_file = {:?}\n",
            root.join("experiments/scenes/point-over-plane.toml").display().to_string(),
            root.join("tests/scenes/sanity/points.csv").display().to_string()
        ),
    );
    // `check` shows them before anything runs; `run` prints and records them.
    let o = crate::common::raycost()
        .arg("check")
        .arg(&spec)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("1 of 4 points") && text.contains("farther than d"),
        "{text}"
    );
    assert!(
        text.contains("have a normal facing into the surface"),
        "{text}"
    );
    let out = tmp.path().join("out");
    let o = run_quiet(&spec, &out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let w = meta_warnings(&out.join("pts/pts.meta.toml"));
    assert_eq!(w.len(), 2, "{w:?}");
}
