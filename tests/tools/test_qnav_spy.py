"""tools/qnav-spy without an X display (issue 20): lcm-spy is a Swing window, and Java
printed a HeadlessException stack trace; the script now says so in one line and exits 2,
in both its window mode and --check mode. QNAV_SPY is the build tree's copy (beside the
jars, so that the jar checks before it pass)."""
import os
import subprocess
import unittest

SPY = os.environ["QNAV_SPY"]


def run_without_display(*args):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    return subprocess.run(["/bin/sh", SPY, *args], capture_output=True, text=True, env=env, timeout=100)


class WithoutDisplay(unittest.TestCase):
    def test_window_and_check_modes_say_so_in_one_line(self):
        for args in ((), ("--check", "1"), ("--lcm-url", "memq://")):
            r = run_without_display(*args)
            self.assertEqual(r.returncode, 2, f"{args}: {r.stderr}")
            self.assertNotIn("Exception", r.stderr, args)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1, f"{args}: {r.stderr}")
            self.assertTrue(r.stderr.startswith("qnav-spy: no X display (DISPLAY is not set)"), r.stderr)
            self.assertEqual(r.stdout, "", args)


if __name__ == "__main__":
    unittest.main()
