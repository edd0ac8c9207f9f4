"""Unit tests of python/cdemblast/analyses/monitor_spread.py on synthetic run summaries: the
points it adds, the monitors appended to a case, and the per-distance figures (ratios, points
within 20 %, mirrored left / right ratios), each checked against values worked out by hand.

Run by tests/unit/test_python.sh (CTest unit.test_python)."""

import json
import os
import tempfile
import unittest

from cdemblast.analyses import monitor_spread as ms

try:
    import tomllib
except ImportError:  # pragma: no cover
    tomllib = None


def write_summary(path, peaks):
    """A summary.json whose monitor `name` peaked at peaks[name] (Pa) at 1 ms."""
    with open(path, "w") as f:
        json.dump({"monitors": {name: {"peak_von_mises": p, "time": 1e-3} for name, p in peaks.items()}}, f)


class Points(unittest.TestCase):
    def test_mirrored_points_and_names(self):
        pts = ms.spread_points(2.0, {"m": 0.5}, [1.6, 1.75])
        self.assertEqual(pts, {"m_L_1600": (1.5, 1.6), "m_L_1750": (1.5, 1.75),
                               "m_R_1600": (2.5, 1.6), "m_R_1750": (2.5, 1.75)})

    @unittest.skipIf(tomllib is None, "needs Python 3.11's tomllib")
    def test_monitors_appended_to_the_case(self):
        text = ms.with_monitors('title = "t"\n[[monitor]]\nname = "a"\npoint = [1, 2]\n',
                                {"m_R_1750": (2.5, 1.75)})
        doc = tomllib.loads(text)
        self.assertEqual([m["name"] for m in doc["monitor"]], ["a", "m_R_1750"])
        self.assertEqual(doc["monitor"][1]["point"], [2.5, 1.75])


class Analyse(unittest.TestCase):
    def test_ratios_band_and_mirrors(self):
        pts = ms.spread_points(2.0, {"m": 0.5}, [1.6, 1.75])
        bar = {"m_L_1600": 900e6, "m_L_1750": 600e6, "m_R_1600": 450e6, "m_R_1750": 500e6}
        solid = {"m_L_1600": 1000e6, "m_L_1750": 500e6, "m_R_1600": 600e6, "m_R_1750": 500e6}
        with tempfile.TemporaryDirectory() as d:
            dirs = {}
            for c, p in (("bar", bar), ("solid", solid)):
                dirs[c] = os.path.join(d, c)
                os.makedirs(dirs[c])
                write_summary(os.path.join(dirs[c], "summary.json"), p)
            r = ms.analyse(dirs, pts, {"m": 0.5})
            ms.plot(r, os.path.join(d, "s.png"), {"m_R_1750"})
            self.assertGreater(os.path.getsize(os.path.join(d, "s.png")), 10000)
            ms.write_json(r, os.path.join(d, "s.json"))
            self.assertEqual(json.load(open(os.path.join(d, "s.json")))["by_distance"]["m"]["points"], 4)
        m = r["by_distance"]["m"]
        # ratios 0.9, 1.2, 0.75, 1.0: median 0.95, range 0.75-1.2, 3 within 20 % (1.2 is on the edge)
        self.assertAlmostEqual(m["ratio_median"], 0.95)
        self.assertAlmostEqual(m["ratio_min"], 0.75)
        self.assertAlmostEqual(m["ratio_max"], 1.2)
        self.assertEqual(m["points_within_20pct"], 3)
        # mean bar 612.5, mean solid 650
        self.assertAlmostEqual(m["ratio_of_means"], 612.5 / 650.0)
        # left / right at y 1.6 and 1.75: bar 2.0 and 1.2, solid 1000/600 and 1.0
        self.assertAlmostEqual(m["left_over_right_bar"][0], 1.2)
        self.assertAlmostEqual(m["left_over_right_bar"][1], 2.0)
        self.assertAlmostEqual(m["left_over_right_solid"][0], 1.0)
        self.assertAlmostEqual(m["left_over_right_solid"][1], 1000 / 600)
        row = next(q for q in r["points"] if q["point"] == "m_R_1750")
        self.assertAlmostEqual(row["t_bar_ms"], 1.0)
        self.assertIn("0.95 (0.75-1.20)", ms.table(r))


if __name__ == "__main__":
    unittest.main()
