"""tools/floors (docs/architecture.md, "The map"): the checkout's includes run only down the
floors, and an include that runs upward is named in one line (file, line, include) with
exit status 1."""
import os
import shutil
import subprocess
import tempfile
import unittest

TOOLS = os.environ.get("QNAV_TOOLS_DIR") or os.path.join(os.path.dirname(__file__), "..", "..", "tools")
FLOORS = os.path.join(TOOLS, "floors")
ROOT = os.path.join(TOOLS, "..")


def run(root):
    return subprocess.run([FLOORS, root], capture_output=True, text=True)


def tree(test, files):
    """A git checkout in a temporary folder holding files {path: text}, removed after the test."""
    d = tempfile.mkdtemp(prefix="qnav-floors-")
    test.addCleanup(shutil.rmtree, d)
    for path, text in files.items():
        os.makedirs(os.path.join(d, os.path.dirname(path)), exist_ok=True)
        with open(os.path.join(d, path), "w") as f:
            f.write(text)
    subprocess.run(["git", "init", "-q", d], check=True)
    subprocess.run(["git", "-C", d, "add", "."], check=True)
    return d


class Floors(unittest.TestCase):
    def test_the_checkout_includes_only_downward(self):
        r = run(ROOT)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertTrue(r.stdout.startswith("floors: ok"), r.stdout)

    def test_firmware_including_common_is_named_by_file_line_and_include(self):
        d = tree(self, {"common/include/qnav/rng.h": "/* rng */\n",
                  "firmware/src/ctrl.c": "#include <stdint.h>\n#include \"qnav/rng.h\"\n"})
        r = run(d)
        self.assertEqual(r.returncode, 1)
        self.assertEqual(r.stdout.splitlines(), [
            'floors: firmware/src/ctrl.c:2: #include "qnav/rng.h" is '
            'common/include/qnav/rng.h (floor 1, common/) above firmware/ (floor 0)'])

    def test_sim_including_navbridge_fails_and_policyio_on_its_own_floor_passes(self):
        d = tree(self, {"host/navbridge/bridge.h": "\n",
                  "host/policyio/include/qnav/policy_io.h": "\n",
                  "sim/src/world.cpp": "#include \"qnav/policy_io.h\"\n"
                                       "#include \"../../host/navbridge/bridge.h\"\n"})
        r = run(d)
        self.assertEqual(r.returncode, 1)
        self.assertEqual(len(r.stdout.splitlines()), 1, r.stdout)
        self.assertIn("sim/src/world.cpp:2: ", r.stdout)

    def test_headers_lcm_generates_belong_to_lcmtypes(self):
        d = tree(self, {"host/lcmtypes/scan_t.lcm": "package qnav;\n",
                  "common/include/qnav/one.h": "#include \"qnav_scan_t.h\"\n"})
        r = run(d)
        self.assertEqual(r.returncode, 1)
        self.assertIn("host/lcmtypes/scan_t.lcm (floor 2", r.stdout)


if __name__ == "__main__":
    unittest.main()
