//! The light-transport rows of `raycost bench` alone: photon tracing and reference path tracing on
//! the Cornell box, the BART kitchen and museum, the exact core against Embree (feature `embree`),
//! one thread, alternating rounds. `cargo run --release --features embree --example lt_speed [quick]`

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("profile") {
        return profile(&args[2], &args[3]);
    }
    let quick = args.iter().any(|a| a == "quick");
    let (rows, warnings) = raycost::bench::lt::run(quick)?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    println!(
        "{:<8} {:<18} {:>7} {:>10} {:>9} {:>8} {:>5} {:>11} {:>7}",
        "scene", "engine", "tris", "rays", "ns/ray", "/embree", "mism", "disagree", "path"
    );
    for r in rows {
        println!(
            "{:<8} {:<18} {:>7} {:>10} {:>9.1} {:>8.3} {:>5} {:>11} {:>7}",
            r.scene,
            r.engine,
            r.triangles,
            r.rays.iter().sum::<u64>(),
            1e9 / r.rays_per_s(),
            r.embree_ratio,
            r.mismatches,
            format!("{}/{}", r.embree_disagree, r.checked),
            r.bvh_path
        );
    }
    Ok(())
}

/// `lt_speed profile SCENE photons|paths`: one workload with the exact core on one thread, for
/// callgrind (`valgrind --tool=callgrind`).
fn profile(name: &str, what: &str) -> anyhow::Result<()> {
    use raycost::bench::lt::{find, SCENES};
    let rel = SCENES
        .iter()
        .find(|s| s.0 == name)
        .ok_or_else(|| anyhow::anyhow!("no scene {name}"))?
        .1;
    let path = find(rel).ok_or_else(|| anyhow::anyhow!("{rel} not found"))?;
    let mut scene = raycost::lt::Scene::load(&path).map_err(|e| anyhow::anyhow!("{e}"))?;
    scene.set_tau(0.0);
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()?;
    #[cfg(feature = "embree")]
    let embree = raycost::embree::triangles::EmbreeTriangles::build(&scene)?;
    let rays = match what {
        "photons" => run(&scene, &scene, true),
        "paths" => run(&scene, &scene, false),
        #[cfg(feature = "embree")]
        "photons-embree" => run(&scene, &embree, true),
        #[cfg(feature = "embree")]
        "paths-embree" => run(&scene, &embree, false),
        _ => anyhow::bail!("photons, paths, photons-embree or paths-embree"),
    };
    println!("{name} {what}: {rays} rays");
    Ok(())
}

/// 20 000 photons, or 32 samples at 32 points, with `caster`: the rays cast.
fn run<C: raycost::lt::cast::Caster>(scene: &raycost::lt::Scene, caster: &C, photons: bool) -> u64 {
    if photons {
        raycost::detp::photon::trace_photons_with(scene, caster, 20_000, 1)
            .segments
            .len() as u64
    } else {
        let tris = scene.triangles.iter().take(32);
        let pts: Vec<glam::DVec3> = tris
            .clone()
            .map(|t| t.centroid() + t.normal() * 1e-3)
            .collect();
        let nrm: Vec<glam::DVec3> = tris.map(|t| t.normal()).collect();
        raycost::lt::reference::irradiance_with(scene, caster, &pts, &nrm, 32, 1).1
    }
}
