"""Unit tests of python/cdemblast/perf.py: the cost-growth rows, table and picture from bench
reports (synthetic ones here, of the shape `cdemblast bench --json` writes).

Run by tests/unit/test_python.sh (CTest unit.test_python)."""

import os
import tempfile
import unittest

from cdemblast import perf


def report(blocks, ns2, ns1, setup):
    return {"blocks": blocks, "ns_per_block_step_2_threads": ns2, "ns_per_block_step_1_thread": ns1,
            "speedup_2_threads": ns1 / ns2, "bytes_per_block_with_solver": 1000.0 + blocks % 7,
            "setup_s": {"total": setup, "mesh": 0.1 * setup, "topology": 0.2 * setup,
                        "charges": 0.0, "simulation": 0.7 * setup}}


class CostGrowth(unittest.TestCase):
    def setUp(self):
        # given out of order: the rows come sorted by size
        self.rows = perf.growth_rows([report(300000, 110.0, 190.0, 6.0), report(30000, 100.0, 180.0, 0.6),
                                      report(1000000, 120.0, 200.0, 22.0)])

    def test_rows_sorted_with_ratios_to_the_smallest(self):
        self.assertEqual([r["blocks"] for r in self.rows], [30000, 300000, 1000000])
        self.assertAlmostEqual(self.rows[0]["ns_2t_ratio"], 1.0)
        self.assertAlmostEqual(self.rows[2]["ns_2t_ratio"], 1.2)
        self.assertAlmostEqual(self.rows[1]["setup_us_per_block"], 20.0)
        self.assertAlmostEqual(self.rows[2]["setup_simulation_s"], 15.4)

    def test_table_has_a_row_per_size(self):
        t = perf.growth_table(self.rows).splitlines()
        self.assertEqual(len(t), 2 + 3)
        self.assertIn("1 000 000", t[-1])
        self.assertIn("= 22.00", t[-1])

    def test_picture_is_a_real_png(self):
        with tempfile.TemporaryDirectory() as d:
            path = perf.plot_growth(self.rows, os.path.join(d, "growth.png"), "t")
            with open(path, "rb") as f:
                data = f.read()
            self.assertEqual(data[:8], b"\x89PNG\r\n\x1a\n")
            self.assertGreater(len(data), 20000)  # three panels of lines and bars, not a blank page


if __name__ == "__main__":
    unittest.main()
