//! The stability table: the Cornell box translated by 10⁰ … 10¹² of its size, scaled by
//! 10⁻⁹ … 10⁶ (and by powers of two), and rotated, each against the box where it is — the same
//! photon streams, the same sample points moved alike, crossings summed by brute force
//! ([`raycost::detp::stability`], which `tests/stability.rs` asserts on).
//!
//! ```text
//! cargo run --release --example stability -- [PHOTONS] [OUT]
//! ```
//! Defaults: 100 000 photons, `results/stability/stability.csv`. Placements that `raycost check`
//! refuses (fewer than 20 bits of f64 left for d, `raycost::lt::precision`) are still measured,
//! to show what the refusal prevents, and say so in `refused` and `message`.

use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};
use raycost::detp::stability::{compare, mean_and_se, measure, place_scene_text, Placement, Setup};
use raycost::lt::Scene;

/// The Cornell box's size (its bounding box's diagonal, mm) and centre.
const SIZE: f64 = 960.7;
const CENTRE: DVec3 = DVec3::new(278.0, 274.4, 279.6);

fn variants() -> Vec<(String, Placement)> {
    let id = Placement::IDENTITY;
    let mut v = vec![("base".to_string(), id)];
    for k in 0..=12 {
        let t = 10f64.powi(k) * SIZE;
        let translation = DVec3::new(t, -0.5 * t, 0.25 * t);
        v.push((
            format!("translate 1e{k} S"),
            Placement { translation, ..id },
        ));
    }
    for k in -9..=6 {
        let scale = 10f64.powi(k);
        v.push((format!("scale 1e{k}"), Placement { scale, ..id }));
    }
    for k in [-30, -10, 10, 20] {
        let scale = 2f64.powi(k);
        v.push((format!("scale 2^{k}"), Placement { scale, ..id }));
    }
    for (axis, deg) in [
        (DVec3::Y, 90.0),
        (DVec3::X, 180.0),
        (DVec3::new(1.0, 2.0, 3.0), 37.0),
    ] {
        let rotation = DMat3::from_axis_angle(axis.normalize(), f64::to_radians(deg));
        let name = format!("rotate {deg} deg about ({} {} {})", axis.x, axis.y, axis.z);
        v.push((
            name,
            Placement {
                rotation,
                centre: CENTRE,
                ..id
            },
        ));
    }
    v
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let photons = args.first().map_or(Ok(100_000), |s| s.parse())?;
    let out = args.get(1).map_or_else(
        || PathBuf::from("results/stability/stability.csv"),
        PathBuf::from,
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("experiments/scenes/cornell.toml"))?;
    let setup = Setup {
        disc_radius: 20.0,
        spacing: 60.0,
        photons,
        seed: 7,
    };
    let base = measure(&text, &Placement::IDENTITY, &setup)?;
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let mut w = csv::Writer::from_path(&out)?;
    w.write_record([
        "variant",
        "translation",
        "scale",
        "rotation",
        "points",
        "photons",
        "disc_radius",
        "bits_for_d",
        "irradiance_mean",
        "se",
        "max_abs_diff",
        "points_differ",
        "mean_z2",
        "max_z",
        "bit_identical",
        "refused",
        "message",
    ])?;
    for (name, at) in variants() {
        let d = setup.disc_radius * at.scale;
        let placed = Scene::parse(&place_scene_text(&text, &at)?, Path::new("cornell.toml"))?;
        let precision = placed.precision();
        let refusal = precision.check(d).err();
        let got = measure(&text, &at, &setup)?;
        let c = compare(&base, &got);
        let (mean, se) = mean_and_se(&got);
        let rotation = if at.rotation == DMat3::IDENTITY {
            "none".to_string()
        } else {
            name.trim_start_matches("rotate ").to_string()
        };
        w.write_record([
            name.clone(),
            format!("{:e}", at.translation.length()),
            format!("{:e}", at.scale),
            rotation,
            got.len().to_string(),
            photons.to_string(),
            format!("{d:e}"),
            format!("{:.1}", precision.bits(d)),
            format!("{mean:.6e}"),
            format!("{se:.3e}"),
            format!("{:.3e}", c.max_abs_diff),
            c.differ.to_string(),
            format!("{:.4}", c.mean_z2),
            format!("{:.2}", c.max_z),
            c.bit_identical.to_string(),
            refusal.is_some().to_string(),
            refusal.unwrap_or_default(),
        ])?;
        eprintln!(
            "{name}: mean z² {:.4}, {} points differ",
            c.mean_z2, c.differ
        );
    }
    w.flush()?;
    eprintln!("wrote {}", out.display());
    Ok(())
}
