"""evaluation_units.py — unit tests of scripts/evaluation.py: method specs with further reduce
options (method_spec: METHOD:OPTION=VALUE...), and the pooling of a method's reduction errors
over its importance seeds (pool_draws, what `scripts/evaluate --importance-seeds N`
reports): the mean of the squared errors against exact sums, the standard error from the seeds'
spread or from the renders, whichever is larger, and a mean below zero (the renders' noise
larger than the change) reported as 0 with a finite error. Run by tests/test_report.c (python3
tests/evaluation_units.py from the repository root); exits non-zero when a test fails."""
import math
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                "scripts"))
from evaluation import method_spec, pool_draws  # noqa: E402


def draw(mse, se, flip=0.1, noisy=0.5, reference=0.2):
    return {"reduction_mse": mse, "mse_standard_error": se, "flip": flip, "noisy_rmse": noisy,
            "rmse_vs_reference": reference}


class MethodSpec(unittest.TestCase):
    def test_a_bare_method_has_no_options(self):
        self.assertEqual(method_spec("combined"), ("combined", [], "combined"))

    def test_options_become_reduce_arguments_and_label(self):
        self.assertEqual(method_spec("combined:initial=0.05:passes=2"),
                         ("combined", ["--initial", "0.05", "--passes", "2"],
                          "combined-initial0.05-passes2"))

    def test_malformed_options_are_refused(self):
        for bad in ("combined:initial", "combined:=2", "combined:passes=", ":passes=2"):
            with self.assertRaises(ValueError):
                method_spec(bad)


class PoolDraws(unittest.TestCase):
    def test_one_draw_is_its_own_figure(self):
        p = pool_draws([draw(4e-4, 1e-4)])
        self.assertAlmostEqual(p["reduction_mse"], 4e-4, delta=1e-18)
        self.assertAlmostEqual(p["reduction_rmse"], 0.02, delta=1e-15)
        self.assertAlmostEqual(p["mse_standard_error"], 1e-4, delta=1e-18)
        # idmr compare's rule: half the difference of sqrt(mse ± se).
        self.assertAlmostEqual(p["standard_error"], 0.5 * (math.sqrt(5e-4) - math.sqrt(3e-4)),
                               delta=1e-15)

    def test_spread_of_seeds_sets_the_error(self):
        # Squared errors 1, 2, 3, 6 (e-4): mean 3e-4, sample variance 14/3 e-8, so the error of
        # the mean is sqrt(14/3)/2 e-4; the renders' own (1e-6 each) is far smaller.
        p = pool_draws([draw(m * 1e-4, 1e-6) for m in (1, 2, 3, 6)])
        self.assertAlmostEqual(p["reduction_mse"], 3e-4, delta=1e-18)
        self.assertAlmostEqual(p["reduction_rmse"], math.sqrt(3e-4), delta=1e-15)
        self.assertAlmostEqual(p["mse_standard_error"], math.sqrt(14 / 3) / 2 * 1e-4,
                               delta=1e-18)

    def test_render_noise_sets_the_error_when_seeds_agree(self):
        p = pool_draws([draw(2e-4, 5e-5), draw(2e-4, 5e-5)])
        self.assertAlmostEqual(p["mse_standard_error"], math.sqrt(2 * 25e-10) / 2, delta=1e-18)

    def test_other_figures_are_means(self):
        p = pool_draws([draw(1e-4, 0, flip=0.1, noisy=0.4, reference=0.3),
                        draw(3e-4, 0, flip=0.3, noisy=0.6, reference=0.5)])
        self.assertAlmostEqual(p["flip"], 0.2, delta=1e-15)
        self.assertAlmostEqual(p["noisy_rmse"], 0.5, delta=1e-15)
        self.assertAlmostEqual(p["rmse_vs_reference"], 0.4, delta=1e-15)

    def test_negative_mean_is_zero_and_finite(self):
        # Mean -5e-7, error sqrt(2 * 4e-12) / 2: the root is 0, its error half sqrt(mse + se).
        p = pool_draws([draw(-1e-6, 2e-6), draw(0.0, 2e-6)])
        se = math.sqrt(8e-12) / 2
        self.assertEqual(p["reduction_rmse"], 0.0)
        self.assertAlmostEqual(p["mse_standard_error"], se, delta=1e-20)
        self.assertAlmostEqual(p["standard_error"], 0.5 * math.sqrt(-5e-7 + se), delta=1e-15)


if __name__ == "__main__":
    unittest.main()
