//! DETP for indirect light (`detp.direct = "nee"`): the ray store's segments after the
//! first bounce only, so that DETP estimates the indirect irradiance and next-event estimation
//! ([`crate::lt::direct`]) adds the direct part at each point: E = E_direct(NEE) + E_indirect(DETP).
//!
//! Why the split is exact: a segment with `bounce = 0` leaves a light, so the power it carries across
//! a disc is direct light; every other segment leaves a surface after a reflection, so it is indirect
//! light. A disc's sum over the whole store is, in integers, the sum over the bounce-0 segments plus
//! the sum over the others, with no rounding (the tests check it bit for bit). Every DETP engine reads
//! the same filtered store, so the engines still agree bit for bit; the direct part is one number per
//! point, the same for every engine.
//!
//! Two forms, for two uses:
//! - [`indirect_store`] drops the bounce-0 segments: fewer segments, so every engine is faster (kind
//!   `detp`), and the photon map over it estimates indirect light from indirect impacts only (a
//!   zero-power impact among the k nearest would bias its density);
//! - [`mute_direct`] keeps every segment and sets the power of the bounce-0 ones to 0: photon ids,
//!   offsets and geometry stay, so the quasi-static layer still finds every photon a moving object
//!   touches — a photon whose *first* segment the object now blocks must be retraced, though that
//!   segment carries no counted power — and a retraced photon muted the same way replaces its old
//!   segments exactly. Engines add 0 for a muted segment, so their sums equal [`indirect_store`]'s.

use rayon::prelude::*;

use super::store::{Segment, SegmentStore};

/// Is `s` indirect light (it left a surface after at least one reflection)?
#[inline]
pub fn is_indirect(s: &Segment) -> bool {
    s.bounce >= 1
}

/// The store of `store`'s indirect segments, in the same order and with the same power scale; its
/// photon offsets (when `store` has them) index the kept segments of each photon.
pub fn indirect_store(store: &SegmentStore) -> SegmentStore {
    let segments: Vec<Segment> = store
        .segments
        .iter()
        .filter(|s| is_indirect(s))
        .copied()
        .collect();
    let mut out = SegmentStore::new(segments, store.scale);
    if !store.photon_start.is_empty() {
        // Photon p's kept segments start after the kept segments of photons 0..p.
        let mut kept = 0u32;
        out.photon_start = Vec::with_capacity(store.photon_start.len());
        out.photon_start.push(0);
        for p in 0..store.photon_start.len() - 1 {
            kept += store.photon(p).iter().filter(|s| is_indirect(s)).count() as u32;
            out.photon_start.push(kept);
        }
    }
    out
}

/// Sets the power of every direct (bounce-0) segment of `segments` to 0, keeping the segments.
pub fn mute_direct(segments: &mut [Segment]) {
    segments.par_iter_mut().for_each(|s| {
        if !is_indirect(s) {
            s.power = 0;
        }
    });
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use glam::DVec3;

    use super::*;
    use crate::detp::brute;
    use crate::detp::disc::Discs;
    use crate::detp::fixed::Acc;
    use crate::detp::photon::trace_photons;
    use crate::lt::direct::direct_irradiance;
    use crate::lt::direct::tests::FURNACE;
    use crate::lt::reference;
    use crate::lt::reference::tests::{rectangle, scene};

    /// Brute-force DETP sums of `store` at `discs`.
    fn sums(store: &SegmentStore, discs: &Discs) -> Vec<Acc> {
        let mut acc = vec![0; discs.len()];
        brute::accumulate(store, discs, None, 1, &mut acc);
        acc
    }

    /// Every photon's kept segments, in order, are its bounce ≥ 1 segments; muted segments weigh
    /// nothing; and a disc's sum over the whole store is its bounce-0 sum plus its indirect sum, in
    /// integers, bit for bit, whichever form carries the indirect part.
    #[test]
    fn the_split_is_exact_and_keeps_each_photons_segments() {
        let s = rectangle(0.5);
        let store = trace_photons(&s, 20_000, 4);
        let ind = indirect_store(&store);
        assert!(!ind.is_empty() && ind.len() < store.len());
        assert_eq!(ind.photon_start.len(), store.photon_start.len());
        for p in 0..store.photon_start.len() - 1 {
            let want: Vec<Segment> = store
                .photon(p)
                .iter()
                .filter(|s| s.bounce >= 1)
                .copied()
                .collect();
            assert_eq!(ind.photon(p), &want[..], "photon {p}");
        }
        let mut muted = store.clone();
        mute_direct(&mut muted.segments);
        let mut direct = store.clone();
        direct.segments.retain(|s| s.bounce == 0);
        let pts: Vec<DVec3> = (0..50)
            .map(|i| DVec3::new(-2.0 + 0.08 * i as f64, 0.0, 0.3 - 0.01 * i as f64))
            .collect();
        let discs = Discs::new(pts, vec![DVec3::Y; 50], 0.2).expect("discs");
        let (all, d, i, m) = (
            sums(&store, &discs),
            sums(&direct, &discs),
            sums(&ind, &discs),
            sums(&muted, &discs),
        );
        assert_eq!(i, m, "muted and dropped give the same sums");
        for k in 0..discs.len() {
            assert_eq!(all[k], d[k] + i[k], "disc {k}");
        }
        assert!(i.iter().any(|&x| x > 0) && d.iter().any(|&x| x > 0));
    }

    /// DETP's irradiance at discs from brute-force sums, and its Poisson SE (segments of equal power
    /// w: SE = √(E·w/πd²)).
    fn detp(store: &SegmentStore, discs: &Discs, w: f64) -> Vec<(f64, f64)> {
        let area = PI * discs.radius * discs.radius;
        sums(store, discs)
            .into_iter()
            .map(|a| {
                let e = store.scale.watts(a) / area;
                (e, (e.max(0.0) * w / area).sqrt())
            })
            .collect()
    }

    /// The closed furnace: NEE gives the direct π·L_e, DETP over the indirect store the rest,
    /// π·L_e·α/(1 − α), and their sum the closed form π·L_e/(1 − α), within DETP's SE.
    #[test]
    fn in_the_furnace_nee_direct_plus_detp_indirect_is_the_closed_form() {
        let s = scene(FURNACE);
        let photons = 200_000;
        let store = trace_photons(&s, photons, 11);
        let ind = indirect_store(&store);
        // 40 points spread over the sphere (Fibonacci lattice), facing in.
        let pts: Vec<DVec3> = (0..40)
            .map(|i| {
                let z = 1.0 - (2.0 * i as f64 + 1.0) / 40.0;
                let phi = i as f64 * PI * (3.0 - 5f64.sqrt());
                let r = (1.0 - z * z).sqrt();
                DVec3::new(r * phi.cos(), r * phi.sin(), z)
            })
            .collect();
        let normals: Vec<DVec3> = pts.iter().map(|p| -*p).collect();
        let discs = Discs::new(pts.clone(), normals.clone(), 0.08).expect("discs");
        let w = s.total_power() / photons as f64;
        let indirect = detp(&ind, &discs, w);
        let (direct, _) = direct_irradiance(&s, &pts, &normals, 16, 5, 0);
        let (le, alpha) = (1.0, 0.5);
        let (want_ind, want) = (PI * le * alpha / (1.0 - alpha), PI * le / (1.0 - alpha));
        let (mut z2_ind, mut z2_tot) = (0.0, 0.0);
        for (d, &(e, se)) in direct.iter().zip(&indirect) {
            assert!((d.mean - PI * le).abs() < 1e-9, "{d:?}");
            z2_ind += ((e - want_ind) / se).powi(2);
            z2_tot += ((d.mean + e - want) / se).powi(2);
        }
        let n = indirect.len() as f64;
        println!(
            "furnace: mean z² indirect {:.2}, total {:.2}",
            z2_ind / n,
            z2_tot / n
        );
        assert!((0.5..1.6).contains(&(z2_ind / n)), "{}", z2_ind / n);
        assert!((0.5..1.6).contains(&(z2_tot / n)), "{}", z2_tot / n);
    }

    /// The Lambertian rectangle over a reflecting floor: NEE direct (Lambert's formula) plus DETP
    /// indirect agrees with the path-traced reference total within their combined SE.
    #[test]
    fn under_a_lamp_nee_direct_plus_detp_indirect_is_the_reference_total() {
        let s = rectangle(0.5);
        let photons = 400_000;
        let store = trace_photons(&s, photons, 2);
        let ind = indirect_store(&store);
        let pts: Vec<DVec3> = (0..12)
            .map(|i| DVec3::new(-1.1 + 0.2 * i as f64, 0.0, 0.1 * (i % 3) as f64))
            .collect();
        let normals = vec![DVec3::Y; pts.len()];
        let discs = Discs::new(pts.clone(), normals.clone(), 0.15).expect("discs");
        let w = s.total_power() / photons as f64;
        let indirect = detp(&ind, &discs, w);
        let (direct, _) = direct_irradiance(&s, &pts, &normals, 4096, 5, 0);
        let truth = reference::irradiance(&s, &pts, &normals, 8192, 9);
        let mut z2 = 0.0;
        for ((d, &(e, se)), t) in direct.iter().zip(&indirect).zip(&truth) {
            assert!(
                e > 0.0 && e < 0.2 * d.mean,
                "indirect {e} against direct {}",
                d.mean
            );
            let sd = (d.se * d.se + se * se + t.se * t.se).sqrt();
            let z = (d.mean + e - t.mean) / sd;
            println!(
                "{:.5} + {e:.5} vs {:.5} ± {:.5}: z = {z:.2}",
                d.mean, t.mean, t.se
            );
            assert!(z.abs() < 4.0, "z = {z}");
            z2 += z * z;
        }
        let chi = z2 / pts.len() as f64;
        assert!(chi < 2.5, "mean z² {chi}");
    }
}
