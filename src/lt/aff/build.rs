//! The AFF scene builder: the block stack (static transforms, animated nodes), materials, the
//! triangles each block emits (static or belonging to a mover part), tessellated spheres and cones,
//! and [`Loader::finish`], which resolves animated nodes into [`AffScene`] movers.

use std::collections::HashMap;
use std::path::PathBuf;
use std::rc::Rc;

use glam::{DAffine3, DMat3, DVec3};

use super::{AffMover, AffScene, AnimatedPatch, MoverPart};
use crate::lt::shapes::Triangle;
use crate::lt::spline::{axis_angle_deg, KbTransform, Node};
use crate::lt::Surface;

/// Segments around a tessellated sphere or cone.
pub(super) const ROUND: usize = 24;

// Loader

#[derive(Clone, Debug)]
pub(super) enum Link {
    Fixed(DAffine3),
    Anim(String),
}

pub(super) struct PartBuild {
    pub(super) mover: usize,
    pub(super) chain: Vec<Link>,
    pub(super) tris: Vec<Triangle>,
}

pub(super) struct PatchBuild {
    pub(super) surface: u32,
    pub(super) times: Vec<f64>,
    pub(super) vertices: Vec<[DVec3; 3]>,
    pub(super) part: Option<usize>,
}

#[derive(Clone, Copy)]
pub(super) struct Frame {
    /// From this block's coordinates to the innermost animated node's (or world).
    pub(super) local: DAffine3,
    /// The mover part geometry here belongs to (None: static).
    pub(super) part: Option<usize>,
    /// Where its `{` is, for "unterminated" errors.
    pub(super) open: (usize, usize),
    /// Directive that opened it.
    pub(super) key: &'static str,
}

#[derive(Default)]
pub(super) struct Counts {
    pub(super) degenerate: usize,
    pub(super) textured: usize,
    pub(super) cones: usize,
    pub(super) spheres: usize,
    pub(super) visibility: usize,
    pub(super) lights_in_movers: usize,
    pub(super) duplicate_keys: Vec<String>,
    pub(super) unsorted: Vec<String>,
}

pub(super) struct Loader {
    pub(super) root: PathBuf,
    pub(super) out: AffScene,
    pub(super) stack: Vec<Frame>,
    pub(super) parts: Vec<PartBuild>,
    pub(super) mover_names: Vec<String>,
    pub(super) patches: Vec<PatchBuild>,
    pub(super) anims: HashMap<String, KbTransform>,
    pub(super) material: Option<u32>,
    pub(super) counts: Counts,
    pub(super) cache: HashMap<PathBuf, Rc<[u8]>>,
    /// Inclusions read so far, repeats counted (bounded by [`MAX_INCLUSIONS`]).
    pub(super) inclusions: u64,
    /// Bytes of scene text read so far, top file and every inclusion, repeats counted (bounded by
    /// [`MAX_SCENE_BYTES`]).
    pub(super) bytes_read: u64,
}

/// Inclusions (`i` directives followed, a file included twice counted twice) one scene may make.
/// BART's robot makes 835 (the kitchen 186, the museum 6); a file that includes the next twice,
/// 40 deep, makes 2⁴¹ — without a bound it ran for ever, growing past 1.4 GB.
pub(super) const MAX_INCLUSIONS: u64 = 100_000;

/// Bytes of scene text one scene may expand to, its includes counted every time they are included.
/// BART's robot expands to 11.2 MB (the kitchen 5.8 MB); 128 MiB of text is a few million
/// triangles, a few hundred MB once built.
pub(super) const MAX_SCENE_BYTES: u64 = 128 << 20;

/// Counts above this are refused (a corrupt count would otherwise allocate wildly).
pub(super) const MAX_COUNT: usize = 1 << 26;

pub(super) fn trs(scale: DVec3, axis: DVec3, angle_deg: f64, trans: DVec3) -> DAffine3 {
    DAffine3 {
        matrix3: DMat3::from_quat(axis_angle_deg(axis, angle_deg)) * DMat3::from_diagonal(scale),
        translation: trans,
    }
}

pub(super) fn mean(c: DVec3) -> f64 {
    (c.x + c.y + c.z) / 3.0
}

impl Loader {
    pub(super) fn new(root: PathBuf) -> Self {
        Loader {
            root,
            out: AffScene::default(),
            stack: vec![Frame {
                local: DAffine3::IDENTITY,
                part: None,
                open: (0, 0),
                key: "",
            }],
            parts: Vec::new(),
            mover_names: Vec::new(),
            patches: Vec::new(),
            anims: HashMap::new(),
            material: None,
            counts: Counts::default(),
            cache: HashMap::new(),
            inclusions: 0,
            bytes_read: 0,
        }
    }

    pub(super) fn top(&self) -> Frame {
        self.stack[self.stack.len() - 1]
    }

    pub(super) fn surface(&mut self) -> u32 {
        if let Some(m) = self.material {
            return m;
        }
        let id = self.out.surfaces.len() as u32;
        self.out.surfaces.push(Surface {
            name: "default material (geometry before any fm/f)".into(),
            albedo: 0.5,
            emission: 0.0,
        });
        self.material = Some(id);
        id
    }

    pub(super) fn add_material(&mut self, albedo: f64, name: &str, at: (usize, usize)) {
        let id = self.out.surfaces.len() as u32;
        let albedo = if albedo.is_finite() {
            albedo.clamp(0.0, 0.95)
        } else {
            0.0
        };
        self.out.surfaces.push(Surface {
            name: format!("material {id} ({name}:{})", at.0),
            albedo,
            emission: 0.0,
        });
        self.material = Some(id);
    }

    /// A triangle in the current block's coordinates.
    pub(super) fn emit(&mut self, v: [DVec3; 3]) {
        let f = self.top();
        let surface = self.surface();
        let t = Triangle {
            v: v.map(|p| f.local.transform_point3(p)),
            surface,
        };
        if t.degenerate() {
            self.counts.degenerate += 1;
            return;
        }
        match f.part {
            None => self.out.triangles.push(t),
            Some(p) => self.parts[p].tris.push(t),
        }
    }

    /// A triangle whose winding is fixed so that its normal points away from `inside`
    /// (towards it if `flip`).
    pub(super) fn emit_oriented(&mut self, mut v: [DVec3; 3], inside: DVec3, flip: bool) {
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let c = (v[0] + v[1] + v[2]) / 3.0;
        if (n.dot(c - inside) < 0.0) != flip {
            v.swap(1, 2);
        }
        self.emit(v);
    }

    pub(super) fn sphere(&mut self, c: DVec3, r: f64) {
        let inside = r < 0.0;
        let r = r.abs();
        let (nu, nv) = (ROUND, ROUND / 2);
        let p = |i: usize, j: usize| {
            let th = std::f64::consts::TAU * i as f64 / nu as f64;
            let ph = std::f64::consts::PI * j as f64 / nv as f64;
            c + r * DVec3::new(ph.sin() * th.cos(), ph.cos(), ph.sin() * th.sin())
        };
        for i in 0..nu {
            for j in 0..nv {
                let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                if j > 0 {
                    self.emit_oriented([a, b, cc], c, inside);
                }
                if j + 1 < nv {
                    self.emit_oriented([a, cc, d], c, inside);
                }
            }
        }
    }

    pub(super) fn cone(&mut self, b: DVec3, r0: f64, a: DVec3, r1: f64) {
        // NFF: both radii negative = only the inside is visible.
        let inside = r0 < 0.0;
        let (r0, r1) = (r0.abs(), r1.abs());
        let d = (a - b).normalize_or_zero();
        if d == DVec3::ZERO {
            self.counts.degenerate += 1;
            return;
        }
        let (u, w) = d.any_orthonormal_pair();
        let ring = |c: DVec3, r: f64, i: usize| {
            let th = std::f64::consts::TAU * i as f64 / ROUND as f64;
            c + r * (th.cos() * u + th.sin() * w)
        };
        for i in 0..ROUND {
            let (b0, b1, a0, a1) = (
                ring(b, r0, i),
                ring(b, r0, i + 1),
                ring(a, r1, i),
                ring(a, r1, i + 1),
            );
            // The radial direction of this slice, on the axis line, decides the outside.
            let mid = (b0 + b1 + a0 + a1) / 4.0;
            let axis_pt = b + d * (mid - b).dot(d);
            if r0 > 0.0 {
                self.emit_oriented([b0, b1, a1], axis_pt, inside);
            }
            if r1 > 0.0 {
                self.emit_oriented([b0, a1, a0], axis_pt, inside);
            }
        }
    }

    pub(super) fn finish(mut self) -> AffScene {
        let mut missing = Vec::new();
        let anims = std::mem::take(&mut self.anims);
        let node = |l: &Link, missing: &mut Vec<String>| match l {
            Link::Fixed(m) => Node::Fixed(*m),
            Link::Anim(n) => Node::Animated {
                name: n.clone(),
                kb: anims.get(n).cloned().unwrap_or_else(|| {
                    if !missing.contains(n) {
                        missing.push(n.clone());
                    }
                    KbTransform::default()
                }),
            },
        };
        let mut movers: Vec<AffMover> = self
            .mover_names
            .iter()
            .map(|n| AffMover {
                name: n.clone(),
                parts: Vec::new(),
            })
            .collect();
        let mut chains: Vec<Option<Vec<Node>>> = vec![None; self.parts.len()];
        for (i, p) in self.parts.iter().enumerate() {
            let used = !p.tris.is_empty() || self.patches.iter().any(|q| q.part == Some(i));
            if used {
                chains[i] = Some(p.chain.iter().map(|l| node(l, &mut missing)).collect());
            }
        }
        for (i, p) in self.parts.into_iter().enumerate() {
            if !p.tris.is_empty() {
                movers[p.mover].parts.push(MoverPart {
                    triangles: p.tris,
                    chain: chains[i].clone().unwrap_or_default(),
                });
            }
        }
        movers.retain(|m| !m.parts.is_empty());
        self.out.movers = movers;
        self.out.patches = self
            .patches
            .into_iter()
            .map(|p| AnimatedPatch {
                surface: p.surface,
                times: p.times,
                vertices: p.vertices,
                chain: p.part.and_then(|i| chains[i].clone()).unwrap_or_default(),
            })
            .collect();
        let c = &self.counts;
        let w = &mut self.out.warnings;
        if c.degenerate > 0 {
            w.push(format!(
                "{} degenerate triangle(s) skipped (zero area)",
                c.degenerate
            ));
        }
        if c.textured > 0 {
            w.push(format!(
                "{} textured mesh(es)/triangle(s): geometry kept, texture coordinates and images ignored",
                c.textured
            ));
        }
        if c.cones > 0 {
            w.push(format!(
                "{} cone(s)/cylinder(s) tessellated into {ROUND} quads each (open, no caps)",
                c.cones
            ));
        }
        if c.spheres > 0 {
            w.push(format!(
                "{} sphere(s) tessellated into {} triangles each",
                c.spheres,
                2 * ROUND * (ROUND / 2 - 1)
            ));
        }
        if c.visibility > 0 {
            w.push(format!(
                "{} visibility track(s) ignored (objects always visible)",
                c.visibility
            ));
        }
        if c.lights_in_movers > 0 {
            w.push(format!(
                "{} light(s) inside animated transforms placed with their static transforms only",
                c.lights_in_movers
            ));
        }
        if !missing.is_empty() {
            w.push(format!(
                "{} animated transform(s) without `k` keyframes (held at identity): {}",
                missing.len(),
                missing.join(", ")
            ));
        }
        if !c.unsorted.is_empty() {
            w.push(format!(
                "{} keyframe track(s) with decreasing key times, evaluated as BART's reference code does (first segment ending after t): {}",
                c.unsorted.len(),
                c.unsorted.join(", ")
            ));
        }
        if !c.duplicate_keys.is_empty() {
            w.push(format!(
                "keyframes given more than once (the last kept): {}",
                c.duplicate_keys.join(", ")
            ));
        }
        self.out
    }
}
