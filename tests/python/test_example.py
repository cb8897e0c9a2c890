"""examples/python/evolve_policy.py, briefly (python.example_evolve): it evolves, keeps the
best (its training R never falls: the strategy is elitist on fixed episodes), writes a
policy file that reads back, prints the held-out comparison and draws the trajectory."""

import os
import re
import subprocess
import sys
import tempfile
import unittest

import qnavpy

SCRIPT = os.path.join(os.environ["QNAV_SOURCE_DIR"], "examples", "python", "evolve_policy.py")


class EvolvePolicyExample(unittest.TestCase):
    def test_a_short_run_evolves_writes_the_policy_and_draws_the_episode(self):
        with tempfile.TemporaryDirectory() as out:
            p = subprocess.run([sys.executable, SCRIPT, "--generations", "4", "--children", "4", "--episodes", "2",
                                "--held-out", "4", "--hidden", "3", "--out", out, "--jobs", "2"],
                               capture_output=True, text=True, timeout=300)
            self.assertEqual(p.returncode, 0, p.stderr)
            best = [float(m) for m in re.findall(r"^generation +\d+: best training R +(\S+)", p.stdout, re.M)]
            self.assertEqual(len(best), 4, p.stdout)
            self.assertEqual(best, sorted(best), "an elitist strategy lost its best")
            self.assertEqual(len(re.findall(r"^held-out \(4 episodes, seed 1001\): (evolved|probabilistic) +mean R",
                                            p.stdout, re.M)), 2, p.stdout)
            policy = qnavpy.Policy.read(os.path.join(out, "best.policy"))
            self.assertEqual((policy.kind, policy.hidden, len(policy.raw)), ("net", 3, 13))
            with open(os.path.join(out, "trajectory.png"), "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
            self.assertRegex(p.stdout, r"trajectory .*trajectory\.png \(tekbot, dense, evolved network \(H = 3\): "
                                       r"(reached|not reached) in [\d.]+ s, R -?[\d.]+\)")


if __name__ == "__main__":
    unittest.main()
