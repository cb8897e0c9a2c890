"""tools/gap-sweep against the built qnav-sim: a gap narrower than the body is never passed
(refused as walled in, or no arrival), a wide one is, the rows are in width order with
their intervals, --set sweeps an edited copy of the profile, and bad input gets one line."""
import os
import re
import subprocess
import sys
import tempfile
import unittest

TOOL = os.path.join(os.environ["QNAV_TOOLS_DIR"], "gap-sweep")
SIM = os.environ["QNAV_SIM_EXE"]
ROW = re.compile(r"^\s*([\d.]+)\s+(-?[\d.]+)\s+([\d.]+)%\s+\[\s*([\d.]+),\s*([\d.]+)\]\s+([\d.]+)%\s+"
                 r"\[\s*([\d.]+),\s*([\d.]+)\]\s+([\d.]+)$")
REFUSED = re.compile(r"^\s*([\d.]+)\s+(-?[\d.]+)\s+refused by qnav-sim")


def tool(*args, env=None):
    return subprocess.run([sys.executable, TOOL, "--sim", SIM, *args], capture_output=True,
                          text=True, timeout=600, env=env)


class GapSweep(unittest.TestCase):
    def test_narrower_than_the_body_never_wide_always(self):
        r = tool("--robot", "tekbot", "--clearances", "0.6,-0.05", "--episodes", "4", "-j", "2")
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = r.stdout.splitlines()
        narrow, wide = lines[2], lines[3]
        self.assertTrue(REFUSED.match(narrow) or ROW.match(narrow), r.stdout)
        m = ROW.match(narrow)
        if m:
            self.assertEqual(float(m.group(3)), 0.0, r.stdout)  # no body passes a narrower gap
            self.assertEqual(float(m.group(6)), 0.0, r.stdout)
        self.assertAlmostEqual(float((REFUSED.match(narrow) or m).group(1)), 0.19, places=3)
        w = ROW.match(wide)
        self.assertIsNotNone(w, r.stdout)
        self.assertAlmostEqual(float(w.group(1)), 0.84, places=3)
        self.assertGreaterEqual(float(w.group(3)), 75.0, r.stdout)
        self.assertGreaterEqual(float(w.group(6)), float(w.group(3)))
        self.assertLessEqual(float(w.group(4)), float(w.group(3)))
        self.assertIn("narrowest gap passed in >= 90% within the limit: 0.840 m", r.stdout)

    def test_a_name_plus_map_reads_the_profiles_radius(self):
        # NAME+map is the profile NAME with its map on: the same body, so the same widths
        r = tool("--robot", "tekbot+map", "--clearances", "0.6", "--episodes", "1", "-j", "2")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("robot tekbot+map (radius 0.120 m)", r.stdout)
        self.assertAlmostEqual(float(ROW.match(r.stdout.splitlines()[2]).group(1)), 0.84, places=3)

    def test_set_sweeps_an_edited_copy(self):
        # the widths follow the copy's body (0.2 m: 0.4 + 0.3); the copy is kept where the
        # header says, in TMPDIR
        with tempfile.TemporaryDirectory() as tmp:
            r = tool("--set", "body.radius_m=0.2", "--set", "clearance.safety_m=0.02", "--clearances",
                     "0.3", "--episodes", "1", "-j", "1", env=dict(os.environ, TMPDIR=tmp))
            self.assertEqual(r.returncode, 0, r.stderr)
            head = re.match(r"^robot (\S+) \(radius 0.200 m\)", r.stdout)
            self.assertTrue(head and head.group(1).startswith(tmp), r.stdout)
            with open(head.group(1), encoding="utf-8") as f:
                self.assertRegex(f.read(), r"(?m)^safety_m = 0.02 +#")
        self.assertAlmostEqual(float(ROW.match(r.stdout.splitlines()[2]).group(1)), 0.7, places=3)

    def test_bad_input_is_one_line(self):
        # argparse's own refusals: usage, then one line naming the option
        for args, words in ((["--clearances", "abc"], "--clearances: not a list of numbers"),
                            (["--offset", "3"], "|--offset| <= 2")):
            r = tool(*args)
            self.assertEqual(r.returncode, 2, args)
            self.assertIn(words, r.stderr.strip().splitlines()[-1])
            self.assertNotIn("Traceback", r.stderr)
        # the tool's own: exactly one line
        for args, words in ((["--robot", "/no/such/profile.toml"], "/no/such/profile.toml"),
                            (["--clearances", "12"], "fit the 10 m wall"),
                            (["--sim", "/no/such/qnav-sim"], "not an executable qnav-sim"),
                            (["--set", "clearance.safety_m=x"], "--set clearance.safety_m=x: the value is not TOML"),
                            (["--set", "safety_m=0"], "expected SECTION.KEY=VALUE")):
            r = tool(*args)
            self.assertEqual(r.returncode, 1, args)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
            self.assertIn(words, r.stderr)


if __name__ == "__main__":
    unittest.main()
