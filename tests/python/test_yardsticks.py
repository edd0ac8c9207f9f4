"""Unit tests of python/cdemblast/yardsticks.py: Kuz-Ram, Rosin-Rammler, Swebrec, the PPV fit.

Run by tests/unit/test_python.sh (CTest unit.test_python):
    PYTHONPATH=python /usr/bin/python3 -m unittest discover -s tests/python
"""

import math
import unittest

import numpy as np

from cdemblast import yardsticks as y


class KuzRam(unittest.TestCase):
    def test_kuznetsov_for_tnt_is_the_original_equation(self):
        # Kuznetsov (1973) wrote x = A K^-0.8 Q^(1/6) for TNT; Cunningham's strength term
        # (115 / RWS)^(19/30) is 1 for TNT (RWS 115).
        for A, K, Q in ((7, 0.5, 100), (10, 0.8, 250), (13, 0.3, 30)):
            self.assertAlmostEqual(y.kuznetsov_x50(A, K, Q, rws=115) * 100,
                                   A * K ** -0.8 * Q ** (1 / 6), places=10)

    def test_hand_worked_example(self):
        # A hand calculation from the published equations (Cunningham 1983, 1987), each
        # factor written out so that it can be checked with a calculator:
        #   A = 7, K = 0.5 kg/m3, Q = 100 kg of ANFO (RWS 100):
        #   0.5^-0.8 = 2^0.8 = 1.741101, 100^(1/6) = 10^(1/3) = 2.154435,
        #   (115/100)^(19/30) = exp(0.633333 x 0.139762) = 1.092552,
        #   x50 = 7 x 1.741101 x 2.154435 x 1.092552 = 28.688 cm.
        self.assertAlmostEqual(y.kuznetsov_x50(7, 0.5, 100, 100) * 100, 28.688, places=2)
        #   B = 3 m, S = 3.5 m, d = 102 mm, L = 8 m, H = 10 m, W = 0:
        #   n = (2.2 - 14 x 3/102) x sqrt((1 + 3.5/3)/2) x 1 x 8/10
        #     = 1.788235 x 1.040833 x 0.8 = 1.48900.
        self.assertAlmostEqual(y.uniformity_index(3, 3.5, 0.102, 8, 10), 1.48900, places=4)
        self.assertAlmostEqual(y.uniformity_index(3, 3.5, 0.102, 8, 10, staggered=True),
                               1.1 * 1.48900, places=4)
        # The design form: powder factor Q / (B S H) = 100 / 105 kg/m3.
        k = y.KuzRam({"rock_factor": 7, "burden": 3, "spacing": 3.5, "bench_height": 10,
                      "hole_diameter": 0.102, "charge_length": 8, "charge_per_hole": 100})
        self.assertAlmostEqual(k.k, 100 / 105, places=12)
        self.assertAlmostEqual(k.x50, y.kuznetsov_x50(7, 100 / 105, 100), places=12)

    def test_the_19_20_exponent_of_cunningham_2005(self):
        a = y.kuznetsov_x50(8, 0.6, 200, 80, rws_exponent=19 / 20)
        self.assertAlmostEqual(a * 100, 8 * 0.6 ** -0.8 * 200 ** (1 / 6) * (115 / 80) ** 0.95,
                               places=10)

    def test_refuses_nonsense(self):
        with self.assertRaises(ValueError):
            y.kuznetsov_x50(7, 0.0, 100)
        with self.assertRaises(ValueError):
            y.KuzRam({"rock_factor": 7})


class Curves(unittest.TestCase):
    def test_rosin_rammler_median_and_inverse(self):
        x50, n = 0.3, 1.4
        self.assertAlmostEqual(float(y.rosin_rammler(x50, x50, n)), 0.5, places=12)
        for p in (0.1, 0.4, 0.8, 0.9):
            self.assertAlmostEqual(float(y.rosin_rammler(y.size_at(p, x50, n), x50, n)), p, 12)

    def test_swebrec_shape(self):
        # Ouchterlony (2005): P(x50) = 1/2, P -> 1 at xmax, P -> 0 as x -> 0, monotone.
        x50, xmax, b = 0.25, 1.5, 2.3
        self.assertAlmostEqual(float(y.swebrec(np.array([x50]), x50, xmax, b)[0]), 0.5, 12)
        self.assertEqual(float(y.swebrec(np.array([xmax]), x50, xmax, b)[0]), 1.0)
        self.assertLess(float(y.swebrec(np.array([1e-30]), x50, xmax, b)[0]), 1e-3)  # slowly: log
        xs = np.linspace(1e-3, xmax, 200)
        self.assertTrue(np.all(np.diff(y.swebrec(xs, x50, xmax, b)) >= 0))
        for p in (0.2, 0.4, 0.8):
            x = y.size_at(p, x50, None, "swebrec", xmax, b)
            self.assertAlmostEqual(float(y.swebrec(np.array([x]), x50, xmax, b)[0]), p, 12)

    def test_kco_link(self):
        # b = 2 ln 2 ln(xmax / x50) n (Ouchterlony 2005, the KCO model): the Swebrec curve then
        # has the Rosin-Rammler curve's slope at the median on log axes: dP/dln x = n ln2 / 2.
        x50, xmax, n = 0.2, 1.0, 1.3
        b = y.swebrec_b(x50, xmax, n)
        self.assertAlmostEqual(b, 2 * math.log(2) * math.log(5) * 1.3, places=12)
        h = 1e-6
        xs = np.array([x50 * math.exp(-h), x50 * math.exp(h)])
        sw = y.swebrec(xs, x50, xmax, b)
        rr = y.rosin_rammler(xs, x50, n)
        self.assertAlmostEqual((sw[1] - sw[0]) / (2 * h), (rr[1] - rr[0]) / (2 * h), places=6)


class Ppv(unittest.TestCase):
    def test_fit_recovers_k_and_beta_exactly(self):
        sd = np.array([2.0, 5.0, 10.0, 20.0, 50.0])
        v = 1140.0 * sd ** -1.6
        fit = y.fit_ppv(sd, v)
        self.assertAlmostEqual(fit["K"], 1140.0, places=6)
        self.assertAlmostEqual(fit["beta"], 1.6, places=10)
        self.assertAlmostEqual(fit["r2"], 1.0, places=12)

    def test_fit_recovers_k_and_beta_from_noisy_data(self):
        rng = np.random.default_rng(7)
        sd = np.geomspace(1.0, 100.0, 400)
        v = 500.0 * sd ** -1.3 * np.exp(rng.normal(0.0, 0.2, sd.size))
        fit = y.fit_ppv(sd, v)
        self.assertLess(abs(fit["beta"] - 1.3), 0.05)
        self.assertLess(abs(math.log(fit["K"] / 500.0)), 0.1)
        self.assertGreater(fit["r2"], 0.9)

    def test_fit_needs_two_distances(self):
        self.assertIsNone(y.fit_ppv([3.0, 3.0], [1.0, 2.0]))
        self.assertIsNone(y.fit_ppv([], []))

    def test_charge_per_delay(self):
        decks = [{"delay_s": 0.0, "mass_kg": 2.0}, {"delay_s": 0.005, "mass_kg": 3.0},
                 {"delay_s": 0.02, "mass_kg": 4.0}, {"delay_s": 0.03, "mass_kg": 4.5}]
        self.assertEqual(y.charge_per_delay(decks), 5.0)   # 0 and 5 ms within 8 ms
        self.assertEqual(y.charge_per_delay(decks, window=0.011), 8.5)
        self.assertAlmostEqual(y.distance_to_segment([1, 1], [0, 0], [0, 2]), 1.0)
        self.assertAlmostEqual(y.distance_to_segment([0, 3, 0], [0, 0, 0], [0, 2, 0]), 1.0)


if __name__ == "__main__":
    unittest.main()
