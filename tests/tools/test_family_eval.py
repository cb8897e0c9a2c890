"""tools/family-eval against the built qnav-sim: one world per family, its table's shape and
sense (arrival at twice the limit never below arrival at the limit), several policies
compared on the same worlds (the summary agrees with the rows it summarizes), --set on a key
a profile gives another way, the listing
of failed episodes (its commands draw an episode that missed the limit), a robot profile
file of a robot not in data/robots (worlds sized for it, its own sector count), the note
on a sonar noisier than its map allows for, and its one-line errors for a bad family, a
missing profile and a missing simulator."""
import os
import re
import shlex
import subprocess
import sys
import tempfile
import unittest

TOOL = os.path.join(os.environ["QNAV_TOOLS_DIR"], "family-eval")
SIM = os.environ["QNAV_SIM_EXE"]
ROW = re.compile(r"^(\w+)\s+([\d.]+)%\s+\[\s*([\d.]+),\s*([\d.]+)\]\s+([\d.]+)%\s+\[\s*([\d.]+),\s*([\d.]+)\]"
                 r"\s+(\d+)/(\d+)\s+([\d.]+)\s+([\d.]+)$")


def tool(*args, env=None):
    return subprocess.run([sys.executable, TOOL, "--sim", SIM, *args], capture_output=True,
                          text=True, timeout=600, env=env)


class FamilyEval(unittest.TestCase):
    def test_one_world_per_family(self):
        r = tool("--worlds", "1", "--episodes", "2", "-j", "2")
        self.assertEqual(r.returncode, 0, r.stderr)
        rows = [ROW.match(l) for l in r.stdout.splitlines()[2:8]]
        self.assertEqual([m.group(1) for m in rows if m],
                         ["clutter", "gaps", "corridor", "pocket", "rooms", "shelves"], r.stdout)
        for m in rows:
            at1, lo1, hi1, at2 = (float(m.group(k)) for k in (2, 3, 4, 5))
            self.assertIn(at1, (0.0, 50.0, 100.0))
            self.assertLessEqual(lo1, at1)
            self.assertLessEqual(at1, hi1)
            self.assertGreaterEqual(at2, at1)
            self.assertEqual(m.group(9), "1")
        # every row has the same whitespace-separated fields, whatever its interval (an
        # interval padded inside its bracket, "[ 0.0,", used to add one below 10 %)
        counts = {len(l.split()) for l in r.stdout.splitlines()[2:7]}
        self.assertEqual(counts, {10}, r.stdout)
        # the sum line adds up the rows above it (what docs/results.md quotes)
        total = re.search(r"^sum over the 6 families: arrival % ([\d.]+) at the limit \(([\d.]+) at "
                          r"twice it\), worlds with no arrival (\d+)/6, collisions an episode "
                          r"([\d.]+), recovery ticks an episode ([\d.]+)$", r.stdout, re.M)
        self.assertTrue(total, r.stdout)
        ms = [m for m in rows if m]
        self.assertAlmostEqual(float(total.group(1)), sum(float(m.group(2)) for m in ms), delta=0.31)
        self.assertAlmostEqual(float(total.group(2)), sum(float(m.group(5)) for m in ms), delta=0.31)
        self.assertEqual(int(total.group(3)), sum(int(m.group(8)) for m in ms))
        self.assertAlmostEqual(float(total.group(4)), sum(float(m.group(10)) for m in ms), delta=0.004)

    def test_an_interval_is_two_fields_at_any_value(self):
        sys.path.insert(0, os.environ["QNAV_TOOLS_DIR"])
        import simtrials
        for lo, hi in ((0.0, 23.1), (9.7, 100.0), (100.0, 100.0), (34.2, 56.0)):
            text = simtrials.interval(lo, hi)
            self.assertEqual(text.split(), [f"[{lo:.1f},", f"{hi:.1f}]"], text)
            self.assertGreaterEqual(len(text), 13)

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
        fams = ["clutter", "gaps", "corridor", "pocket", "rooms", "shelves", "worst"]
        rows = {l.split()[0]: l for l in lines[7:]}
        self.assertEqual(list(rows), fams, r.stdout)
        for i, f in enumerate(fams):
            m = re.match(r"^\w+\s+([\d.]+)\s+\[\s*([\d.]+),\s*([\d.]+)\]\s+([\d.]+)\s+([\d.]+)\s+(\d)/2\s+([\d.]+)"
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

    def listed(self, family, worlds, *args, env=None):
        """Run with --failures; run every listed command and check the episode does what its
        line says. The set of what the lines say, and the touches listed."""
        r = tool("--worlds", str(worlds), "--episodes", "2", "-j", "2", "--families", family,
                 "--failures", *args, env=env)
        self.assertEqual(r.returncode, 0, r.stderr)
        row = ROW.match(r.stdout.splitlines()[2])
        listing = r.stdout.splitlines()[3:]
        n = int(re.match(r"^(\d+) episodes missed the limit or touched something", listing[0]).group(1))
        missed = round(2 * worlds * (100.0 - float(row.group(2))) / 100)
        kinds, touches = set(), 0
        with tempfile.TemporaryDirectory() as tmp:
            for line in listing[1:]:
                world = re.match(rf"^{family} (\d+): qnav-sim (gen-env .*)$", line)
                if world:
                    g = subprocess.run([SIM, *shlex.split(world.group(2))], cwd=tmp,
                                       capture_output=True, text=True)
                    self.assertEqual(g.returncode, 0, g.stderr)
                    limit = float(re.search(r"limit (\d+(?:\.\d+)?) s", g.stdout).group(1))
                    seed = world.group(1)
                    continue
                ep = re.match(r"^  episode (\d+) (arrived|arrived late|did not arrive at twice the limit)"
                              r"(?:, touched something (\d+) times?)?: qnav-sim (run .*)$", line)
                self.assertTrue(ep, line)
                n -= 1
                missed -= ep.group(2) != "arrived"
                self.assertTrue(ep.group(2) != "arrived" or ep.group(3), line)
                kinds.add(ep.group(2))
                touches += int(ep.group(3) or 0)
                e = subprocess.run([SIM, *shlex.split(ep.group(4))], cwd=tmp, capture_output=True,
                                   text=True)
                self.assertEqual(e.returncode, 0, e.stderr)
                m = re.search(rf"^episode {ep.group(1)}: (reached|not reached) in (\d+) ticks.*"
                              r"collisions (\d+)", e.stdout, re.M)
                self.assertTrue(m, e.stdout)
                self.assertEqual(m.group(1) == "reached", ep.group(2) != "did not arrive at twice the limit",
                                 e.stdout)
                self.assertEqual(m.group(1) == "reached" and int(m.group(2)) <= 10 * limit,
                                 ep.group(2) == "arrived", e.stdout)
                self.assertEqual(int(m.group(3)), int(ep.group(3) or 0), e.stdout)
                self.assertTrue(os.path.getsize(os.path.join(tmp, f"{family}-{seed}-{ep.group(1)}.svg")))
        self.assertEqual((n, missed), (0, 0), r.stdout)
        self.assertAlmostEqual(touches / (2 * worlds), float(row.group(10)), delta=0.0051)
        return kinds, touches

    def test_failures_are_listed_with_commands_that_draw_them(self):
        # fixed seeds: the TekBot without a map misses the limit in these rooms, and one
        # without its safety distance, speed guard, passing distance and sonar minimum range
        # (a reading at the minimum range blocks what it may touch; --set: the listed
        # commands drive the edited copy) touches something in denser clutter
        kinds, _ = self.listed("rooms", 2, "--seed-base", "5000007", "--robot", "tekbot-map")
        self.assertTrue({"arrived late", "did not arrive at twice the limit"} <= kinds, kinds)
        with tempfile.TemporaryDirectory() as tmp:
            _, touches = self.listed("clutter", 3, "--seed-base", "3000000", "--difficulty", "0.8",
                                     "--set", "clearance.safety_m=0.0",
                                     "--set", "clearance.speed_guard=false", "--set", "map.pass_m=0.0",
                                     "--set", "sonar.range_min_m=0.0",
                                     env=dict(os.environ, TMPDIR=tmp))
        self.assertGreater(touches, 0)

    def test_lateness_accounts_for_every_missed_episode(self):
        # the seeds of the listing test: the TekBot without a map misses the limit in these
        # rooms, some episodes late and some not at all
        r = tool("--worlds", "2", "--episodes", "2", "-j", "2", "--families", "rooms,corridor",
                 "--seed-base", "5000007", "--robot", "tekbot-map", "--lateness")
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = r.stdout.splitlines()
        rows = {m.group(1): m for m in map(ROW.match, lines[2:4]) if m}
        self.assertEqual(sorted(rows), ["corridor", "rooms"], r.stdout)
        self.assertTrue(lines[4].startswith("sum over the 2 families:"), r.stdout)
        self.assertTrue(lines[5].startswith("episodes that missed the limit"), r.stdout)
        late = {}
        for l in lines[7:9]:
            m = re.match(r"^(\w+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\S+) \|\s+(\S+)"
                         r"\s+(\S+) \|\s+(\S+)$", l)
            self.assertTrue(m, l)
            late[m.group(1)] = m
        for f, row in rows.items():
            m = late[f]
            n, k1, k2 = 4, round(4 * float(row.group(2)) / 100), round(4 * float(row.group(5)) / 100)
            missed, bins, never = int(m.group(2)), [int(m.group(k)) for k in range(3, 7)], int(m.group(7))
            self.assertEqual(missed, n - k1, r.stdout)
            self.assertEqual(sum(bins), k2 - k1, r.stdout)
            self.assertEqual(never, n - k2, r.stdout)
            for k in (8, 9):  # length over the straight line: at least 1, "-" with no episode
                self.assertTrue(m.group(k) == "-" or float(m.group(k)) >= 1.0, l)
            for k in (10, 11):  # a speed within the TekBot's 0.5 m/s
                self.assertTrue(m.group(k) == "-" or 0.0 <= float(m.group(k)) <= 0.5, l)
        self.assertGreater(int(late["rooms"].group(2)), 0, r.stdout)
        two = tool("--worlds", "1", "--lateness", "--policy", "a.policy", "--policy", "b.policy")
        self.assertNotEqual(two.returncode, 0)
        self.assertIn("give --policy once", two.stderr)

    def test_set_drives_an_edited_copy_of_the_profile(self):
        # map.on=false is the robot tekbot-map names: the same episodes; a key the profile
        # lacks is added to its section; data/robots is not touched
        src = os.path.join(os.environ["QNAV_TOOLS_DIR"], "..", "data", "robots", "tekbot.toml")
        with open(src, encoding="utf-8") as f:
            before = f.read()
        with tempfile.TemporaryDirectory() as tmp:
            env = dict(os.environ, TMPDIR=tmp)
            args = ("--worlds", "2", "--episodes", "2", "-j", "2", "--families", "rooms,clutter",
                    "--seed-base", "5000007")
            edited = tool(*args, "--set", "map.on=false", "--set", "map.look_m=1.0", env=env)
            named = tool(*args, "--robot", "tekbot-map")
            self.assertEqual(edited.returncode, 0, edited.stderr)
            self.assertEqual(named.returncode, 0, named.stderr)
            self.assertEqual(edited.stdout.splitlines()[1:], named.stdout.splitlines()[1:])
            prof = re.match(r"^robot (\S+), worlds sized for tekbot,", edited.stdout).group(1)
            self.assertTrue(prof.startswith(tmp), prof)
            with open(prof, encoding="utf-8") as f:
                copy = f.read()
        self.assertRegex(copy, r"(?m)^on = false +# ")
        self.assertRegex(copy, r"(?m)^\[map\] .*\n( +#.*\n)*look_m = 1.0\ncompact = true ")
        with open(src, encoding="utf-8") as f:
            self.assertEqual(f.read(), before)

    def test_set_replaces_a_key_that_says_the_same_another_way(self):
        # the TekBot places a reading by wedge_deg; --set clearance.wedge_pct drops it (a
        # profile gives one of the two): 25 % of 16 sectors is its 5.625 deg, the same
        # episodes; at 8 sectors 25 % is not 5.625 deg of 45 (13 %), other episodes
        with tempfile.TemporaryDirectory() as tmp:
            env = dict(os.environ, TMPDIR=tmp)
            args = ("--worlds", "2", "--episodes", "2", "-j", "2", "--families", "clutter,shelves",
                    "--seed-base", "5000011")
            as_pct = tool(*args, "--set", "clearance.wedge_pct=25", env=env)
            as_deg = tool(*args)
            self.assertEqual(as_pct.returncode, 0, as_pct.stderr)
            self.assertEqual(as_deg.returncode, 0, as_deg.stderr)
            self.assertEqual(as_pct.stdout.splitlines()[1:], as_deg.stdout.splitlines()[1:])
            prof = re.match(r"^robot (\S+), worlds sized for tekbot,", as_pct.stdout).group(1)
            with open(prof, encoding="utf-8") as f:
                copy = f.read()
            self.assertRegex(copy, r"(?m)^speed_guard = .*\n( +#.*\n)*wedge_pct = 25\nwedge_near_m = ")
            self.assertNotIn("wedge_deg", copy)
            eight = [tool(*args, "--sectors", "8", *extra, env=env)
                     for extra in ((), ("--set", "clearance.wedge_pct=25"))]
            self.assertEqual([r.returncode for r in eight], [0, 0], eight[1].stderr)
            self.assertNotEqual(eight[0].stdout.splitlines()[1:], eight[1].stdout.splitlines()[1:])

    def test_a_profile_file_sizes_its_worlds_and_keeps_its_sectors(self):
        # a robot not in data/robots: its worlds are sized from the file, and qnav-sim run is
        # given no sector count unless --sectors asks for one (the profile's own, 12, then)
        src = os.path.join(os.environ["QNAV_TOOLS_DIR"], "..", "data", "robots", "tekbot.toml")
        with tempfile.TemporaryDirectory() as tmp:
            prof = os.path.join(tmp, "wide.toml")
            with open(src, encoding="utf-8") as f:
                text = f.read().replace('name = "tekbot"', 'name = "widebot"')
            text = re.sub(r"(?m)^radius_m = 0.12 ", "radius_m = 0.2 ", text)
            text = re.sub(r"(?m)^default_sectors = 16 ", "default_sectors = 12 ", text)
            with open(prof, "w", encoding="utf-8") as f:
                f.write(text)
            log = os.path.join(tmp, "argv")
            wrap = os.path.join(tmp, "sim")
            with open(wrap, "w", encoding="utf-8") as f:
                f.write(f"#!/bin/sh\necho \"$*\" >> {shlex.quote(log)}\nexec {shlex.quote(SIM)} \"$@\"\n")
            os.chmod(wrap, 0o755)
            for extra, want in (([], None), (["--sectors", "12"], "12")):
                open(log, "w").close()
                r = subprocess.run([sys.executable, TOOL, "--sim", wrap, "--robot", prof, "--worlds", "1",
                                    "--episodes", "1", "-j", "1", "--families", "gaps", *extra],
                                   capture_output=True, text=True, timeout=600)
                self.assertEqual(r.returncode, 0, r.stderr)
                self.assertIn(f"worlds sized for {prof}", r.stdout)
                with open(log, encoding="utf-8") as f:
                    calls = f.read().splitlines()
                gen = [c for c in calls if c.startswith("gen-env")]
                run = [c for c in calls if c.startswith("run")]
                self.assertEqual((len(gen), len(run)), (1, 1), calls)
                self.assertIn(f"--robot {prof} ", gen[0] + " ")
                m = re.search(r"--sectors (\d+)", run[0])
                self.assertEqual(m.group(1) if m else None, want, run[0])

    def test_bad_input_is_one_line(self):
        for args, words in ((["--families", "bogus"], "unknown family 'bogus'"),
                            (["--robot", "/no/such/profile.toml"], "/no/such/profile.toml"),
                            (["--worlds", "0"], "at least 1"),
                            (["--sectors", "0"], "at least 1"),
                            (["--failures", "--policy", "a", "--policy", "b"], "give --policy once"),
                            (["--set", "map.cell_m"], "expected SECTION.KEY=VALUE"),
                            (["--set", "nosuch.k=1"], "no [nosuch] section"),
                            (["--set", "drive.model=mix"], "--set drive.model=mix: the value is not TOML"),
                            (["--set", "drive.model=mix"], "a string takes quotes: --set 'drive.model=\"mix\"'"),
                            (["--robot", "tekbot-map", "--set", "map.on=true"], "--set map.on=false")):
            r = tool("--worlds", "1", *args) if args[0] != "--worlds" else tool(*args)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn(words, r.stderr)
            self.assertNotIn("Traceback", r.stderr)

    def test_a_sonar_noisier_than_its_map_allows_for_is_noted(self):
        # the TekBot's map allows for 0.10 (its [map] noise): 0.15 is noted, once, and the
        # table follows; the profile's own noise, a map set to allow for it, and a robot
        # without a map are not
        base = ("--worlds", "1", "--episodes", "1", "--families", "pocket", "-j", "1")
        r = tool(*base, "--sensor-noise", "0.15")
        self.assertEqual(r.returncode, 0, r.stderr)
        notes = [l for l in r.stderr.splitlines() if "allows for" in l]
        self.assertEqual(len(notes), 1, r.stderr)
        self.assertIn("0.15", notes[0])
        self.assertIn("0.1 ", notes[0])
        self.assertTrue(ROW.match(r.stdout.splitlines()[2]), r.stdout)
        for args in (("--sensor-noise", "0.05"), ("--sensor-noise", "0.15", "--set", "map.noise=0.15"),
                     ("--sensor-noise", "0.15", "--robot", "tekbot-map")):
            r = tool(*base, *args)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertNotIn("allows for", r.stderr, args)

    def test_missing_simulator(self):
        r = subprocess.run([sys.executable, TOOL, "--sim", "/no/such/qnav-sim"],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 1)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)


if __name__ == "__main__":
    unittest.main()
