"""Unit tests of the study's helpers (python/cdemblast/study.py): --set overrides on a case,
the resolved-case match that decides a resume, the recommendation's lexicographic choice, the
design funnel and the volume-weighted grading."""

import unittest

import numpy as np

from cdemblast import study as st


class Overrides(unittest.TestCase):
    def test_apply_set_paths_and_indices(self):
        case = {"simulation": {"end_time": 1e-3}, "hole": [{"charge": [{"length": 0.5}]}]}
        st.apply_set(case, "simulation.end_time", st.parse_value("2e-3"))
        st.apply_set(case, "hole.0.charge.0.length", st.parse_value("0.25"))
        st.apply_set(case, "mesh.generate.element_size", st.parse_value("0.2"))
        self.assertEqual(case["simulation"]["end_time"], 2e-3)
        self.assertEqual(case["hole"][0]["charge"][0]["length"], 0.25)
        self.assertEqual(case["mesh"]["generate"]["element_size"], 0.2)
        with self.assertRaises(st.StudyError):
            st.apply_set(case, "hole.3.diameter", 0.1)
        with self.assertRaises(st.StudyError):
            st.parse_value("bare_word")
        self.assertEqual(st.parse_value('"roller"'), "roller")
        self.assertEqual(st.split_set(" a.b = [1, 2] "), ("a.b", "[1, 2]"))

    def test_resolved_case_match(self):
        resolved = {"mesh": {"generate": {"size": [4, 2, 0], "element_size": 0.10000000000000001,
                                          "quads": True, "circle_segments": 16}},
                    "hole": [{"collar": [2, 2, 0], "charge": [{"length": 0.5, "delay": 0}]}]}
        want = {"mesh": {"generate": {"size": [4.0, 2.0], "element_size": 0.1, "quads": True}},
                "hole": [{"collar": [2.0, 2.0], "charge": [{"length": 0.5}]}]}
        self.assertTrue(st.same_value(want, resolved))
        want["hole"][0]["charge"][0]["length"] = 0.25
        self.assertFalse(st.same_value(want, resolved))
        self.assertFalse(st.same_value({"quads": 1}, {"quads": True}))  # bool is not a number


class Recommendation(unittest.TestCase):
    def test_lexicographic_pick_with_tolerance(self):
        names = ["a", "b", "c"]
        first = {"a": 10.0, "b": 10.2, "c": 20.0}     # a and b tie within 5 %
        second = {"a": 3.0, "b": 2.0, "c": 1.0}
        w, decided, trail = st.pick([first, second], [False, False], 0.05, names)
        self.assertEqual((w, decided), ("b", 1))
        self.assertEqual(trail[0], ["a", "b"])
        w, decided, _ = st.pick([first, second], [True, False], 0.05, names)
        self.assertEqual((w, decided), ("c", 0))
        w, decided, trail = st.pick([{"a": 1.0, "b": 1.0}], [True], 0.05, ["a", "b"])
        self.assertIsNone(w)  # a tie on every criterion: no clear winner
        self.assertEqual(trail[-1], ["a", "b"])


class FlyRockQuantiles(unittest.TestCase):
    def test_weighted_quantile(self):
        # four fragments: 1 m3 at 1 m/s, 1 m3 at 2 m/s, 1.9 m3 at 3 m/s, and a 1e-4 m3 splinter
        # at 2 780 m/s (the kind of outlier that decided the coarse SPEC 5.3 study)
        sp = np.array([2780.0, 1.0, 3.0, 2.0])
        vol = np.array([1e-4, 1.0, 1.9, 1.0])
        self.assertEqual(st.weighted_quantile(sp, vol, 0.95), 3.0)  # the splinter is < 5 %
        self.assertEqual(st.weighted_quantile(sp, vol, 1.0), 2780.0)  # q = 1: the largest
        self.assertEqual(st.weighted_quantile(sp, vol, 0.5), 2.0)   # 2 of 3.9 m3 at <= 2 m/s
        self.assertEqual(st.weighted_quantile(sp, vol, 0.25), 1.0)
        # equal weights: the order statistic ceil(q n)
        self.assertEqual(st.weighted_quantile(np.arange(1.0, 11.0), np.ones(10), 0.9), 9.0)
        # no data, NaN and zero weights are left out
        self.assertIsNone(st.weighted_quantile([], [], 0.9))
        self.assertEqual(st.weighted_quantile([np.nan, 5.0, 7.0], [1.0, 1.0, 0.0], 0.99), 5.0)

    def test_quantile_keys_are_checked(self):
        class S:
            path = "study.toml"
            recommend = {}
        self.assertEqual(st.fly_rock_quantiles(S()), (0.95, 0.99))
        S.recommend = {"speed_quantile": 0.9, "rise_quantile": 1}
        self.assertEqual(st.fly_rock_quantiles(S()), (0.9, 1.0))
        for bad in (0, 1.5, "0.9", True, -0.1):
            S.recommend = {"speed_quantile": bad}
            with self.assertRaisesRegex(st.StudyError, r"\[recommend\] speed_quantile"):
                st.fly_rock_quantiles(S())

    def test_an_outlier_does_not_decide_the_fly_rock_goal(self):
        def measure(name, q_speed, max_speed, q_rise):
            return {"name": name, "label": name, "design_funnel": None,
                    "grading": {"d80_m": 0.2, "d40_m": 0.1},
                    "fracture_degree": {"total": 0.9, "by_region": None},
                    "fly_rock": {"quantile_launch_speed_m_s": q_speed,
                                 "max_launch_speed_m_s": max_speed, "quantile_rise_m": q_rise}}

        class S:
            path = "study.toml"
            recommend = {}
            design = None
        # a throws its bulk faster; b has one splinter at 2 780 m/s
        ms = [measure("a", 12.0, 40.0, 1.5), measure("b", 6.0, 2780.0, 0.8)]
        rec = st.recommend(ms, S())
        fly = next(g for g in rec["goals"] if g["goal"] == "limits fly-rock")
        self.assertEqual(fly["winner"], "b")
        self.assertEqual(rec["most_fly_rock"], "a")


class Funnel(unittest.TestCase):
    def test_box_and_cylinder(self):
        pts = np.array([[0.5, 0.5, 0.0], [2.0, 0.5, 0.0], [0.0, 0.0, -0.5], [0.0, 0.0, -1.5],
                        [0.9, 0.0, -0.2]])
        box = st.in_funnel(pts, {"shape": "box", "lo": [0, 0], "hi": [1, 1]}, np.array([0, 1, 0.]))
        self.assertEqual(box.tolist(), [True, False, True, True, True])  # 2D box: any z
        cyl = st.in_funnel(pts, {"shape": "cylinder", "center": [0, 0, 0], "radius": 0.8,
                                 "depth": 1.0}, np.array([0, 0, 1.0]))
        self.assertEqual(cyl.tolist(), [True, False, True, False, False])

    def test_passing_sizes(self):
        d, s, cum = st.passing_sizes(np.array([0.3, 0.1, 0.2]), np.array([1.0, 1.0, 2.0]))
        self.assertEqual(s.tolist(), [0.1, 0.2, 0.3])
        self.assertEqual(cum.tolist(), [25.0, 75.0, 100.0])
        self.assertAlmostEqual(d["d50_m"], 0.15)
        self.assertAlmostEqual(d["d80_m"], 0.2 + 0.1 * 5 / 25)


if __name__ == "__main__":
    unittest.main()


class PerRegionAndWarnings(unittest.TestCase):
    def test_fracture_per_region_columns_are_drawn_and_their_absence_noted(self):
        import os
        import tempfile
        from types import SimpleNamespace
        t = np.linspace(0, 1e-3, 11)
        with_cols = {"time": t, "degree_area": t * 100, "degree_area_rock": t * 50,
                     "degree_area_ring": t * 300}
        plain = {"time": t, "degree_area": t * 100}
        v1 = SimpleNamespace(label="A", run=SimpleNamespace(fracture=with_cols))
        v2 = SimpleNamespace(label="B", run=SimpleNamespace(fracture=plain))
        with tempfile.TemporaryDirectory() as d:
            written, notes = [], []
            self.assertEqual(st.plot_fracture_regions([v1, v2], d, written, notes),
                             "fracture_regions.png")
            self.assertTrue(os.path.getsize(os.path.join(d, "fracture_regions.png")) > 1000)
            self.assertEqual(notes, [])
            self.assertIsNone(st.plot_fracture_regions([v2], d, written, notes))
            self.assertIn("per-region", notes[0])

    def test_summary_warnings_are_merged(self):
        from cdemblast import checks
        ours = [checks.warning("energy_error", "ours")]
        theirs = ["a plain string", {"code": "energy_error", "message": "theirs"},
                  {"code": "charge_larger_than_block", "message": "per block", "value": 1.7}]
        merged = checks.merge(ours, theirs)
        self.assertEqual([w["message"] for w in merged], ["ours", "a plain string", "per block"])
        self.assertEqual(merged[2]["value"], 1.7)
        self.assertEqual(checks.merge([], None), [])
