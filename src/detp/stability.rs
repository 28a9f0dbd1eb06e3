//! Numerical stability of DETP wherever a scene sits and whatever its unit: a scene's
//! text with every vertex moved by an affine map, and the irradiance of the same sample points
//! (mapped alike) from the same photon streams, summed by brute force, compared with the scene
//! unmoved. Shared by the stability suite (`tests/stability.rs`) and the committed table
//! (`examples/stability.rs` → `results/stability/stability.csv`), so that both measure the same
//! thing.
//!
//! Translations, rotations and changes of unit leave the irradiance unchanged when the light is an
//! emitting surface of given radiance (as in the Cornell box: its power scales with its area, s²,
//! as the discs' areas do), so results are compared as they are.

use std::path::Path;

use glam::{DMat3, DVec3};

use crate::detp::brute;
use crate::detp::disc::Discs;
use crate::detp::photon::trace_photons;
use crate::detp::surface_points::surface_points;
use crate::lt::Scene;

/// A rigid motion and uniform scale: p ↦ centre + rotation·(s·p − centre) + translation.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    /// Added to every position after scaling and rotating.
    pub translation: DVec3,
    /// Uniform scale (a change of unit).
    pub scale: f64,
    /// Rotation about `centre` (scaled).
    pub rotation: DMat3,
    /// The point rotations turn about, in scaled coordinates.
    pub centre: DVec3,
}

impl Placement {
    /// The scene where it is.
    pub const IDENTITY: Self = Self {
        translation: DVec3::ZERO,
        scale: 1.0,
        rotation: DMat3::IDENTITY,
        centre: DVec3::ZERO,
    };

    /// A position mapped.
    pub fn apply(&self, p: DVec3) -> DVec3 {
        let q = p * self.scale;
        self.centre + self.rotation * (q - self.centre) + self.translation
    }
}

/// A scene file's text (`[[surface]]` vertices and point-light positions) with every position
/// mapped by `at`; the camera is dropped (not part of DETP).
pub fn place_scene_text(text: &str, at: &Placement) -> Result<String, String> {
    let mut t: toml::Table = text.parse().map_err(|e| format!("{e}"))?;
    let map = |v: &toml::Value| -> Result<toml::Value, String> {
        let a: Vec<f64> = v
            .as_array()
            .ok_or("a position is not an array")?
            .iter()
            .map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)))
            .collect::<Option<_>>()
            .ok_or("a coordinate is not a number")?;
        let p = at.apply(DVec3::new(a[0], a[1], a[2]));
        Ok(toml::Value::Array(vec![p.x.into(), p.y.into(), p.z.into()]))
    };
    let sections = [("surface", "vertices"), ("light", "position")];
    for (section, key) in sections {
        let Some(items) = t.get_mut(section).and_then(|s| s.as_array_mut()) else {
            continue;
        };
        for item in items {
            let Some(item) = item.as_table_mut() else {
                continue;
            };
            let Some(v) = item.get(key) else { continue };
            let mapped = match v.as_array() {
                Some(a) if a.first().is_some_and(|x| x.is_array()) => {
                    toml::Value::Array(a.iter().map(map).collect::<Result<_, _>>()?)
                }
                _ => map(v)?,
            };
            item.insert(key.into(), mapped);
        }
    }
    t.remove("camera");
    toml::to_string(&t).map_err(|e| format!("{e}"))
}

/// One sample point's result: crossing sum (integer power units), irradiance, and its Poisson SE.
pub type PointResult = (i64, f64, f64);

/// What [`measure`] needs besides the placement.
#[derive(Clone, Copy, Debug)]
pub struct Setup {
    /// Disc radius in the unmoved scene (scaled with the scene).
    pub disc_radius: f64,
    /// Sample-point spacing on the unmoved scene's surfaces.
    pub spacing: f64,
    /// Photons traced.
    pub photons: u64,
    /// Seed of the photon streams.
    pub seed: u64,
}

/// The irradiance at the unmoved scene's surface points, mapped by `at`, in the scene text `text`
/// mapped by `at`, by brute force. Points are placed on the unmoved scene so that every placement
/// measures the same spots.
pub fn measure(text: &str, at: &Placement, setup: &Setup) -> Result<Vec<PointResult>, String> {
    let file = Path::new("stability.toml");
    let base = Scene::parse(text, file).map_err(|e| e.to_string())?;
    let scene = Scene::parse(&place_scene_text(text, at)?, file).map_err(|e| e.to_string())?;
    let (pts, nrm) = surface_points(&base, setup.spacing, 0);
    let pts: Vec<DVec3> = pts.into_iter().map(|p| at.apply(p)).collect();
    let nrm: Vec<DVec3> = nrm.into_iter().map(|n| at.rotation * n).collect();
    let discs = Discs::new(pts, nrm, setup.disc_radius * at.scale).map_err(|e| e.to_string())?;
    let store = trace_photons(&scene, setup.photons, setup.seed);
    let mut acc = vec![0; discs.len()];
    brute::accumulate(&store, &discs, None, 1, &mut acc);
    let watts = |a: i64| store.scale.watts(a);
    let mean_w = store
        .segments
        .iter()
        .map(|s| watts(i64::from(s.power)))
        .sum::<f64>()
        / store.len().max(1) as f64;
    Ok(acc
        .iter()
        .enumerate()
        .map(|(i, &a)| {
            let e = discs.irradiance(i, watts(a));
            let se = (e.max(0.0) * mean_w / discs.area(i)).sqrt();
            (a, e, se)
        })
        .collect())
}

/// How a placement's results differ from the unmoved scene's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// Points whose crossing sums differ.
    pub differ: usize,
    /// Mean of z² over points, z = ΔE / √(SE_a² + SE_b²).
    pub mean_z2: f64,
    /// Largest |z|.
    pub max_z: f64,
    /// Largest |ΔE|.
    pub max_abs_diff: f64,
    /// Every crossing sum and every irradiance equal to the bit.
    pub bit_identical: bool,
}

/// `b` against `a`, point by point. (Irradiances can differ in their last bits while the sums
/// agree, where the light's area rounds differently, as a decimal translation makes it.)
pub fn compare(a: &[PointResult], b: &[PointResult]) -> Comparison {
    assert_eq!(a.len(), b.len(), "the same points");
    let mut c = Comparison {
        differ: 0,
        mean_z2: 0.0,
        max_z: 0.0,
        max_abs_diff: 0.0,
        bit_identical: true,
    };
    for (x, y) in a.iter().zip(b) {
        c.differ += usize::from(x.0 != y.0);
        c.bit_identical &= x.0 == y.0 && x.1.to_bits() == y.1.to_bits();
        let se = x.2.hypot(y.2);
        let z = if se > 0.0 { (x.1 - y.1) / se } else { 0.0 };
        c.mean_z2 += z * z;
        c.max_z = c.max_z.max(z.abs());
        c.max_abs_diff = c.max_abs_diff.max((x.1 - y.1).abs());
    }
    c.mean_z2 /= a.len().max(1) as f64;
    c
}

/// Mean irradiance over points and its SE (independent points).
pub fn mean_and_se(r: &[PointResult]) -> (f64, f64) {
    let n = r.len().max(1) as f64;
    let mean = r.iter().map(|p| p.1).sum::<f64>() / n;
    let se = r.iter().map(|p| p.2 * p.2).sum::<f64>().sqrt() / n;
    (mean, se)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placement_moves_vertices_and_lights_and_drops_the_camera() {
        let text = "[[surface]]\nname = \"f\"\nkind = \"quad\"\nvertices = [[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0]]\n[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\npower = 1.0\n[camera]\nposition = [0, 0, 5]\n";
        let at = Placement {
            translation: DVec3::new(10.0, 0.0, 0.0),
            scale: 2.0,
            ..Placement::IDENTITY
        };
        let t: toml::Table = place_scene_text(text, &at).unwrap().parse().unwrap();
        assert!(t.get("camera").is_none());
        let v = t["surface"][0]["vertices"][2].as_array().unwrap();
        assert_eq!(v[0].as_float(), Some(12.0));
        assert_eq!(t["light"][0]["position"][1].as_float(), Some(2.0));
    }
}
