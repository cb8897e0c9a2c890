"""tools/family-eval against the built qnav-sim: one world per family, its table's shape and
sense (arrival at twice the limit never below arrival at the limit), several policies
compared on the same worlds (the summary agrees with the rows it summarizes), and its
one-line errors for a bad family, a missing profile and a missing simulator."""
import os
import re
import subprocess
import sys
import unittest

TOOL = os.path.join(os.environ["QNAV_TOOLS_DIR"], "family-eval")
SIM = os.environ["QNAV_SIM_EXE"]
ROW = re.compile(r"^(\w+)\s+([\d.]+)% \[\s*([\d.]+),\s*([\d.]+)\]\s+([\d.]+)% \[\s*([\d.]+),\s*([\d.]+)\]"
                 r"\s+(\d+)/(\d+)\s+([\d.]+)\s+([\d.]+)$")


def tool(*args):
    return subprocess.run([sys.executable, TOOL, "--sim", SIM, *args], capture_output=True,
                          text=True, timeout=600)


class FamilyEval(unittest.TestCase):
    def test_one_world_per_family(self):
        r = tool("--worlds", "1", "--episodes", "2", "-j", "2")
        self.assertEqual(r.returncode, 0, r.stderr)
        rows = [ROW.match(l) for l in r.stdout.splitlines()[2:]]
        self.assertEqual([m.group(1) for m in rows if m],
                         ["clutter", "gaps", "corridor", "pocket", "rooms"], r.stdout)
        for m in rows:
            at1, lo1, hi1, at2 = (float(m.group(k)) for k in (2, 3, 4, 5))
            self.assertIn(at1, (0.0, 50.0, 100.0))
            self.assertLessEqual(lo1, at1)
            self.assertLessEqual(at1, hi1)
            self.assertGreaterEqual(at2, at1)
            self.assertEqual(m.group(9), "1")

    def test_policies_compared_on_the_same_worlds(self):
        fixtures = os.path.join(os.environ["QNAV_TOOLS_DIR"], "..", "bench", "fixtures", "policies")
        pols = [os.path.join(fixtures, n) for n in ("e12-n05-direct-r10.policy", "e04-dense16-s1.policy")]
        r = tool("--worlds", "2", "--episodes", "1", "-j", "2", "--policy", pols[0], "--policy", pols[1])
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = r.stdout.splitlines()
        per = {}
        for l in lines[2:5]:
            name, *cols = l.split()
            per[name] = [float(c) for c in cols]
        self.assertEqual(sorted(per)[-1], "reference", r.stdout)
        evolved = [v for k, v in per.items() if k != "reference"]
        self.assertEqual(len(evolved), 2, r.stdout)
        fams = ["clutter", "gaps", "corridor", "pocket", "rooms", "worst"]
        rows = {l.split()[0]: l for l in lines[7:]}
        self.assertEqual(list(rows), fams, r.stdout)
        for i, f in enumerate(fams):
            m = re.match(r"^\w+\s+([\d.]+) \[\s*([\d.]+),\s*([\d.]+)\]\s+([\d.]+)\s+([\d.]+)\s+(\d)/2\s+([\d.]+)"
                         r"\s+p ([\d.e+-]+) \((above|below|level)\)$", rows[f])
            self.assertTrue(m, rows[f])
            mean, lo, hi, p10, low, n95, ref = (float(m.group(k)) for k in range(1, 8))
            xs = [v[i] for v in evolved]
            self.assertAlmostEqual(mean, sum(xs) / 2, delta=0.051)
            self.assertAlmostEqual(low, min(xs), delta=0.051)
            self.assertTrue(lo <= mean <= hi and low <= p10 <= mean, rows[f])
            self.assertEqual(n95, sum(x >= 95 for x in xs))
            self.assertAlmostEqual(ref, per["reference"][i], delta=0.051)
            self.assertEqual(m.group(9), "above" if mean > ref else "below" if mean < ref else "level")

    def test_bad_input_is_one_line(self):
        for args, words in ((["--families", "bogus"], "unknown family 'bogus'"),
                            (["--robot", "/no/such/profile.toml"], "/no/such/profile.toml"),
                            (["--worlds", "0"], "at least 1")):
            r = tool("--worlds", "1", *args) if args[0] != "--worlds" else tool(*args)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn(words, r.stderr)
            self.assertNotIn("Traceback", r.stderr)

    def test_missing_simulator(self):
        r = subprocess.run([sys.executable, TOOL, "--sim", "/no/such/qnav-sim"],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 1)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)


if __name__ == "__main__":
    unittest.main()
