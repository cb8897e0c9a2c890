"""tools/qnav_log.py on logs the tests record: make_sample_log's log (one message of every
qnav type with known values, written by the generated C encoders) and a software-in-the-loop
trial on udpm:// recorded by lcm-logger inside a private network namespace (skipped when
`unshare -n` is not permitted; DESIGN.md section 7). The CSVs hold the values written, the
row counts agree with navbridge --replay (lcm's C reader), the plot is drawn in the format
asked, and bad input is refused with one line and status 2.
Environment: QNAV_TOOLS_DIR, QNAV_PYTHON_DIR (generated types), SAMPLE_LOG_EXE,
NAVBRIDGE_EXE, SIL_EXE, UDPM_SCRIPT, UNSHARE_EXE, QNAV_DATA_DIR."""
import csv
import os
import subprocess
import sys
import tempfile
import unittest

TOOL = os.path.join(os.environ["QNAV_TOOLS_DIR"], "qnav_log.py")
ENV = os.environ


def run_tool(*args):
    return subprocess.run([sys.executable, TOOL, *args], capture_output=True, text=True, timeout=600)


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


class SampleLog(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        cls.log = os.path.join(cls.dir.name, "sample.lcmlog")
        subprocess.run([ENV["SAMPLE_LOG_EXE"], cls.log], check=True)

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def test_counts_every_channel(self):
        r = run_tool(self.log)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.split("\n")[:6], [f"QNAV_{c} 1" for c in
                         ("COMMAND", "GOAL", "LINK_STATUS", "POSE", "QUALITIES", "SCAN")])

    def test_csv_holds_the_values_written(self):
        out = os.path.join(self.dir.name, "csv")
        r = run_tool(self.log, "--csv", out)
        self.assertEqual(r.returncode, 0, r.stderr)
        pose = rows(os.path.join(out, "qnav_pose.csv"))
        self.assertEqual((pose[0]["x_m"], pose[0]["y_m"], pose[0]["reached"]), ("1.5", "2.5", "0"))
        self.assertEqual(pose[0]["log_utime"], "1700000000000000")
        scan = rows(os.path.join(out, "qnav_scan.csv"))[0]
        self.assertEqual((scan["seq"], scan["n_sectors"], scan["goal_bearing_cdeg"]), ("42", "16", "-4500"))
        self.assertEqual(scan["ranges_mm"].split()[:16], [str(1000 + k) for k in range(16)])
        cmd = rows(os.path.join(out, "qnav_command.csv"))[0]
        self.assertEqual((cmd["heading_deg"], cmd["speed_q15"], cmd["speed"]), ("-30", "16384", "0.5"))
        st = rows(os.path.join(out, "qnav_link_status.csv"))[0]
        self.assertEqual((st["mode"], st["drop_crc"]), ("1", "3"))
        q = rows(os.path.join(out, "qnav_qualities.csv"))[0]
        self.assertEqual(q["quality_q15"].split()[:3], ["0", "90", "180"])
        self.assertEqual(len(q["quality_q15"].split()), 360)

    def test_not_a_log_and_directory_are_bad_input(self):
        notlog = os.path.join(self.dir.name, "notes.txt")
        with open(notlog, "w") as f:
            f.write("not a log\n")
        for path, needle in ((notlog, "not an LCM log"), (self.dir.name, "is a directory")):
            r = run_tool(path)
            self.assertEqual(r.returncode, 2, path)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1)
            self.assertIn(needle, r.stderr)
        r = run_tool(self.log, "--plot", os.path.join(self.dir.name, "x.gif"))
        self.assertEqual(r.returncode, 2)
        self.assertIn("unknown plot format", r.stderr)


class RecordedTrial(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        d = cls.dir.name
        if subprocess.run([ENV["UNSHARE_EXE"], "-n", "true"], capture_output=True).returncode != 0:
            raise unittest.SkipTest("`unshare -n` is not permitted: no private network namespace "
                                    "for a udpm:// trial (DESIGN.md section 7)")
        r = subprocess.run([ENV["UNSHARE_EXE"], "-n", "/bin/sh", ENV["UDPM_SCRIPT"], ENV["NAVBRIDGE_EXE"],
                            ENV["SIL_EXE"], d], capture_output=True, text=True, timeout=900)
        if r.returncode == 10:
            raise unittest.SkipTest("cannot configure loopback multicast in the namespace")
        with open(os.path.join(d, "rc.txt")) as f:
            cls.rc = f.read().strip()
        cls.log = os.path.join(d, "trial.lcmlog")

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def test_trial_csv_agrees_with_navbridge_replay(self):
        self.assertEqual(self.rc, "sil=0 navbridge=1 spy=-")
        out = os.path.join(self.dir.name, "csv")
        r = run_tool(self.log, "--csv", out)
        self.assertEqual(r.returncode, 0, r.stderr)
        scans = rows(os.path.join(out, "qnav_scan.csv"))
        replay = subprocess.run([ENV["NAVBRIDGE_EXE"], "--replay", self.log], capture_output=True,
                                text=True, timeout=300)
        self.assertEqual(replay.returncode, 0, replay.stderr)
        first = replay.stdout.split("replay: ")[1]
        self.assertEqual(int(first.split()[0]), len(scans))  # "N scans"
        poses = rows(os.path.join(out, "qnav_pose.csv"))
        self.assertGreater(len(poses), 100)
        self.assertEqual(poses[-1]["reached"], "1")
        self.assertEqual([int(p["tick"]) for p in poses[:3]], [1, 2, 3])
        self.assertLess(float(poses[-1]["goal_distance_m"]), float(poses[0]["goal_distance_m"]))
        cmds = rows(os.path.join(out, "qnav_command.csv"))
        self.assertGreater(len(cmds), 100)
        self.assertTrue(all(-179 <= int(c["heading_deg"]) <= 180 for c in cmds))

    def test_trial_plot_in_each_format(self):
        for ext, magic in (("png", b"\x89PNG"), ("pdf", b"%PDF"), ("svg", b"<?xml")):
            out = os.path.join(self.dir.name, "trial." + ext)
            r = run_tool(self.log, "--plot", out)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(out, "rb") as f:
                head = f.read()
            self.assertTrue(head.startswith(magic), ext)
            self.assertGreater(len(head), 10000, ext)


if __name__ == "__main__":
    unittest.main()
