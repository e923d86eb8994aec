"""report_units.py — unit tests of the pieces of scripts/report that compute: the Pareto front,
the sweep's points (each distinct point once, quadric without importance settings), the
agreement test of the stop rule's error, and points.csv (its columns, empty cells only where a
point has no value). Run by tests/test_report.c (python3 tests/report_units.py from the
repository root); exits non-zero when a test fails."""
import csv
import importlib.machinery
import importlib.util
import math
import os
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LOADER = importlib.machinery.SourceFileLoader("report", os.path.join(ROOT, "scripts", "report"))
SPEC = importlib.util.spec_from_loader("report", LOADER)
report = importlib.util.module_from_spec(SPEC)
LOADER.exec_module(report)


class ParetoFront(unittest.TestCase):
    def test_dominated_points_leave(self):
        points = [(10, 0.5), (5, 0.9), (20, 0.1), (12, 0.6), (5, 1.0), (30, 0.1)]
        # (12, 0.6) is beaten by (10, 0.5); (5, 1.0) by (5, 0.9); (30, 0.1) by (20, 0.1).
        self.assertEqual(report.pareto_front(points), [1, 0, 2])

    def test_one_point_and_none(self):
        self.assertEqual(report.pareto_front([(1, 1)]), [0])
        self.assertEqual(report.pareto_front([]), [])

    def test_equal_points_kept_once(self):
        self.assertEqual(report.pareto_front([(2, 0.3), (2, 0.3)]), [0])

    def test_front_against_brute_force(self):
        values = [((i * 37) % 11, ((i * 53) % 13) / 13) for i in range(40)]
        front = set(report.pareto_front(values))
        for i, (t, e) in enumerate(values):
            beaten = any((t2 <= t and e2 <= e) and (t2, e2) != (t, e) for t2, e2 in values)
            first_of_equals = values.index((t, e)) == i
            self.assertEqual(i in front, not beaten and first_of_equals, (i, t, e))


class Points(unittest.TestCase):
    def arguments(self, sweeps):
        with tempfile.TemporaryDirectory() as empty:
            return report.parse_arguments([os.path.join(ROOT, "data", "cornell", "scene.xml"),
                                           "-o", empty, "--sweeps", sweeps, "--targets",
                                           "0.1,0.03", "--methods", "quadric,combined",
                                           "--iteration-counts", "5,20", "--photons", "1000"])

    def test_shared_points_measured_once(self):
        points = report.sweep_points(self.arguments("iterations,photons,gamma,targets"))
        keys = [report.point_key(p) for p, _ in points]
        self.assertEqual(len(keys), len(set(keys)))
        base = [sweeps for p, sweeps in points if p["method"] == "combined" and
                p["target"] == 0.1 and p.get("stop") == "rule" and p["photons"] == 1000 and
                p["gamma"] == 1]
        self.assertEqual(base, [["iterations", "photons", "gamma", "targets"]])
        # iterations: 5, 20 fixed and the rule; photons: 250 and 4000 more; gamma: 0, 0.25, 4;
        # targets: quadric at both D, combined at 0.03.
        self.assertEqual(len(points), 3 + 2 + 3 + 3)

    def test_quadric_has_no_importance_settings(self):
        points = report.sweep_points(self.arguments("targets"))
        quadric = [p for p, _ in points if p["method"] == "quadric"]
        self.assertEqual(len(quadric), 2)
        for p in quadric:
            self.assertFalse(set(p) & set(report.IMPORTANCE_COLUMNS))
            self.assertEqual(report.reduce_options(p), ["--method", "quadric"])
        combined = [p for p, _ in points if p["method"] == "combined"][0]
        self.assertNotIn("--factor-tolerance", report.reduce_options(combined))


    def test_weights_come_from_one_simulation(self):
        points = report.sweep_points(self.arguments("gamma,shadow"))
        stops = [p.get("stop") for p, _ in points]
        # The base point first (its stop rule chooses the simulation's iterations), then the
        # other weights, each read from the saved simulation.
        self.assertEqual(stops[0], "rule")
        self.assertEqual(set(stops[1:]), {"simulation"})
        self.assertEqual(len(points), 1 + 3 + 2)  # gamma 0, 0.25, 4; shadow weight 0, 4
        options = report.reduce_options(points[1][0], "sim/simulation.bin")
        self.assertIn("--simulation", options)
        self.assertNotIn("--iterations", options)


class StopRuleAgreement(unittest.TestCase):
    def test_within_combined_standard_error(self):
        longest = {"reduction_rmse": 1.0, "standard_error": 0.03}
        self.assertTrue(report.within_standard_error(
            {"reduction_rmse": 1.04, "standard_error": 0.04}, longest))  # 0.04 <= 0.05
        self.assertFalse(report.within_standard_error(
            {"reduction_rmse": 1.06, "standard_error": 0.04}, longest))


class PointsCsv(unittest.TestCase):
    def test_columns_and_cells(self):
        rows = [{"scene": "s", "sweeps": "targets", "label": "quadric-0.1", "method": "quadric",
                 "target": 0.1, "vertices": 10, "reduction_rmse": 0.25, "standard_error": 1e-3}]
        with tempfile.TemporaryDirectory() as directory:
            path = os.path.join(directory, "points.csv")
            report.write_points(path, rows)
            with open(path) as f:
                table = list(csv.reader(f))
            self.assertFalse(os.path.exists(path + ".tmp"))
        self.assertEqual(tuple(table[0]), report.COLUMNS)
        row = dict(zip(table[0], table[1]))
        self.assertEqual(row["stop"], "")
        self.assertEqual(float(row["reduction_rmse"]), 0.25)
        self.assertTrue(math.isfinite(float(row["standard_error"])))


if __name__ == "__main__":
    result = unittest.main(exit=False, verbosity=2).result
    sys.exit(0 if result.wasSuccessful() and not result.skipped else 1)
