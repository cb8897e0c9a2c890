"""The plot scripts (tools/plot_policy.py, tools/plot_learning.py through tools/plotcommon.py):
argparse command line (--help, --version, bad usage exits 2), the plot written in the format
its file name asks for, temporary files created exclusively so that a symlink planted
beside the output is never followed, and what the pictures tell a reader (issue 21):
policy.png by what decides, learning.png's curves and references named, episodes.png with
a legend and axes in metres."""
import os
import subprocess
import sys
import tempfile
import unittest

TOOLS = os.environ.get("QNAV_TOOLS_DIR") or os.path.join(os.path.dirname(__file__), "..", "..", "tools")
sys.path.insert(0, TOOLS)

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import plotcommon  # noqa: E402

MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "pdf": b"%PDF-", "svg": b"<?xml"}


def quality_csv(folder):
    with open(os.path.join(folder, "quality.csv"), "w") as f:
        f.write("policy,level,distance_m,dtheta_deg,quality\n")
        for lvl in range(3):
            for dt in range(181):
                f.write(f"prob,{lvl},{lvl * 0.5:.1f},{dt},{(180 - dt) / 180 * lvl / 2:.3f}\n")


def run_script(name, *args):
    return subprocess.run([sys.executable, os.path.join(TOOLS, name), *args],
                          capture_output=True, text=True, timeout=600)


class PlotFormatByName(unittest.TestCase):
    def test_each_extension_gets_its_own_format(self):
        with tempfile.TemporaryDirectory() as d:
            quality_csv(d)
            for fmt, magic in MAGIC.items():
                out = os.path.join(d, "q." + fmt)
                r = run_script("plot_policy.py", d, out)
                self.assertEqual(r.returncode, 0, r.stderr)
                with open(out, "rb") as f:
                    self.assertTrue(f.read(16).startswith(magic), fmt)
            self.assertEqual(sorted(n for n in os.listdir(d) if n.startswith(".")), [])

    def test_unknown_extension_is_bad_usage(self):
        with tempfile.TemporaryDirectory() as d:
            quality_csv(d)
            r = run_script("plot_policy.py", d, os.path.join(d, "q.jpeg"))
            self.assertEqual(r.returncode, 2)
            self.assertIn("unknown plot format", r.stderr)
            self.assertEqual(len(r.stderr.strip().splitlines()), 2)  # usage line + error
            self.assertFalse(os.path.exists(os.path.join(d, "q.jpeg")))


class CommandLine(unittest.TestCase):
    def test_help_exits_0_and_describes_the_plot(self):
        for script in ("plot_policy.py", "plot_learning.py"):
            r = run_script(script, "--help")
            self.assertEqual(r.returncode, 0, script)
            self.assertIn("usage: " + script, r.stdout)
            self.assertIn("EXPERIMENT_DIR", r.stdout)

    def test_version_names_qnav_version(self):
        with open(os.path.join(TOOLS, "..", "VERSION")) as f:
            want = f.read().strip()
        r = run_script("plot_policy.py", "--version")
        self.assertEqual(r.returncode, 0)
        self.assertEqual(r.stdout.strip(), f"plot_policy.py (qnav) {want}")

    def test_unknown_option_and_missing_folder_are_bad_usage(self):
        r = run_script("plot_learning.py", "--bogus", "x")
        self.assertEqual(r.returncode, 2)
        self.assertIn("unrecognized arguments: --bogus", r.stderr)
        r = run_script("plot_learning.py")
        self.assertEqual(r.returncode, 2)
        self.assertIn("EXPERIMENT_DIR", r.stderr)

    def test_missing_input_file_is_one_line_exit_1(self):
        with tempfile.TemporaryDirectory() as d:
            r = run_script("plot_policy.py", d)
            self.assertEqual(r.returncode, 1)
            self.assertEqual(r.stderr.strip(), f"plot_policy.py: {d}/quality.csv: No such file or directory")


class PolicyPictureShowsWhatDecides(unittest.TestCase):
    """Issue 21: a saturated network's quality is 0.999969 in every cell, so policy.png was
    flat; the controller ranks by the output's pre-activation, and the picture now shows it."""

    def saturated_csv(self, folder, rank="preact"):
        path = os.path.join(folder, "quality.csv")
        with open(path, "w") as f:
            f.write("policy,level,distance_m,dtheta_deg,quality,rank,key\n")
            for lvl in range(4):
                for dt in range(181):
                    f.write(f"net,{lvl},{lvl * 0.5:.1f},{dt},0.999969,{rank},{20.0 + lvl - dt / 10:.6f}\n")
        return path

    def test_a_saturated_network_is_drawn_by_its_preactivation(self):
        import plot_policy  # TOOLS is on sys.path
        with tempfile.TemporaryDirectory() as d:
            fig = plot_policy.draw(plot_policy.read_quality(self.saturated_csv(d)))
            drawn = fig.axes[0].images[0].get_array()
            self.assertEqual(drawn.shape, (4, 181))
            self.assertAlmostEqual(float(drawn[3, 0]), 23.0)
            self.assertAlmostEqual(float(drawn[0, 180]), 2.0)
            self.assertIn("pre-activation", fig.axes[1].get_ylabel())

    def test_an_unknown_rank_is_one_line_naming_the_row(self):
        with tempfile.TemporaryDirectory() as d:
            self.saturated_csv(d, rank="bogus")
            r = run_script("plot_policy.py", d, os.path.join(d, "p.png"))
            self.assertEqual(r.returncode, 1)
            self.assertEqual(r.stderr.strip(),
                             f"plot_policy.py: {d}/quality.csv:2: rank 'bogus' is not preact or quality")


def tiny_summary():
    return {"title": "t", "name": "t", "figure": None, "runs": 2, "preset": "quick", "curve_bin": 10,
            "episodes_per_candidate": 3, "robot_radius_m": 0.1,
            "conditions": [{"label": "probabilistic", "final_mean": 0.5, "final_ci95": 0.1,
                            "arrival": {"mean": 0.9, "ci95_low": 0.8, "ci95_high": 0.95}}],
            # as simevo writes them from its reference table
            "references": [{"label": "probabilistic", "plot_name": "probabilistic (held out)",
                            "plot_style": "--", "plot_color": "tab:gray"}]}


class LearningPictureSaysWhatIsHeldOut(unittest.TestCase):
    """Issue 21: the arrival panel drew the candidates' (training) arrival and the references'
    held-out arrival side by side without a word; now its legend and title say which is which."""

    def test_arrival_panel_names_candidates_and_held_out_references(self):
        import plot_learning
        col = {k: [0.4, 0.6] for k in plot_learning.KEYS}
        col["episode"] = [10, 20]
        fig = plot_learning.draw(tiny_summary(), {"direct": col, "transfer-open": dict(col)})
        arrival = fig.axes[2]
        labels = [t.get_text() for t in arrival.get_legend().get_texts()]
        self.assertIn("direct (random population): candidates", labels)
        self.assertIn("transfer from open: candidates", labels)
        self.assertIn("probabilistic: arrival on held-out episodes", labels)
        self.assertIn("held-out", arrival.get_title())
        self.assertIn("training", arrival.get_title())
        self.assertEqual(arrival.get_ylabel(), "episodes that arrived (%)")
        plt.close(fig)


class EpisodesPictureHasLegendAndScale(unittest.TestCase):
    """Issue 21: episodes.png had neither a legend nor a scale."""

    def test_legend_names_every_mark_and_axes_are_in_metres(self):
        import plot_episodes
        env = {"arena": {"width_m": 4.0, "height_m": 3.0}, "destination": {"x_m": 3, "y_m": 2, "radius_m": 0.3}}
        ep = {"x": [0.5, 1.0, 1.5], "y": [0.5, 1.0, 1.2], "recovering": [False, True, False],
              "collided": [False, True, False], "R": 1.0, "reached": False, "tau_c": 3}
        fig = plot_episodes.draw(tiny_summary(), env, {"direct": {0: ep, 1: ep}, "vfh": {0: ep}})
        legends = [a.get_legend() for a in fig.axes if a.get_legend() is not None]
        self.assertEqual(len(legends), 1)
        labels = [t.get_text() for t in legends[0].get_texts()]
        for want in ("obstacle", "destination", "path", "path while recovering from a collision", "collision",
                     "start", "robot at the end", "start zone"):
            self.assertIn(want, labels)
        panels = [a for a in fig.axes if a.get_title()]
        self.assertEqual(len(panels), 3)
        self.assertEqual([a.get_ylabel() for a in panels], ["y (m)", "", "y (m)"])
        # the lowest panel of each column names x; column 2 ends in row 1
        self.assertEqual([a.get_xlabel() for a in panels], ["", "x (m)", "x (m)"])
        self.assertGreater(len(panels[0].get_xticks()), 1)  # a scale, not bare panels
        plt.close(fig)


class WithoutMatplotlib(unittest.TestCase):
    """Issue 20: run by a python3 that lacks matplotlib (here: -S, no site-packages), each
    plot script printed a traceback; now one line naming the interpreter and exit 1."""

    def test_each_plot_script_says_matplotlib_is_missing_in_one_line(self):
        with tempfile.TemporaryDirectory() as d:
            quality_csv(d)
            for script in ("plot_policy.py", "plot_learning.py", "plot_episodes.py"):
                r = subprocess.run([sys.executable, "-S", os.path.join(TOOLS, script), d],
                                   capture_output=True, text=True, timeout=100)
                self.assertEqual(r.returncode, 1, script + ": " + r.stderr)
                self.assertNotIn("Traceback", r.stderr, script)
                self.assertEqual(len(r.stderr.strip().splitlines()), 1, script + ": " + r.stderr)
                self.assertTrue(r.stderr.startswith(f"{script}: {sys.executable} cannot import matplotlib"),
                                r.stderr)
                self.assertIn("python3-matplotlib", r.stderr)


class SigmoidTable(unittest.TestCase):
    def test_generator_reproduces_the_committed_table_and_refuses_arguments(self):
        r = run_script("gen_sigmoid_lut.py")
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(os.path.join(TOOLS, "..", "firmware", "src", "sigmoid_lut.c")) as f:
            self.assertEqual(r.stdout, f.read())
        r = run_script("gen_sigmoid_lut.py", "--bogus")
        self.assertEqual(r.returncode, 2)
        self.assertIn("unrecognized arguments: --bogus", r.stderr)


class ExclusiveTemporaryFiles(unittest.TestCase):
    def test_planted_symlink_at_the_old_temporary_name_is_not_followed(self):
        with tempfile.TemporaryDirectory() as d, tempfile.TemporaryDirectory() as outside:
            victim = os.path.join(outside, "victim.txt")
            with open(victim, "w") as f:
                f.write("keep me\n")
            out = os.path.join(d, "learning.png")
            # the names the scripts used to write through, whatever format was asked for
            os.symlink(victim, out + ".tmp.png")
            fig = plt.figure()
            plotcommon.save(fig, out)
            plt.close(fig)
            with open(victim) as f:
                self.assertEqual(f.read(), "keep me\n")
            with open(out, "rb") as f:
                self.assertTrue(f.read(8).startswith(MAGIC["png"]))
            self.assertEqual(sorted(os.listdir(d)), ["learning.png", "learning.png.tmp.png"])

    def test_failed_save_leaves_neither_output_nor_temporary(self):
        with tempfile.TemporaryDirectory() as d:
            fig = plt.figure()
            fig.add_subplot().plot([0, 1], [0, float("nan")])
            out = os.path.join(d, "x.pdf")
            with self.assertRaises(plotcommon.PlotError):
                plotcommon.save(fig, os.path.join(d, "x.bmp"))
            plotcommon.save(fig, out)
            plt.close(fig)
            self.assertEqual(os.listdir(d), ["x.pdf"])


if __name__ == "__main__":
    unittest.main()
