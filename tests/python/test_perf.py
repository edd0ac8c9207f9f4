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


class Roofline(unittest.TestCase):
    # a report of the shape bench --json writes: 400 flop per block over 800 B in the block
    # kernel at 8 GFlop/s, the step 2000 B per block at 100 ns
    rep = {"blocks": 1000, "tet_flops_per_block": 400.0, "block_kernel_bytes_per_block": 800.0,
           "block_kernel_gflops": 8.0, "step_bytes_estimate": 2000.0 * 1000, "ns_per_block_step": 100.0,
           "peak_gflops": 100.0, "triad_gb_s": 30.0, "triad_ws_gb_s": 80.0}

    def test_points(self):
        p = perf.roofline_points(self.rep)
        self.assertAlmostEqual(p["kernel_ai"], 0.5)
        self.assertAlmostEqual(p["kernel_gflops"], 8.0)
        self.assertAlmostEqual(p["step_ai"], 0.2)
        self.assertAlmostEqual(p["step_gflops"], 4.0)  # 400 flop in 100 ns

    def test_picture_is_a_real_png(self):
        with tempfile.TemporaryDirectory() as d:
            path = perf.plot_roofline([("a", self.rep), ("b", dict(self.rep, block_kernel_gflops=4.0))],
                                      os.path.join(d, "roof.png"), "t")
            with open(path, "rb") as f:
                data = f.read()
            self.assertEqual(data[:8], b"\x89PNG\r\n\x1a\n")
            self.assertGreater(len(data), 20000)


if __name__ == "__main__":
    unittest.main()
