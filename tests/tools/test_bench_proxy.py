"""tools/bench-proxy: the network-mode steps measured both in simavr cycles and in hidden-unit
evaluations are paired by H, N, policy, set and scan, and each sector count gets its
correlation, least-squares line and worst cases; other steps are left out; bad input is named
by file and line with exit status 2."""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.environ.get("QNAV_TOOLS_DIR") or os.path.join(HERE, "..", "..", "tools")
PROXY = os.path.join(TOOLS, "bench-proxy")


def m(target, policy, scan, value, n=32, mode="network", set_name="adversary"):
    return (f"M\ttarget={target}\tmode={mode}\tH=12\tN={n}\tpolicy={policy}\tset={set_name}"
            f"\tscan={scan}\t{value}\n")


def run_on(avr, count):
    with tempfile.TemporaryDirectory() as d:
        paths = []
        for name, text in (("avr.txt", avr), ("count.txt", count)):
            paths.append(os.path.join(d, name))
            with open(paths[-1], "w") as f:
                f.write(text)
        res = subprocess.run([sys.executable, PROXY, *paths], capture_output=True, text=True,
                             timeout=120)
        return paths, res


class Pairs(unittest.TestCase):
    def test_an_exact_line_is_found_with_r_one(self):
        # cycles = 20000 + 200 x evaluations
        avr = m("avr", "p1", "adversary:0", 20000) + m("avr", "p2", "adversary:1", 220000) + \
            m("avr", "p3", "adversary:2", 420000)
        count = m("count", "p1", "adversary:0", 0) + m("count", "p2", "adversary:1", 1000) + \
            m("count", "p3", "adversary:2", 2000)
        _, res = run_on(avr, count)
        self.assertEqual(res.returncode, 0, res.stderr)
        self.assertIn("N = 32 (adversary): 3 steps, evaluations 0..2000, cycles 20000..420000",
                      res.stdout)
        self.assertIn("Pearson r 1.0000, Spearman 1.0000", res.stdout)
        self.assertIn("cycles = 20000 + 200.0 x evaluations", res.stdout)

    def test_worst_by_count_and_by_cycles_are_named(self):
        avr = m("avr", "p1", "adversary:0", 500000) + m("avr", "p2", "adversary:1", 400000)
        count = m("count", "p1", "adversary:0", 1900) + m("count", "p2", "adversary:1", 2000)
        _, res = run_on(avr, count)
        self.assertIn("worst by count: p2 adversary:1 (H 12, adversary set) (2000 evaluations, "
                      "400000 cycles)", res.stdout)
        self.assertIn("worst by cycles: p1 adversary:0 (H 12, adversary set)", res.stdout)

    def test_steps_measured_once_or_in_other_modes_are_left_out(self):
        avr = m("avr", "p1", "adversary:0", 1000) + m("avr", "p2", "adversary:1", 3000) + \
            m("avr", "p3", "adversary:2", 9999) + m("avr", "p1", "clear:0", 7, mode="table")
        count = m("count", "p1", "adversary:0", 1) + m("count", "p2", "adversary:1", 3) + \
            m("count", "p1", "clear:0", 7, mode="table")
        _, res = run_on(avr, count)
        self.assertIn("N = 32 (adversary): 2 steps", res.stdout)

    def test_sector_counts_are_fitted_apart(self):
        avr = m("avr", "p1", "adversary:0", 100) + m("avr", "p2", "adversary:1", 300) + \
            m("avr", "p1", "adversary:2", 1000, n=180) + m("avr", "p2", "adversary:3", 1100, n=180)
        count = m("count", "p1", "adversary:0", 1) + m("count", "p2", "adversary:1", 3) + \
            m("count", "p1", "adversary:2", 1, n=180) + m("count", "p2", "adversary:3", 3, n=180)
        _, res = run_on(avr, count)
        self.assertIn("cycles = 0 + 100.0 x evaluations", res.stdout)
        self.assertIn("cycles = 950 + 50.0 x evaluations", res.stdout)


class BadInput(unittest.TestCase):
    def test_a_bad_m_line_names_file_and_line(self):
        paths, res = run_on("text\n" + m("avr", "p1", "adversary:0", 12.5), m("count", "p1", "adversary:0", 1))
        self.assertEqual(res.returncode, 2)
        self.assertIn(f"{paths[0]}:2: ", res.stderr)
        self.assertIn("value '12.5'", res.stderr)

    def test_no_pairs_is_bad_input(self):
        _, res = run_on(m("avr", "p1", "adversary:0", 10), m("count", "p2", "adversary:0", 1))
        self.assertEqual(res.returncode, 2)
        self.assertIn("no network-mode step has both", res.stderr)


if __name__ == "__main__":
    unittest.main()
