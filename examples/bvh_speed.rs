//! Rays per second of the light-transport BVH (first and second hit) against the `bvh` crate
//! (SAH build, SIMD ray–box tests; its `traverse` returns the triangles whose boxes the ray meets,
//! which are then tested for the two nearest hits) and against testing every triangle, on the
//! Cornell box and on a generated OBJ mesh of ≥ 10⁵ triangles (a tessellated sphere written to a
//! temporary folder and read back through the scene format and `tobj`). Every answer of both BVHs
//! is checked against brute force on the rays brute force traces.
//!
//! `cargo run --release --example bvh_speed`

use std::time::Instant;

use bvh::aabb::{Aabb, Bounded};
use bvh::bounding_hierarchy::BHShape;
use glam::DVec3;
use nalgebra::{Point3, Vector3};
use raycost::lt::bvh::{two_nearest_brute, TwoNearest};
use raycost::lt::shapes::Triangle;
use raycost::lt::Scene;

/// A triangle as the `bvh` crate sees it.
struct CrateTri {
    tri: Triangle,
    id: u32,
    node: usize,
}

impl Bounded<f64, 3> for CrateTri {
    fn aabb(&self) -> Aabb<f64, 3> {
        let (lo, hi) = self.tri.bounds();
        Aabb::with_bounds(Point3::new(lo.x, lo.y, lo.z), Point3::new(hi.x, hi.y, hi.z))
    }
}

impl BHShape<f64, 3> for CrateTri {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}
use raycost::sample::{directions::uniform_direction, rng::stream};

fn cpu() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

fn measure(name: &str, scene: &Scene, eye: DVec3, rays: usize, brute_rays: usize) {
    let mut rng = stream(&[0xb0b, rays as u64]);
    let dirs: Vec<DVec3> = (0..rays).map(|_| uniform_direction(&mut rng)).collect();
    let t0 = Instant::now();
    let mut hits = 0usize;
    let mut answers = Vec::with_capacity(rays);
    for d in &dirs {
        let (h, t2) = scene.first_two_hits(eye, *d, 1e-9, None);
        hits += usize::from(h.is_some());
        answers.push((h.map(|h| h.t), t2));
    }
    let bvh_s = t0.elapsed().as_secs_f64();
    // The bvh crate over the same triangles.
    let mut shapes: Vec<CrateTri> = scene
        .triangles
        .iter()
        .enumerate()
        .map(|(i, t)| CrateTri {
            tri: *t,
            id: i as u32,
            node: 0,
        })
        .collect();
    let tb = Instant::now();
    let crate_bvh = bvh::bvh::Bvh::build(&mut shapes);
    let crate_build_s = tb.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let mut crate_answers = Vec::with_capacity(rays);
    for d in &dirs {
        let ray = bvh::ray::Ray::new(
            Point3::new(eye.x, eye.y, eye.z),
            Vector3::new(d.x, d.y, d.z),
        );
        let mut best = TwoNearest::default();
        for s in crate_bvh.traverse(&ray, &shapes) {
            if let Some(t) = s.tri.intersect(eye, *d, 1e-9) {
                best.offer(t, s.id);
            }
        }
        crate_answers.push((
            best.first.0.is_finite().then_some(best.first.0),
            best.second.0,
        ));
    }
    let crate_s = t2.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let (mut mismatches, mut crate_mismatches) = (0, 0);
    // Only t is compared: the tie order (ranks) does not matter here.
    let ranks: Vec<u32> = (0..scene.triangles.len() as u32).collect();
    for ((d, a), c) in dirs
        .iter()
        .zip(&answers)
        .zip(&crate_answers)
        .take(brute_rays)
    {
        let b = two_nearest_brute(&scene.triangles, &ranks, eye, *d, 1e-9, u32::MAX);
        let first = b.first.0.is_finite().then_some(b.first.0);
        mismatches += usize::from((first, b.second.0) != *a);
        crate_mismatches += usize::from((first, b.second.0) != *c);
    }
    let brute_s = t1.elapsed().as_secs_f64();
    println!(
        "{name}: {} triangles, {hits} of {rays} rays hit\n  raycost BVH {:.3e} rays/s ({mismatches} mismatches)\n  \
         bvh crate   {:.3e} rays/s, build {crate_build_s:.3} s ({crate_mismatches} mismatches)\n  \
         brute force {:.3e} rays/s (checked {brute_rays} rays)",
        scene.triangles.len(),
        rays as f64 / bvh_s,
        rays as f64 / crate_s,
        brute_rays as f64 / brute_s,
    );
}

fn main() -> anyhow::Result<()> {
    println!("CPU: {}, one thread", cpu());
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let cornell = Scene::load(&root.join("experiments/scenes/cornell.toml"))?;
    measure(
        "Cornell box",
        &cornell,
        DVec3::new(278.0, 274.0, 280.0),
        1_000_000,
        100_000,
    );

    // A UV sphere of 2·n·n triangles, n = 230: 105 800 triangles.
    let dir = tempfile_dir()?;
    let n = 230usize;
    let mut obj = String::new();
    for i in 0..=n {
        let th = std::f64::consts::PI * i as f64 / n as f64;
        for j in 0..n {
            let ph = std::f64::consts::TAU * j as f64 / n as f64;
            obj.push_str(&format!(
                "v {} {} {}\n",
                th.sin() * ph.cos(),
                th.cos(),
                th.sin() * ph.sin()
            ));
        }
    }
    for i in 0..n {
        for j in 0..n {
            let a = i * n + j + 1;
            let b = i * n + (j + 1) % n + 1;
            let (c, d) = (a + n, b + n);
            obj.push_str(&format!("f {a} {b} {d}\nf {a} {d} {c}\n"));
        }
    }
    std::fs::write(dir.join("sphere.obj"), obj)?;
    std::fs::write(
        dir.join("mesh.toml"),
        "[[surface]]\nkind = \"obj\"\npath = \"sphere.obj\"\nalbedo = 0.5\n\n[[light]]\nkind = \"point\"\nposition = [0, 0, 0]\npower = 1\n",
    )?;
    let mesh = Scene::load(&dir.join("mesh.toml"))?;
    for w in &mesh.warnings {
        println!("  {w}");
    }
    measure(
        "tessellated sphere (OBJ)",
        &mesh,
        DVec3::new(0.1, 0.2, -0.3),
        1_000_000,
        1_000,
    );
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}

fn tempfile_dir() -> std::io::Result<std::path::PathBuf> {
    let d = std::env::temp_dir().join(format!("raycost-bvh-{}", std::process::id()));
    std::fs::create_dir_all(&d)?;
    Ok(d)
}
