"""tools/fit-network against the built qnavpy: the network it writes gives, through libqnav,
the robot's probabilistic policy's quality over every (level, dtheta) to within a few
thousandths, and a clear row still prefers the smallest turn; it never
overwrites a file, and a bad robot or hidden count is one line and a non-zero exit."""
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

import qnavpy

TOOL = os.path.join(os.environ["QNAV_TOOLS_DIR"], "fit-network")


def tool(*args):
    return subprocess.run([sys.executable, TOOL, *args], capture_output=True, text=True,
                          timeout=600)


class FitNetwork(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.out = os.path.join(self.tmp.name, "fit.policy")

    def tearDown(self):
        self.tmp.cleanup()

    def test_the_fitted_network_gives_the_probabilistic_quality(self):
        r = tool("--robot", "tekbot", "--starts", "1", "--iterations", "1500", "--out", self.out)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("tekbot's probabilistic policy", r.stdout)
        robot = qnavpy.Robot("tekbot")
        net = qnavpy.Policy.read(self.out)
        self.assertEqual((net.kind, net.hidden, net.inputs), ("net", 12, 2))
        _, want, _ = qnavpy.Controller(robot.probabilistic_policy(), robot=robot).grid()
        keys, got, rank = qnavpy.Controller(net, robot=robot).grid()
        err = np.abs(got.astype(float) - want) / 32768.0
        self.assertLess(float(np.sqrt(np.mean(err ** 2))), 0.02)
        # an unfitted network of the same shape is far off: the check can fail
        zero = qnavpy.Policy.network(np.zeros(4 * 12 + 1))
        _, flat, _ = qnavpy.Controller(zero, robot=robot).grid()
        self.assertGreater(float(np.sqrt(np.mean(((flat.astype(float) - want) / 32768.0) ** 2))), 0.1)
        # ranked by its pre-activation, a clear row still prefers the smallest turn
        self.assertEqual(rank, "preact")
        self.assertEqual(int(np.argmax(keys[31])), 0)

    def test_an_existing_file_is_not_overwritten(self):
        with open(self.out, "w") as f:
            f.write("mine\n")
        r = tool("--out", self.out)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("exists; not overwritten", r.stderr)
        with open(self.out) as f:
            self.assertEqual(f.read(), "mine\n")

    def test_bad_input_is_one_line(self):
        r = tool("--robot", "no-such-robot", "--out", self.out)
        self.assertNotEqual(r.returncode, 0)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
        self.assertIn("no-such-robot", r.stderr)
        r = tool("--hidden", "40", "--out", self.out)
        self.assertNotEqual(r.returncode, 0)
        self.assertEqual(r.stderr.strip(), "fit-network: --hidden 40: must be 1..32")
        self.assertFalse(os.path.exists(self.out))


if __name__ == "__main__":
    unittest.main()
