//! The report end to end on a made-up results folder: every folder appears, hostile names and
//! descriptions are escaped, and every image and link on the page resolves to a file.

use std::fs;
use std::path::{Path, PathBuf};

use super::html::unhref;
use super::{run, ReportOptions};
use crate::error::Error;

/// A folder name with every character HTML cares about.
const HOSTILE: &str = "a <b>&\"c'";

/// A real 3×2 grey PNG.
fn png_bytes() -> Vec<u8> {
    let mut out = Vec::new();
    let mut e = png::Encoder::new(&mut out, 3, 2);
    e.set_color(png::ColorType::Grayscale);
    e.set_depth(png::BitDepth::Eight);
    let mut w = e.write_header().expect("header");
    w.write_image_data(&[0, 128, 255, 255, 128, 0])
        .expect("data");
    drop(w);
    out
}

/// A real 2×2 GIF.
fn gif_bytes() -> Vec<u8> {
    let mut out = Vec::new();
    {
        let palette = [0u8, 0, 0, 255, 255, 255];
        let mut e = gif::Encoder::new(&mut out, 2, 2, &palette).expect("gif");
        let mut f = gif::Frame::default();
        (f.width, f.height) = (2, 2);
        f.buffer = std::borrow::Cow::Owned(vec![0, 1, 1, 0]);
        e.write_frame(&f).expect("frame");
    }
    out
}

fn put(root: &Path, rel: &str, bytes: &[u8]) {
    let p = root.join(rel);
    fs::create_dir_all(p.parent().expect("parent")).expect("mkdir");
    fs::write(p, bytes).expect("write");
}

/// A results folder: a schema-1 experiment with a hostile name, a schema-2 one, a bench, a render
/// folder without metadata, and a claims file.
fn results(root: &Path) {
    let old_meta = String::from(
        "[raycost]\nversion = \"0.1.0\"\ngit_commit = \"abc123\"\n\n[run]\nspec_hash = \"feed\"\n\
         threads = 2\n\n[spec.base.experiment]\nname = \"x\"\nkind = \"grid\"\n\
         description = \"<script>alert('x')</script> & more\"\n\n[spec.sweep]\n\"grid.cell_width\" = [0.5, 1.0]\n"
    );
    put(
        root,
        &format!("{HOSTILE}/{HOSTILE}.meta.toml"),
        old_meta.as_bytes(),
    );
    put(
        root,
        &format!("{HOSTILE}/{HOSTILE}.csv"),
        b"point,grid.cell_width,n_s_mean,n_s_se,n_s_n,n_s_theory\n0,0.5,10.0,0.1,1000,10.1\n1,1.0,5.0,0.1,1000,7.0\n",
    );
    put(root, &format!("{HOSTILE}/{HOSTILE}.png"), &png_bytes());
    put(
        root,
        &format!("{HOSTILE}/{HOSTILE}.hist.csv"),
        b"bin,count\n0,1\n",
    );

    let mut m = crate::output::meta::Meta::begin("run", Default::default());
    m.run.spec_hash = "00ff".into();
    let spec: toml::Table = "[base.experiment]\nname = \"new\"\nkind = \"detp\"\n\n[sweep]\n"
        .parse()
        .expect("toml");
    m.spec = spec;
    put(root, "new/new.meta.toml", m.render().as_bytes());
    put(
        root,
        "new/new.csv",
        b"point,hit_mean,hit_se,hit_n,hit_theory,hit_lower,hit_upper,hit_band\n0,0.5,0.01,100,0.5,0.4,0.6,inside\n",
    );
    put(root, "new/new two.png", &png_bytes());

    put(
        root,
        "bench/bench.meta.toml",
        b"[bench]\ncpu = \"Test CPU <8 cores>\"\ncommit = \"abc\"\nthreads = 2\n",
    );
    put(
        root,
        "bench/bench.csv",
        b"engine,n,threads,rays_per_s,mismatches\ngrid,100,1,1.5e6,0\nembree,100,1,NaN,0\n",
    );
    put(root, "bench/bench.png", &png_bytes());

    put(root, "render/cornell.png", &png_bytes());
    put(root, "render/cornell.gif", &gif_bytes());
    put(root, "render/cornell.log", b"log");
    put(
        root,
        "render/broken.png",
        b"not a png at all, but long enough",
    );

    put(
        root,
        "claims.toml",
        b"[[claim]]\nclaim = \"E[N_S] < 11\"\npaper = 10.1\nsource = \"new/new.csv\"\ncolumn = \"hit\"\npoint = 0\n",
    );
}

/// Every value of `attr="…"` in the page.
fn attrs(page: &str, attr: &str) -> Vec<String> {
    let key = format!("{attr}=\"");
    page.match_indices(&key)
        .map(|(i, _)| {
            let rest = &page[i + key.len()..];
            rest[..rest.find('"').expect("closed attribute")].to_string()
        })
        .collect()
}

fn make(root: &Path, out: &Path, force: bool) -> Result<PathBuf, Error> {
    run(&ReportOptions {
        results: root.to_path_buf(),
        out: out.to_path_buf(),
        force,
    })
}

#[test]
fn every_folder_is_on_the_page_with_its_text_escaped() {
    let d = tempfile::tempdir().expect("tempdir");
    let (root, out) = (d.path().join("results"), d.path().join("results/report"));
    results(&root);
    let page = fs::read_to_string(make(&root, &out, false).expect("report")).expect("page");

    // Every folder has its section (the output folder itself is not one).
    for id in ["exp-a__b___c_", "exp-new", "exp-render", "bench", "claims"] {
        assert!(page.contains(&format!("<section id=\"{id}\">")), "{id}");
    }
    assert!(!page.contains("exp-report"));
    assert_eq!(page.matches("<section").count(), 5);

    // Hostile text arrives escaped, never as markup.
    assert!(page.contains("a &lt;b&gt;&amp;&quot;c&#39;"));
    assert!(!page.contains("<b>&"));
    assert!(!page.contains("<script"));
    assert!(page.contains("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt; &amp; more"));
    assert!(page.contains("Test CPU &lt;8 cores&gt;"));
    for tag in ["section", "table", "tr", "figure", "dl", "ul", "p"] {
        assert_eq!(
            page.matches(&format!("<{tag}>")).count() + page.matches(&format!("<{tag} ")).count(),
            page.matches(&format!("</{tag}>")).count(),
            "<{tag}> opened and closed alike"
        );
    }

    // Provenance of both schemas, claims judged, bench CPU.
    assert!(page.contains("schema 1 (older run)"));
    assert!(page.contains("<dd>schema 2</dd>"));
    assert!(page.contains("<dd>feed</dd>") && page.contains("<dd>00ff</dd>"));
    assert!(page.contains("grid.cell_width=0.5000"));
    assert!(page.contains("-20.0 SE"), "5.0 ± 0.1 vs 7.0");
    assert!(page.contains(">ok (99% CI)<"));
    assert!(page.contains(">inside<"));
    assert!(page.contains(">1500000<"), "integers stay integers");
}

#[test]
fn every_image_and_link_on_the_page_resolves() {
    let d = tempfile::tempdir().expect("tempdir");
    let (root, out) = (d.path().join("results"), d.path().join("elsewhere/page"));
    results(&root);
    let page = fs::read_to_string(make(&root, &out, false).expect("report")).expect("page");

    let srcs = attrs(&page, "src");
    // Five drawable images; the broken PNG is linked instead.
    assert_eq!(srcs.len(), 5, "{srcs:?}");
    for src in &srcs {
        let copy = out.join(unhref(src));
        assert!(copy.is_file(), "image {src} -> {}", copy.display());
        let name = copy.file_name().expect("name");
        let folder = copy.parent().and_then(Path::file_name).expect("folder");
        let original = root.join(folder).join(name);
        assert_eq!(
            fs::read(&copy).expect("copy"),
            fs::read(&original).expect("original")
        );
    }
    let hrefs: Vec<String> = attrs(&page, "href")
        .into_iter()
        .filter(|h| !h.starts_with('#') && !h.starts_with("data:"))
        .collect();
    assert!(hrefs.iter().any(|h| h.ends_with("broken.png")));
    assert!(hrefs
        .iter()
        .any(|h| h.contains("a%20%3Cb%3E%26%22c%27.hist.csv")));
    // Every CSV, the metadata, the log, the broken image and the claim's source.
    assert_eq!(hrefs.len(), 4 + 3 + 1 + 1 + 1, "{hrefs:?}");
    for h in &hrefs {
        assert!(h.starts_with("../../results/"), "{h}");
        assert!(out.join(unhref(h)).is_file(), "link {h}");
    }
}

#[test]
fn an_existing_page_is_kept_without_force_and_bad_input_is_refused() {
    let d = tempfile::tempdir().expect("tempdir");
    let (root, out) = (d.path().join("results"), d.path().join("out"));
    results(&root);
    make(&root, &out, false).expect("first");
    fs::write(out.join("index.html"), "mine").expect("write");
    let e = make(&root, &out, false).expect_err("refused");
    assert!(matches!(e, Error::Refused(_)) && e.exit_code() == 2, "{e}");
    assert_eq!(
        fs::read_to_string(out.join("index.html")).expect("kept"),
        "mine"
    );
    make(&root, &out, true).expect("--force replaces it");
    assert_ne!(
        fs::read_to_string(out.join("index.html")).expect("page"),
        "mine"
    );

    let e = make(&d.path().join("nope"), &d.path().join("o2"), false).expect_err("missing");
    assert!(matches!(e, Error::Input(_)) && e.exit_code() == 2, "{e}");
    assert!(
        !d.path().join("o2").exists(),
        "nothing created for a refused run"
    );

    fs::write(root.join("new/new.meta.toml"), "schema = 2\n[raycost").expect("write");
    let e = make(&root, &out, true).expect_err("unreadable meta");
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains("new.meta.toml: not TOML"), "{e}");
}
