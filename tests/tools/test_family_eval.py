"""tools/family-eval against the built qnav-sim: one world per family, its table's shape and
sense (arrival at twice the limit never below arrival at the limit), and its one-line
errors for a bad family, a missing profile and a missing simulator."""
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
