"""raycost_stats against exact values and against simulations whose truth is known.

Run: python3 -m unittest discover -s scripts/tests (from the repository root; .ci/run does).
The simulations are small (a few seconds in all) and seeded: each asserts a coverage or an
identity that the statistic must meet, with a margin for the trials' own noise.
"""

import math
import os
import random
import sys
import unittest
from statistics import NormalDist

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import raycost_stats as S  # noqa: E402

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


class StudentT(unittest.TestCase):
    def test_quantiles_equal_the_rust_side_at_every_dof(self):
        n = 0
        with open(os.path.join(DATA, "statrs_t_quantiles.txt")) as f:
            lines = f.readlines()
        for line in lines:
            if line.startswith("#"):
                continue
            level, dof, t = line.split()
            got = S.t_for_level(float(level), int(dof))
            self.assertAlmostEqual(got, float(t), delta=1e-9 * float(t), msg="level %s dof %s" % (level, dof))
            n += 1
        self.assertGreater(n, 50)

    def test_no_switch_to_the_normal_above_30_dof(self):
        # The old table jumped to 1.96 beyond 30 degrees of freedom; statrs gives 2.0395 at 31.
        self.assertAlmostEqual(S.t95(31), 2.0395134463961622, places=10)
        self.assertGreater(S.t95(100), 1.98)
        self.assertAlmostEqual(S.t95(20000), NormalDist().inv_cdf(0.975), places=12)
        self.assertTrue(math.isnan(S.t95(0)))

    def test_cdf_and_quantile_are_inverse_for_real_dof(self):
        rng = random.Random(3)
        for _ in range(200):
            p, dof = rng.uniform(0.001, 0.999), rng.uniform(0.7, 400)
            self.assertAlmostEqual(S.t_cdf(S.t_quantile(p, dof), dof), p, places=10)

    def test_closed_forms_at_one_and_two_dof(self):
        for x in (-3.0, -0.4, 0.0, 1.3, 7.0):
            self.assertAlmostEqual(S.t_cdf(x, 1), 0.5 + math.atan(x) / math.pi, places=12)
            self.assertAlmostEqual(S.t_cdf(x, 2), 0.5 + x / (2 * math.sqrt(2 + x * x)), places=12)


class ChiSquare(unittest.TestCase):
    def test_survival_matches_closed_forms(self):
        for x in (0.1, 1.0, 3.84, 10.0, 40.0):
            self.assertAlmostEqual(S.chi2_sf(x, 2), math.exp(-x / 2), places=12)
            self.assertAlmostEqual(S.chi2_sf(x, 4), math.exp(-x / 2) * (1 + x / 2), places=12)
            self.assertAlmostEqual(S.chi2_sf(x, 1), 2 * (1 - NormalDist().cdf(math.sqrt(x))), places=10)

    def test_normal_score_of_a_t_statistic(self):
        t = S.t_quantile(0.9, 5)
        self.assertAlmostEqual(S.normal_score(t, 5), NormalDist().inv_cdf(0.9), places=9)


class Polynomials(unittest.TestCase):
    def test_roots_of_a_cubic_are_found_between_its_turning_points(self):
        # (x − 0.2)(x − 0.5)(x − 0.7) = x³ − 1.4x² + 0.59x − 0.07
        r = S.real_roots([-0.07, 0.59, -1.4, 1.0], 0.0, 1.0)
        for got, want in zip(r, (0.2, 0.5, 0.7)):
            self.assertAlmostEqual(got, want, places=12)
        self.assertEqual(S.real_roots([-0.07, 0.59, -1.4, 1.0], 0.3, 0.45), [])

    def test_the_fit_rule_picks_the_lowest_acceptable_degree(self):
        xs = [0.1 * i for i in range(1, 10)]
        ys = [1 + 2 * x for x in xs]
        fit = S.choose_fit(xs, ys, [1e-4] * 9, [1, 2, 3], 0.05)
        self.assertEqual(fit.degree, 1)
        ys = [1 + 2 * x - 5 * x * x for x in xs]
        self.assertEqual(S.choose_fit(xs, ys, [1e-4] * 9, [1, 2, 3], 0.05).degree, 2)


def coverage(trials, make, truth):
    """Share of trials whose (lo, hi) from make(rng) holds the truth."""
    rng = random.Random(11)
    hit = 0
    for _ in range(trials):
        lo, hi = make(rng)
        hit += lo <= truth <= hi
    return hit / trials


def clustered_mean_interval(values, draws, seed):
    cl = S.Clustered(values)
    iv = S.bootstrap(lambda m, v: m[0], cl, draws, seed)
    return iv.lo, iv.hi


def runs_with_effects(rng, k, reps, mean=10.0, between=1.0, within=0.5):
    out = {}
    for run in range(k):
        b = rng.gauss(0, between)
        for rep in range(reps):
            out[(run, rep)] = [mean + b + rng.gauss(0, within)]
    return out


class ClusterBootstrap(unittest.TestCase):
    def test_three_runs_cover_the_mean_with_between_run_variation(self):
        # Between-run variation dominates; the interval must carry it with only 3 runs.
        cov = coverage(300, lambda rng: clustered_mean_interval(runs_with_effects(rng, 3, 4), 300, rng.random()),
                       10.0)
        self.assertGreater(cov, 0.90)

    def test_resampling_three_runs_would_undercover(self):
        # The alternative the wild draws replace: resampling 3 runs with replacement.
        def resampled(rng):
            v = runs_with_effects(rng, 3, 4)
            runs = {}
            for (r, _), x in v.items():
                runs.setdefault(r, []).append(x[0])
            means = [sum(x) / len(x) for x in runs.values()]
            draws = sorted(sum(rng.choice(means) for _ in means) / 3 for _ in range(300))
            return draws[7], draws[292]
        self.assertLess(coverage(300, resampled, 10.0), 0.85)

    def test_one_run_takes_its_replicas_as_clusters(self):
        rng = random.Random(2)
        v = {(0, r): [rng.gauss(5, 1), rng.gauss(3, 1)] for r in range(8)}
        cl = S.Clustered(v)
        self.assertEqual(cl.clusters(), 8)
        m, var = cl.observed()
        xs = [x[0] for x in v.values()]
        mu = sum(xs) / 8
        self.assertAlmostEqual(var[0], sum((x - mu) ** 2 for x in xs) / 7 / 8, places=12)

    def test_draws_keep_the_pairing_of_quantities(self):
        # Two quantities moving together cluster by cluster: their difference is nearly exact.
        rng = random.Random(4)
        v = {(0, r): [x, x + 1.0 + rng.gauss(0, 1e-3)] for r, x in enumerate(rng.gauss(0, 5) for _ in range(8))}
        iv = S.bootstrap(lambda m, _v: m[1] - m[0], S.Clustered(v), 500, 1)
        self.assertLess(iv.hi - iv.lo, 0.01)


class Crossover(unittest.TestCase):
    XS = [0.2 + 0.025 * i for i in range(15)]

    def simulate(self, rng, root, runs=3, reps=4, curve=None):
        """Costs of engines A and B sharing each cluster's noise (common random numbers): log(A/B)
        = 2.5·(x − root) + a run effect and a replica effect, both common to every x."""
        curve = curve or (lambda x: 2.5 * (x - root))
        out = {}
        for run in range(runs):
            eb = rng.gauss(0, 0.03)
            for rep in range(reps):
                er = rng.gauss(0, 0.02)
                b = [100 * (1 + x) * math.exp(rng.gauss(0, 0.01)) for x in self.XS]
                a = [bb * math.exp(curve(x) + eb + er + rng.gauss(0, 0.01)) for bb, x in zip(b, self.XS)]
                out[(run, rep)] = a + b
        return out

    def interval(self, values, draws=200):
        cl = S.Clustered(values)
        c = S.crossover(self.XS, cl, S.paired_log_ratio(len(self.XS), cl), [1, 2, 3], 0.05, draws, 1)
        return c

    def test_the_interval_covers_a_known_root_across_runs(self):
        def make(rng):
            c = self.interval(self.simulate(rng, 0.36))
            return (c.lo, c.hi) if len(c.found) == 1 else (math.nan, math.nan)
        # Exact for a linear statistic (the wild draws are Student-t on runs − 1); the fit and its
        # degree rule cost a little: 0.91 over 120 trials when this was written.
        self.assertGreater(coverage(100, make, 0.36), 0.85)

    def test_draws_without_one_crossing_are_counted_not_dropped(self):
        rng = random.Random(5)
        c = self.interval(self.simulate(rng, 0.0, curve=lambda x: 0.3))  # A always dearer
        self.assertEqual(c.found, [])
        self.assertGreater(c.interval.categories.get("none", 0), 0.99)
        self.assertAlmostEqual(sum(c.interval.categories.values()), 1.0)
        self.assertGreater(c.interval.undefined, 0.99)

    def test_a_curve_that_crosses_twice_is_seen_as_such(self):
        rng = random.Random(6)
        c = self.interval(self.simulate(rng, 0.0, curve=lambda x: 20 * (x - 0.3) * (x - 0.45)))
        self.assertEqual(len(c.found), 2)
        self.assertGreater(c.interval.categories.get("several", 0), 0.9)


class Optimum(unittest.TestCase):
    def test_the_interval_covers_a_known_minimum(self):
        qs = [0.55 + 0.01 * i for i in range(21)]

        def make(rng):
            means = [math.exp(3 * (q - 0.64) ** 2 + 0.3 * (q - 0.64) ** 3) * (1 + rng.gauss(0, 0.002)) for q in qs]
            ses = [0.002 * m for m in means]
            c = S.optimum(qs, S.Parametric(means, ses, [3] * len(qs)), [2, 3, 4], 0.05, 200, rng.random())
            return c.lo, c.hi
        self.assertGreater(coverage(40, make, 0.64), 0.85)


class Fieller(unittest.TestCase):
    def test_coverage_of_a_ratio_of_means(self):
        tq = S.t_for_level(0.95, 7)

        def make(rng):
            a = [rng.gauss(2.0, 0.5) for _ in range(8)]
            b = [rng.gauss(5.0, 0.8) for _ in range(8)]
            ma, mb = sum(a) / 8, sum(b) / 8
            va = sum((x - ma) ** 2 for x in a) / 7 / 8
            vb = sum((x - mb) ** 2 for x in b) / 7 / 8
            _, lo, hi, ok = S.fieller(ma, va, mb, vb, 0.0, tq)
            return (lo, hi) if ok else (-math.inf, math.inf)
        self.assertGreater(coverage(2000, make, 0.4), 0.93)

    def test_unbounded_when_the_denominator_may_be_zero(self):
        self.assertFalse(S.fieller(1.0, 0.01, 0.1, 0.01, 0.0, 1.96)[3])


class FittedSeconds(unittest.TestCase):
    def test_the_misfit_is_inside_the_interval(self):
        """Seconds = 3·a + 5·b times a case-specific misfit (15 %, mean 1), measured very
        precisely: an interval from the measurement noise alone misses the constants; resampling
        the cases covers them."""
        def make(rng, resample):
            a = [rng.uniform(1, 10) for _ in range(12)]
            b = [rng.uniform(1, 10) for _ in range(12)]
            y = [(3 * x + 5 * z) * math.exp(rng.gauss(0, 0.15) - 0.15 ** 2 / 2) for x, z in zip(a, b)]
            se = [1e-4 * v for v in y]
            if resample:
                f = S.fit_costs_ci([a, b], y, se, draws=300, seed=rng.random())
            else:
                c, _ = S.fit_costs([a, b], y)
                draws = sorted(S.fit_costs([a, b], [v + s * rng.gauss(0, 1) for v, s in zip(y, se)])[0][0]
                               for _ in range(100))
                return draws[2], draws[97]
            return f.cis[0]
        self.assertGreater(coverage(60, lambda rng: make(rng, True), 3.0), 0.8)
        self.assertLess(coverage(60, lambda rng: make(rng, False), 3.0), 0.2)

    def test_a_time_drawn_below_zero_is_an_unfit_draw_not_a_clamped_one(self):
        """One case's SE is as large as its value, so about one draw in six moves it below 0. Such
        a draw has no relative residual; clamping it to a tiny positive time made it dominate the
        fit (weights 1/y) and gave NaN bounds. It is counted unfit, and every bound stays finite
        and positive around the true constant."""
        a = [float(i) for i in range(1, 11)]
        y = [2.0 * x for x in a]
        se = [1e-3 * v for v in y]
        se[0] = y[0]
        f = S.fit_costs_ci([a], y, se, draws=400, seed=3)
        self.assertGreater(f.undefined, 0.05)
        self.assertLess(f.undefined, 0.5)
        lo, hi = f.cis[0]
        self.assertTrue(math.isfinite(lo) and math.isfinite(hi), f.cis)
        self.assertLess(0.0, lo)
        self.assertLessEqual(lo, 2.0)
        self.assertLessEqual(2.0, hi)


class Shapley(unittest.TestCase):
    def test_factors_multiply_to_the_total_whatever_the_order(self):
        a = {"list": 0.4, "pop": 1.1, "layout": 0.65}

        def value(s):
            v = 10.0
            for k in s:
                v *= a[k]
            if {"list", "pop"} <= s:
                v *= 1.15  # an interaction: switching order matters
            return v
        sh = S.shapley_factors(value, list(a))
        prod = math.prod(f for f, _, _ in sh.values())
        self.assertAlmostEqual(prod, value(frozenset(a)) / value(frozenset()), places=12)
        self.assertAlmostEqual(sh["layout"][0], 0.65, places=12)  # no interaction: one value
        self.assertLess(sh["list"][1], sh["list"][2])  # the order changes it: a range
        self.assertAlmostEqual(sh["list"][0], 0.4 * math.sqrt(1.15), places=12)


class Pooling(unittest.TestCase):
    def table(self, rng, effect):
        return [{"point": float(p), "m_mean": 10 + effect + rng.gauss(0, 0.2), "m_se": 0.2, "m_n": 4.0,
                 "m_clusters": 4.0} for p in range(3)]

    def test_pooled_se_carries_between_run_variation(self):
        def make(rng):
            tabs = [self.table(rng, rng.gauss(0, 1.0)) for _ in range(3)]
            row = S.pool_runs(tabs, ["point"], ["m"])[0]
            h = S.t95(row["m_clusters"] - 1) * row["m_se"]
            self.assertEqual(row["m_runs"], 3)
            self.assertAlmostEqual(row["m_se_within"], 0.2 / math.sqrt(3), places=12)
            return row["m_mean"] - h, row["m_mean"] + h
        self.assertGreater(coverage(1000, make, 10.0), 0.93)

    def test_one_run_comes_back_unchanged_and_a_missing_point_is_an_error(self):
        rng = random.Random(1)
        t = self.table(rng, 0)
        row = S.pool_runs([t], ["point"], ["m"])[0]
        self.assertEqual((row["m_mean"], row["m_se"], row["m_runs"]), (t[0]["m_mean"], 0.2, 1))
        with self.assertRaises(ValueError):
            S.pool_runs([t, t[:2]], ["point"], ["m"])


class RunsPicks(unittest.TestCase):
    def test_every_runs_replica_members_are_kept_in_run_order(self):
        a = [{"point": 0, "pick_replica_0": "a", "pick_replica_1": "b", "m_mean": 1.0, "m_se": 0.1, "m_n": 2}]
        b = [{"point": 0, "pick_replica_0": "c", "pick_replica_1": math.nan, "m_mean": 2.0, "m_se": 0.1,
              "m_n": 2}]
        row = S.pool_runs([a, b], ["point"], ["m"])[0]
        picks = [row[k] for k in sorted(row) if k.startswith("pick_replica_")]
        self.assertEqual(sorted(picks), ["a", "b", "c"])
        self.assertEqual((row["pick_replica_0"], row["pick_replica_2"]), ("a", "c"))
        self.assertNotIn("pick_replica_3", row)


class ClopperPearson(unittest.TestCase):
    def test_exact_values(self):
        # 8 of 10 at 95 %: [0.4439, 0.9748] (the beta quantiles); 0 and n give 0 and 1 as a bound.
        lo, hi = S.clopper_pearson(8, 10, 0.95)
        self.assertAlmostEqual(lo, 0.44390454, places=6)
        self.assertAlmostEqual(hi, 0.97478927, places=6)
        self.assertEqual(S.clopper_pearson(0, 10)[0], 0.0)
        self.assertAlmostEqual(S.clopper_pearson(0, 10)[1], 1 - 0.025 ** (1 / 10), places=9)
        self.assertEqual(S.clopper_pearson(10, 10)[1], 1.0)
        self.assertTrue(all(math.isnan(x) for x in S.clopper_pearson(0, 0)))

    def test_coverage_is_at_least_the_level(self):
        rng = random.Random(3)
        n, p, hits, trials = 24, 0.8, 0, 400
        for _ in range(trials):
            k = sum(rng.random() < p for _ in range(n))
            lo, hi = S.clopper_pearson(k, n, 0.95)
            hits += lo <= p <= hi
        self.assertGreaterEqual(hits / trials, 0.94)


class BootstrapBookkeeping(unittest.TestCase):
    def test_undefined_draws_are_reported(self):
        sampler = S.Parametric([0.0], [1.0], [10])
        iv = S.bootstrap(lambda m, _v: m[0] if m[0] > 0 else ("none", math.nan), sampler, 2000, 1)
        self.assertAlmostEqual(iv.undefined, 0.5, delta=0.05)
        self.assertAlmostEqual(iv.categories["none"] + iv.categories["ok"], 1.0)


class PercentileShared(unittest.TestCase):
    """The bootstrap's percentile lives in two languages (raycost_stats.percentile and the Rust
    stats::percentile that the crossover's bootstrap uses); both are held to the shared cases of
    data/percentile_cases.txt, which the Rust side reads too."""

    def test_percentile_gives_the_shared_ranks(self):
        with open(os.path.join(DATA, "percentile_cases.txt")) as f:
            cases = [line.split() for line in f if not line.startswith("#")]
        self.assertGreater(len(cases), 100)
        for n, q, rank in cases:
            values = [float(v) for v in range(int(n))]
            self.assertEqual(S.percentile(values, float(q)), float(rank), (n, q))

    def test_the_bootstrap_interval_is_the_percentile_of_its_draws(self):
        # A statistic whose draws are known: the sampler's single mean, drawn around 0.
        sampler = S.Parametric([0.0], [1.0], [10])
        rng = random.Random(7)
        draws = sorted(sampler.draw(rng)[0][0] for _ in range(999))
        iv = S.bootstrap(lambda m, _v: m[0], sampler, 999, 7)
        self.assertEqual((iv.lo, iv.hi), (S.percentile(draws, 0.025), S.percentile(draws, 0.975)))


def cost_fit_cases():
    """The shared cases of data/cost_fit_cases.txt: (γ, [(photons, points, seconds)], expected
    [fixed, a, b, c])."""
    cases = []
    with open(os.path.join(DATA, "cost_fit_cases.txt")) as f:
        for line in f:
            word, *rest = line.split()
            if word == "case":
                cases.append((float(rest[0]), [], None))
            elif word == "sample":
                cases[-1][1].append(tuple(float(v) for v in rest))
            elif word == "expect":
                cases[-1] = (cases[-1][0], cases[-1][1], [float(v) for v in rest])
    return cases


class CostFitShared(unittest.TestCase):
    """The cost fit lives in two languages until it moves to one (raycost_stats.fit_costs and
    the Rust CostModel::fit); both are held to the same shared cases, which the Rust side reads
    too. Agreement means the same columns kept (the same zeros) and fitted seconds within 1e-9
    relative at every sample: the fit is exact arithmetic on rows normalised by their seconds."""

    def test_fit_costs_gives_the_shared_answers(self):
        cases = cost_fit_cases()
        self.assertEqual(len(cases), 5)
        for gamma, samples, expect in cases:
            cols = [[1.0] * len(samples), [n for n, _, _ in samples],
                    [n * p ** gamma for n, p, _ in samples], [p for _, p, _ in samples]]
            coef, _ = S.fit_costs(cols, [s for _, _, s in samples])
            self.assertEqual([c == 0 for c in coef], [c == 0 for c in expect], (gamma, coef))
            for k, (_, _, s) in enumerate(samples):
                got = sum(c * col[k] for c, col in zip(coef, cols))
                want = sum(c * col[k] for c, col in zip(expect, cols))
                self.assertLess(abs(got - want), 1e-9 * s, (gamma, k))

    def test_the_noise_free_case_gives_its_coefficients_back(self):
        gamma, samples, expect = cost_fit_cases()[0]
        for got, want in zip(expect, [0.05, 2e-7, 3e-12, 4e-6]):
            self.assertAlmostEqual(got / want, 1.0, places=12)



def error_fit_cases():
    """The shared cases of data/error_fit_cases.txt: ([(photons, mse)], expected [B, c])."""
    cases = []
    with open(os.path.join(DATA, "error_fit_cases.txt")) as f:
        for line in f:
            word, *rest = line.split()
            if word == "case":
                cases.append(([], None))
            elif word == "sample":
                cases[-1][0].append(tuple(float(v) for v in rest))
            elif word == "expect":
                cases[-1] = (cases[-1][0], [float(v) for v in rest])
    return cases


class ErrorFitShared(unittest.TestCase):
    """The error model's fit MSE = B + c/N lives in two languages (raycost_stats.fit_relative_iterated,
    which the radius-schedule numbers use, and the Rust ErrorFit::fit_relative, which the crossover
    uses); both are held to the shared cases, which the Rust side reads too: the same zeros and the
    fitted MSE within 1e-9 relative at every finite sample."""

    def test_the_error_fit_gives_the_shared_answers(self):
        cases = error_fit_cases()
        self.assertEqual(len(cases), 6)
        for samples, expect in cases:
            ns = [n for n, _ in samples]
            coef, _ = S.fit_relative_iterated([[1.0] * len(ns), [1.0 / n for n in ns]],
                                              [y for _, y in samples])
            self.assertEqual([c == 0 for c in coef], [c == 0 for c in expect], coef)
            for n, y in samples:
                got, want = coef[0] + coef[1] / n, expect[0] + expect[1] / n
                self.assertLessEqual(abs(got - want), 1e-9 * want, (n, y))

    def test_the_noise_free_case_gives_its_floor_and_variance_back(self):
        _, expect = error_fit_cases()[0]
        self.assertAlmostEqual(expect[0] / 1e-4, 1.0, places=9)
        self.assertAlmostEqual(expect[1] / 50.0, 1.0, places=9)

    def test_weights_follow_the_fitted_value_not_the_measured_one(self):
        # One low outlier at the largest N: weighted by its own small value (1/y²) it pulls the floor
        # down hard; weighted by the fitted value it counts like its neighbours.
        ns = [1e4, 1e5, 1e6, 1e7]
        ys = [1e-3 + 1.0 / n for n in ns]
        ys[-1] *= 0.5
        once = S.fit_relative_iterated([[1.0] * 4, [1.0 / n for n in ns]], ys, rounds=0)[0]
        iterated = S.fit_relative_iterated([[1.0] * 4, [1.0 / n for n in ns]], ys)[0]
        self.assertLess(once[0], iterated[0])
        self.assertLess(iterated[0], 1e-3)


if __name__ == "__main__":
    unittest.main()
