//! Photon batches: a point whose segments would not fit its memory budget (`detp.memory_budget_gib`)
//! traces its photons in B batches, one after another in this process, and is measured from their
//! sum — the table a single pass writes, bit for bit.
//!
//! A batch is a photon shard run in process: batch K of B is the kind's
//! [`Kind::trace_part`](super::kind::Kind::trace_part) of photons `[K·P/B, (K+1)·P/B)` (each
//! photon's stream keyed by its id, never by the batch), whose segment store is dropped when the
//! part is returned; the parts are added as they come ([`Kind::add_parts`](super::kind::Kind::add_parts),
//! so two are held at most), and the point is measured from the one total part by the code that
//! merges photon shards ([`Context::merged`]). Engines that read no photons (the reference, path
//! tracing) run once, at the measurement. Seconds are sums over the batches, and a batch rebuilds
//! what does not depend on the photons (the discs, a disc index): that rebuilding is the cost of a
//! batch, in time, not in any measured column.
//!
//! [`batches`] is the rule: a point's needs are split into what grows with the photons traced at
//! once (the segment store; [`Need::per_photon`]) and what every batch holds whole (discs, their
//! sums, indices over the discs); B is the smallest count whose batch fits the budget.

use super::kind::{Batching, Context, DynKind, DynPoint, ErasedOutput, Need};
use crate::error::Error;

const GIB: f64 = (1u64 << 30) as f64;

/// A point's memory as batches see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    /// Bytes every batch holds whole.
    pub fixed: f64,
    /// Bytes that grow with the photons, for all of them at once.
    pub per_photon: f64,
}

impl Split {
    /// The needs, split.
    pub fn of(needs: &[Need]) -> Self {
        let sum = |p: bool| {
            needs
                .iter()
                .filter(|n| n.per_photon == p)
                .map(|n| n.bytes)
                .sum()
        };
        Self {
            fixed: sum(false),
            per_photon: sum(true),
        }
    }

    /// Bytes of the largest of `b` batches of `photons` (batches differ by one photon at most).
    pub fn per_batch(&self, photons: u64, b: u64) -> f64 {
        let largest = photons.div_ceil(b.max(1)) as f64;
        self.fixed + self.per_photon * largest / photons.max(1) as f64
    }
}

/// Why a point's photon batches cannot be chosen: the spec key to name, and what to say.
#[derive(Clone, Debug, PartialEq)]
pub struct Refusal {
    /// The key.
    pub key: &'static str,
    /// Why, and what would work.
    pub message: String,
}

/// The number of batches a point takes: the forced count, or the smallest whose largest batch
/// fits `budget` bytes (1 when the whole point fits). `budget_key` names the budget in messages;
/// `largest` is the key that drives the largest need; `unsplittable` says why the kind cannot
/// batch this point (None: it can).
pub fn batches(
    split: Split,
    batching: &Batching,
    budget: (&'static str, f64),
    largest: &'static str,
    unsplittable: Option<String>,
) -> Result<u64, Refusal> {
    let (budget_key, bytes) = budget;
    let gib = |b: f64| b / GIB;
    let p = batching.photons;
    if let Some(b) = batching.forced {
        let refuse = |message: String| {
            Err(Refusal {
                key: batching.key,
                message,
            })
        };
        if b > 1 {
            if let Some(why) = unsplittable {
                return refuse(format!(
                    "= {b}, but this point's photons cannot be traced in batches: {why}"
                ));
            }
        }
        if b > p.max(1) {
            return refuse(format!("= {b}, more batches than the {p} photons"));
        }
        let each = split.per_batch(p, b);
        if each.is_nan() || each > bytes {
            let hint = match batches(
                split,
                &Batching {
                    forced: None,
                    ..*batching
                },
                budget,
                largest,
                None,
            ) {
                Ok(auto) => format!("\"auto\" takes {auto}"),
                Err(r) => r.message,
            };
            return refuse(format!(
                "= {b}: a batch would need about {:.3} GiB, over {budget_key} = {} GiB ({hint})",
                gib(each),
                gib(bytes)
            ));
        }
        return Ok(b);
    }
    let whole = split.fixed + split.per_photon;
    if !whole.is_nan() && whole <= bytes {
        return Ok(1);
    }
    if let Some(why) = unsplittable {
        return Err(Refusal {
            key: largest,
            message: format!(
                "would need about {:.3} GiB, over {budget_key} = {} GiB, and its photons cannot be traced in batches: {why}. Choose engines whose counts add, raise {budget_key}, or reduce {largest}",
                gib(whole),
                gib(bytes)
            ),
        });
    }
    if split.fixed.is_nan() || split.fixed >= bytes || split.per_photon.is_nan() {
        return Err(Refusal {
            key: largest,
            message: format!(
                "what every photon batch holds whole (the discs, their sums, indices) would need about {:.3} GiB, over {budget_key} = {} GiB: batches cannot help. Raise {budget_key}, or use fewer points (or larger discs)",
                gib(split.fixed),
                gib(bytes)
            ),
        });
    }
    // The smallest B with fixed + per_photon·⌈P/B⌉/P ≤ budget: from the continuous bound, then up
    // by the rounding of P/B.
    let room = bytes - split.fixed;
    let mut b = ((split.per_photon / room).ceil() as u64).clamp(1, p.max(1));
    while b < p && split.per_batch(p, b) > bytes {
        b += 1;
    }
    if split.per_batch(p, b) > bytes {
        return Err(Refusal {
            key: largest,
            message: format!(
                "even one photon per batch would need about {:.3} GiB, over {budget_key} = {} GiB. Raise {budget_key}",
                gib(split.per_batch(p, b)),
                gib(bytes)
            ),
        });
    }
    Ok(b)
}

/// Runs one point in `b` photon batches (see the module doc): its output as a single pass gives
/// it, every measured column bit for bit (the merged parts' accelerator work is written as
/// timing, as for photon shards).
pub fn run(
    kind: &dyn DynKind,
    point: &dyn DynPoint,
    shared: &(dyn std::any::Any + Send + Sync),
    ctx: &Context,
    b: u64,
) -> Result<ErasedOutput, Error> {
    let mut total: Option<serde_json::Value> = None;
    for k in 0..b {
        let part = kind.trace_part(point, shared, ctx, (k, b))?;
        total = Some(match total {
            None => part,
            Some(t) => kind.add_parts(point, t, part)?,
        });
    }
    let parts: Vec<serde_json::Value> = total.into_iter().collect();
    // The batches counted the photons; measuring them counts nothing more.
    let measure = Context {
        stream_point: ctx.stream_point,
        threads: ctx.threads,
        progress: &|_| {},
        merged: Some(&parts),
    };
    kind.run(point, shared, &measure)
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f64 = GIB;

    fn batching(photons: u64, forced: Option<u64>) -> Batching {
        Batching {
            key: "detp.photon_batches",
            forced,
            photons,
        }
    }

    fn count(
        fixed: f64,
        per_photon: f64,
        photons: u64,
        forced: Option<u64>,
        budget: f64,
    ) -> Result<u64, Refusal> {
        batches(
            Split { fixed, per_photon },
            &batching(photons, forced),
            ("detp.memory_budget_gib", budget * G),
            "detp.photons",
            None,
        )
    }

    /// The rule against its definition: B fits, B − 1 does not (brute force over small cases).
    #[test]
    fn the_batch_count_is_the_smallest_that_fits() {
        for photons in [1u64, 2, 7, 10, 1000, 32_000_000] {
            for fixed in [0.0, 0.5, 3.0] {
                for per_photon in [0.1, 4.0, 8.3, 31.0, 100.0] {
                    let budget = 4.0;
                    let split = Split {
                        fixed: fixed * G,
                        per_photon: per_photon * G,
                    };
                    match count(fixed * G, per_photon * G, photons, None, budget) {
                        Ok(b) => {
                            assert!(
                                split.per_batch(photons, b) <= budget * G,
                                "{photons} {fixed} {per_photon}: {b} does not fit"
                            );
                            if b > 1 {
                                assert!(
                                    split.per_batch(photons, b - 1) > budget * G,
                                    "{photons} {fixed} {per_photon}: {} fits too",
                                    b - 1
                                );
                            }
                        }
                        Err(r) => assert!(
                            (1..=photons).all(|b| split.per_batch(photons, b) > budget * G),
                            "{photons} {fixed} {per_photon}: refused ({}) though a count fits",
                            r.message
                        ),
                    }
                }
            }
        }
        // 8.3 GiB of segments and 0.3 GiB of discs: two batches within 8 GiB, three within 3.5, four within 3.
        assert_eq!(count(0.3 * G, 8.3 * G, 32_000_000, None, 8.0), Ok(2));
        assert_eq!(count(0.3 * G, 8.3 * G, 32_000_000, None, 3.5), Ok(3));
        assert_eq!(count(0.3 * G, 8.3 * G, 32_000_000, None, 3.0), Ok(4));
        assert_eq!(count(0.3 * G, 7.0 * G, 32_000_000, None, 8.0), Ok(1));
    }

    #[test]
    fn a_fixed_part_over_the_budget_is_refused() {
        let r = count(5.0 * G, 1.0 * G, 1000, None, 4.0).expect_err("fixed part alone too big");
        assert!(r.message.contains("batches cannot help"), "{}", r.message);
        assert_eq!(r.key, "detp.photons");
    }

    #[test]
    fn an_unsplittable_point_over_the_budget_is_refused_and_one_within_it_runs_whole() {
        let split = Split {
            fixed: 0.0,
            per_photon: 9.0 * G,
        };
        let why = || Some("the sphere cache's counts do not add".to_string());
        let b = ("detp.memory_budget_gib", 8.0 * G);
        let r = batches(split, &batching(100, None), b, "detp.photons", why()).expect_err("over");
        assert!(
            r.message.contains("cannot be traced in batches"),
            "{}",
            r.message
        );
        assert!(
            r.message.contains("raise detp.memory_budget_gib"),
            "{}",
            r.message
        );
        let small = Split {
            fixed: 0.0,
            per_photon: 1.0 * G,
        };
        assert_eq!(
            batches(small, &batching(100, None), b, "detp.photons", why()),
            Ok(1)
        );
        let forced = batches(small, &batching(100, Some(2)), b, "detp.photons", why());
        assert_eq!(forced.expect_err("forced").key, "detp.photon_batches");
    }

    #[test]
    fn a_forced_count_must_fit_and_not_exceed_the_photons() {
        assert_eq!(count(0.0, 9.0 * G, 1000, Some(3), 8.0), Ok(3));
        assert_eq!(count(0.0, 1.0 * G, 1000, Some(3), 8.0), Ok(3));
        let r = count(0.0, 30.0 * G, 1000, Some(2), 8.0).expect_err("a batch of 15 GiB");
        assert!(r.message.contains("\"auto\" takes 4"), "{}", r.message);
        let r = count(0.0, 1.0, 5, Some(6), 8.0).expect_err("6 batches of 5 photons");
        assert!(
            r.message.contains("more batches than the 5 photons"),
            "{}",
            r.message
        );
    }
}
