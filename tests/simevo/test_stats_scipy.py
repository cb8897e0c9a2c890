"""stats.cpp (through tests/simevo/stats_cli) against python3-scipy 1.10: Welch's t-test
(scipy.stats.ttest_ind, equal_var=False), the one-sample t-test (ttest_1samp) and the
Mann-Whitney U test (mannwhitneyu: method='exact' for small samples without ties,
'asymptotic' without continuity correction otherwise), on seeded random samples of many
sizes, with and without ties. Usage: test_stats_scipy.py STATS_CLI"""
import subprocess
import sys
import unittest

import numpy as np
from scipy import stats

CLI = None
REL = 1e-9


def run(lines):
    out = subprocess.run([CLI], input="\n".join(lines) + "\n", capture_output=True, text=True,
                         check=True, timeout=300).stdout
    return [list(map(float, row.split())) for row in out.strip().splitlines()]


def csv(x):
    return ",".join(repr(float(v)) for v in x)


def samples(rng, n, ties):
    x = rng.normal(5.0, 2.0, n)
    return np.round(x, 0) if ties else x


class AgainstScipy(unittest.TestCase):
    def setUp(self):
        self.rng = np.random.default_rng(20261201)

    def assertClose(self, ours, theirs, what):
        self.assertTrue(abs(ours - theirs) <= REL * max(1.0, abs(theirs)),
                        f"{what}: stats.cpp {ours!r}, scipy {theirs!r}")

    def test_welch_t_test(self):
        cases = [(samples(self.rng, n1, False), samples(self.rng, n2, False) + shift)
                 for n1, n2, shift in [(2, 2, 0), (3, 7, 1), (5, 5, 0.5), (10, 4, -2), (30, 30, 0.3),
                                       (30, 12, 1.5), (100, 80, 0.1)]]
        got = run([f"welch {csv(a)} {csv(b)}" for a, b in cases])
        for (a, b), (t, df, p, valid) in zip(cases, got):
            ref = stats.ttest_ind(a, b, equal_var=False)
            va, vb = a.var(ddof=1) / len(a), b.var(ddof=1) / len(b)
            ref_df = (va + vb) ** 2 / (va ** 2 / (len(a) - 1) + vb ** 2 / (len(b) - 1))
            self.assertEqual(valid, 1)
            self.assertClose(t, ref.statistic, "Welch t")
            self.assertClose(df, ref_df, "Welch df")
            self.assertClose(p, ref.pvalue, "Welch p")

    def test_one_sample_t_test(self):
        cases = [(samples(self.rng, n, False), mu) for n, mu in
                 [(2, 0.0), (3, 5.0), (8, 4.0), (30, 5.5), (50, 9.0), (200, 5.0)]]
        got = run([f"one {csv(a)} {mu!r}" for a, mu in cases])
        for (a, mu), (t, df, p, valid) in zip(cases, got):
            ref = stats.ttest_1samp(a, mu)
            self.assertEqual(valid, 1)
            self.assertClose(t, ref.statistic, "one-sample t")
            self.assertEqual(df, len(a) - 1)
            self.assertClose(p, ref.pvalue, "one-sample p")

    def test_mann_whitney_exact_for_small_samples_without_ties(self):
        cases = [(samples(self.rng, n1, False), samples(self.rng, n2, False) + shift)
                 for n1, n2, shift in [(1, 1, 0), (2, 3, 1), (3, 3, 5), (4, 6, 0.5), (8, 8, 1),
                                       (5, 20, -1), (8, 30, 0.2), (30, 8, 2)]]
        got = run([f"mw {csv(a)} {csv(b)}" for a, b in cases])
        for (a, b), (z, p, valid, exact) in zip(cases, got):
            ref = stats.mannwhitneyu(a, b, alternative="two-sided", method="exact")
            self.assertEqual((valid, exact), (1, 1), f"sizes {len(a)}, {len(b)}")
            self.assertClose(p, ref.pvalue, f"exact Mann-Whitney p, sizes {len(a)}, {len(b)}")

    def test_mann_whitney_asymptotic_for_ties_and_large_samples(self):
        cases = [(samples(self.rng, n1, ties), samples(self.rng, n2, ties) + shift)
                 for n1, n2, shift, ties in [(4, 6, 1, True), (8, 8, 0, True), (9, 9, 0.5, False),
                                             (30, 30, 1, False), (30, 30, 0.5, True),
                                             (50, 12, 0, True)]]
        got = run([f"mw {csv(a)} {csv(b)}" for a, b in cases])
        for (a, b), (z, p, valid, exact) in zip(cases, got):
            ref = stats.mannwhitneyu(a, b, alternative="two-sided", method="asymptotic",
                                     use_continuity=False)
            self.assertEqual((valid, exact), (1, 0), f"sizes {len(a)}, {len(b)}")
            self.assertClose(p, ref.pvalue, f"asymptotic Mann-Whitney p, sizes {len(a)}, {len(b)}")
            # z of U_a: scipy's statistic is U_a
            u = ref.statistic
            self.assertEqual(np.sign(z), np.sign(u - len(a) * len(b) / 2))


if __name__ == "__main__":
    CLI = sys.argv.pop(1)
    unittest.main()
