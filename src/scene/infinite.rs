//! Tracing rays through the infinite Poisson scene: one entry point for experiments and the bench,
//! which picks the engine that realises the scene.
//!
//! - `rays_per_scene = 1`: every ray has its own realisation, drawn only in the reach boxes of the
//!   cells it walks ([`super::tube`]), from one stream per ray, by the gaps between occupied slabs
//!   (or, for comparison, a count per slab: [`Walk::slabs`]).
//! - `rays_per_scene > 1`: rays of a group share one realisation, generated block by block where
//!   they go ([`super::lazy`]), so every ray sees the same spheres wherever their walks meet.
//!
//! Both are the same marked Poisson process; the tests hold them to the same counts. Streams are
//! keyed by `[scene key…, group]`, the group being the ray's index in its batch when groups are
//! single rays, so results never depend on threads or sharding.

use glam::DVec3;

use super::lazy::{LazyCache, LazyScene};
use super::tube::{SlabDraw, TubeCache, TubeScene};
use super::{RadiusClass, RadiusDraw};
use crate::geom::Ray;
use crate::grid::mailbox::Mailbox;
use crate::grid::{trace, GridFrame, TraceCounts};

/// What an infinite scene is: intensity, radius classes and how radii are drawn.
#[derive(Clone, Copy, Debug)]
pub struct InfiniteScene<'a> {
    /// Intensity ρ (centres per unit volume).
    pub intensity: f64,
    /// Radius classes (fractions α_i and radius laws).
    pub classes: &'a [RadiusClass],
    /// Radii drawn per sphere or per realisation.
    pub draw: RadiusDraw,
}

/// How one batch is traced.
#[derive(Clone, Copy, Debug)]
pub struct Walk {
    /// Cell width; the grid sits at the origin.
    pub cell_width: f64,
    /// Coordinate magnitude of the eyes (for the listing pad).
    pub eye_magnitude: f64,
    /// Rays per realisation (1 = independent rays).
    pub rays_per_scene: usize,
    /// Mailboxing (skip spheres already tested by this ray).
    pub mailbox: bool,
    /// Walk cut-off.
    pub max_steps: u32,
    /// How the per-ray engine draws its slabs' counts (`rays_per_scene = 1` only; shared
    /// realisations are drawn in blocks either way).
    pub slabs: SlabDraw,
}

/// Per-thread buffers, reused batch after batch.
#[derive(Debug, Default)]
pub struct InfiniteCaches {
    lazy: LazyCache,
    tube: TubeCache,
    mailbox: Mailbox,
}

impl InfiniteScene<'_> {
    /// Traces `rays` (one batch) and appends their counts to `out`; group `g` of the batch is
    /// realised from the stream keyed `[key…, g]`. Returns the spheres generated.
    pub fn trace_batch(
        &self,
        walk: &Walk,
        key: &[u64],
        rays: &[Ray],
        caches: &mut InfiniteCaches,
        out: &mut Vec<TraceCounts>,
    ) -> u64 {
        let frame = GridFrame {
            origin: DVec3::ZERO,
            width: walk.cell_width,
            dims: None,
        };
        let mut group_key = key.to_vec();
        group_key.push(0);
        let last = group_key.len() - 1;
        let mb = &mut caches.mailbox;
        if walk.rays_per_scene <= 1 {
            let scene = TubeScene::new(self.intensity, self.classes, self.draw, walk.cell_width)
                .with_slabs(walk.slabs);
            let mut lists = scene.cells(frame, walk.eye_magnitude, &mut caches.tube);
            for (g, ray) in rays.iter().enumerate() {
                group_key[last] = g as u64;
                // The fused tracer: `trace` over `lists`, bit for bit, whatever `walk.mailbox`.
                out.push(lists.trace_ray(&group_key, ray, walk.max_steps));
            }
            return lists.generated() as u64;
        }
        let mut generated = 0;
        for (g, group) in rays.chunks(walk.rays_per_scene).enumerate() {
            group_key[last] = g as u64;
            let scene = LazyScene::new(
                self.intensity,
                self.classes,
                self.draw,
                walk.cell_width,
                &group_key,
            );
            let mut lists = scene.cells(frame, walk.eye_magnitude, &mut caches.lazy);
            out.extend(
                group
                    .iter()
                    .map(|r| trace(&mut lists, r, mb, walk.mailbox, walk.max_steps)),
            );
            generated += lists.generated() as u64;
        }
        generated
    }
}
