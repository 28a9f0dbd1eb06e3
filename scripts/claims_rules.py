"""The verdict rules of claims/preregistered.toml, applied generically.

A claim's statistic yields units (a point, a level, a scene, an index kind …), each judged by one
of three generic rules — an interval against a band, a p-value against two thresholds, or a
categorical judgement the statistic makes itself — and the units are combined by the aggregation
the claim registered ("all" or "most"). What an interval inside or outside the band *means* for a
claim (holds, differs, refuted) is read from the pre-registration, never decided here.

This module is the only place the five outcome words are spelled (the interface with the report).
"""

import math
from collections import namedtuple

OUTCOMES = HOLDS, HOLDS_IN_PART, DIFFERS, REFUTED, INCONCLUSIVE = (
    "holds", "holds-in-part", "differs", "refuted", "inconclusive")

# A unit's judgement before the claim's registered meaning is applied: the interval lies inside
# the band, outside it, or neither (it straddles an edge, is too wide, or is undefined).
INSIDE, OUTSIDE, UNDECIDED = "inside", "outside", "undecided"

Unit = namedtuple("Unit", "label text judgement reason brief value", defaults=("", None))
Unit.__doc__ = """One judged unit: its label (e.g. "octree, r_D/r_0 …"), the measured text (value
and interval), its judgement (INSIDE, OUTSIDE, UNDECIDED) and why (for UNDECIDED and OUTSIDE); for
the claim's headline (presentation only, never judged) its value and interval in a few words
(`brief`) and the number that orders units (`value`, None when it has no defined interval)."""


def bound(v):
    """A band edge from the TOML: a number, or the strings "inf" / "-inf"."""
    if isinstance(v, str):
        return float(v)
    return float(v)


def band_of(tolerance):
    """(lo, hi) of a registered band, relative to `target` when one is given."""
    lo, hi = (bound(v) for v in tolerance["band"])
    t = tolerance.get("target")
    if t is not None:
        lo, hi = lo * t, hi * t
    return lo, hi


def interval_judgement(lo, hi, band, max_half_width=None, value=None):
    """INSIDE when [lo, hi] ⊂ band, OUTSIDE when they are disjoint, else UNDECIDED; UNDECIDED too
    when the interval is undefined or reaches farther than max_half_width from the value."""
    if lo != lo or hi != hi:
        return UNDECIDED, "no interval"
    if max_half_width is not None and value is not None and value == value:
        reach = max(value - lo, hi - value)
        if reach > max_half_width:
            return UNDECIDED, "interval reaches ±%.3g, wider than ±%.3g" % (reach, max_half_width)
    b0, b1 = band
    if b0 <= lo and hi <= b1:
        return INSIDE, ""
    if hi < b0 or lo > b1:
        return OUTSIDE, "interval outside %s" % band_text(band)
    return UNDECIDED, "interval crosses an edge of %s" % band_text(band)


def band_text(band):
    def f(x):
        if math.isinf(x):
            return "∞" if x > 0 else "−∞"
        return "%.4g" % x
    return "[%s, %s]" % (f(band[0]), f(band[1]))


def p_judgement(p, alpha_hold, alpha_reject):
    """INSIDE when p ≥ alpha_hold, OUTSIDE when p < alpha_reject, else UNDECIDED."""
    if p != p:
        return UNDECIDED, "no p-value"
    if p >= alpha_hold:
        return INSIDE, ""
    if p < alpha_reject:
        return OUTSIDE, "p = %.2g < %g" % (p, alpha_reject)
    return UNDECIDED, "%g ≤ p = %.2g < %g" % (alpha_reject, p, alpha_hold)


def share_judgement(units):
    """Judgement of a group by "most": INSIDE when more than half of its units are INSIDE,
    OUTSIDE when at least half are OUTSIDE, else UNDECIDED."""
    n = len(units)
    inside = sum(u.judgement == INSIDE for u in units)
    outside = sum(u.judgement == OUTSIDE for u in units)
    reason = "%d of %d inside, %d outside" % (inside, n, outside)
    if n and 2 * inside > n:
        return INSIDE, reason
    if n and 2 * outside >= n:
        return OUTSIDE, reason
    return UNDECIDED, reason


def group_judgement(units, mode):
    """Judgement of a group of units (e.g. a scene's levels) by the registered aggregation: "all"
    is INSIDE when every unit is, OUTSIDE when any is; "most" as share_judgement."""
    if mode == "most":
        return share_judgement(units)
    if mode != "all":
        raise ValueError("aggregate must be \"all\" or \"most\", got %r" % mode)
    n = len(units)
    inside = sum(u.judgement == INSIDE for u in units)
    outside = sum(u.judgement == OUTSIDE for u in units)
    reason = "%d of %d inside, %d outside" % (inside, n, outside)
    if n and inside == n:
        return INSIDE, reason
    if outside:
        return OUTSIDE, reason  # a statement about every member fails at any member outside
    return UNDECIDED, reason


def outcome(units, verdict, needs):
    """The claim's outcome and its reason from its judged units, the registered meaning (verdict:
    inside → …, outside → …, aggregate) and what the tables lack (needs).

    - anything needed is missing → INCONCLUSIVE ("needs …"), whatever the units say;
    - every unit INSIDE → verdict["inside"]; every unit OUTSIDE → verdict["outside"];
    - with "all": some INSIDE and some OUTSIDE → HOLDS_IN_PART; any UNDECIDED left → INCONCLUSIVE
      unless every decided unit is OUTSIDE, which gives verdict["outside"] (nothing supports it);
    - with "most": more than half INSIDE → verdict["inside"], at least half OUTSIDE →
      verdict["outside"], else INCONCLUSIVE."""
    for key in ("inside", "outside"):
        if verdict.get(key) not in OUTCOMES:
            raise ValueError("verdict.%s must be one of %s" % (key, ", ".join(OUTCOMES)))
    if needs:
        return INCONCLUSIVE, "needs " + "; needs ".join(dict.fromkeys(needs))
    if not units:
        return INCONCLUSIVE, "no unit to judge"
    n = len(units)
    inside = [u for u in units if u.judgement == INSIDE]
    outside = [u for u in units if u.judgement == OUTSIDE]
    undecided = [u for u in units if u.judgement == UNDECIDED]
    count = "%d of %d %s" % (len(inside), n, "unit holds" if n == 1 else "units hold")
    mode = verdict.get("aggregate", "all")
    if mode == "most":
        j, why = share_judgement(units)
        if j == INSIDE:
            return verdict["inside"], count + " (most)"
        if j == OUTSIDE:
            return verdict["outside"], why
        return INCONCLUSIVE, why
    if len(inside) == n:
        return verdict["inside"], count
    if len(outside) == n:
        return verdict["outside"], "every unit outside"
    if inside and outside:
        return HOLDS_IN_PART, "%s, %d outside%s" % (count, len(outside), undecided_text(undecided))
    if outside and not inside:
        return verdict["outside"], "%d of %d outside, none inside%s" % (len(outside), n, undecided_text(undecided))
    return INCONCLUSIVE, "%s%s" % (count, undecided_text(undecided))


def undecided_text(undecided):
    if not undecided:
        return ""
    reasons = sorted({u.reason for u in undecided if u.reason})
    return "; %d undecided (%s)" % (len(undecided), "; ".join(reasons))
