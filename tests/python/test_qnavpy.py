"""qnavpy against the command-line tools it wraps (docs/python.md): an episode stepped from
Python equals `qnav-sim run --trace` row for row, evaluate equals `simevo eval`, the
controllers equal libqnav's committed shared vectors, and bad input raises the tools' own
one-line messages. Run by CTest (python.qnavpy) with PYTHONPATH on the built package."""

import os
import re
import subprocess
import tempfile
import unittest

import numpy as np

import qnavpy

QNAV_SIM = os.environ["QNAV_SIM"]
SIMEVO = os.environ["SIMEVO"]
SRC = os.environ["QNAV_SOURCE_DIR"]
TRACE_ROW = "%u,%.6f,%.6f,%.6f,%.4f,%d,%.4f,%d,%d"  # qnav-sim run --trace's row format


def run_tool(*args):
    """(status, stdout, stderr) of a tool run."""
    p = subprocess.run(list(args), capture_output=True, text=True, timeout=300)
    return p.returncode, p.stdout, p.stderr


def tool_line(stderr, program):
    """The message a tool printed, without its 'PROGRAM: ' prefix and ' (see PROGRAM --help)'."""
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    line = lines[0]
    if line.startswith(program + ": "):
        line = line[len(program) + 2:]
    return line.replace(f" (see {program} --help)", "")


def qnav_sim_trace(work, *args):
    """qnav-sim run's trajectory rows, without the controller's escape side (the controller's
    memory, not the episode's: the decisions it led to are in the rows) and the destination
    it was given (the map's sub-goal: its input, not the episode's), and its episode line."""
    path = os.path.join(work, "trace.csv")
    st, out, err = run_tool(QNAV_SIM, "run", "--trace", path, *args)
    assert st == 0, err
    with open(path) as f:
        lines = f.read().splitlines()
    assert lines[0].endswith(",escape_side,goal_bearing_deg,goal_range_m"), lines[0]
    rows = [line.rsplit(",", 3)[0] for line in lines[1:]]
    episode = next(line for line in out.splitlines() if line.startswith("episode "))
    return rows, episode


def episode_line(seed, r):
    """The line qnav-sim run prints for an episode's result."""
    return ("episode %d: %s in %u ticks  l %.3f m  beta_l %.3f m  tau_l %.1f s  beta_tau %.2f s  f1 %.3f  "
            "f2 %.3f  tau_c %u  collisions %u  R %.3f" % (seed, "reached" if r["reached"] else "not reached",
                                                         r["ticks"], r["l"], r["beta_l"], r["tau_l"],
                                                         r["beta_tau"], r["f1"], r["f2"], r["tau_c"],
                                                         r["collisions"], r["R"]))


def stepped_rows(env, seed, decide=None):
    """Rows in qnav-sim's trace format of an episode stepped tick by tick from Python; decide:
    None (the env's controller), or a function observation -> (heading_deg, speed)."""
    obs, info = env.reset(seed=seed)
    rows = [TRACE_ROW % (0, *obs["pose"], 0.0, 0, 0.0, 0, 0)]
    while True:
        action = None if decide is None else decide(obs)
        obs, reward, terminated, truncated, info = env.step(action)
        rows.append(TRACE_ROW % (info["tick"], *obs["pose"], info["speed_mps"], round(info["cmd_heading_deg"]),
                                 info["cmd_speed"], info["recovering"], info["collided"]))
        if terminated or truncated:
            return rows, reward, terminated, info["result"]


def make_network(path, hidden=6, seed=5):
    """A random 2-input network written to path (weights within [-4, 4])."""
    rng = np.random.default_rng(seed)
    p = qnavpy.Policy.network(rng.uniform(-4, 4, 4 * hidden + 1))
    p.write(path, comment="test network")
    return p


class SteppedEpisodeEqualsQnavSimRun(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.work = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def test_default_episode_with_noise_is_the_same_row_for_row(self):
        rows, line = qnav_sim_trace(self.work, "--seed", "3", "--episode", "2")
        env = qnavpy.Env(seed=3)  # qnav-sim run's defaults: dense, pioneer3dx, the profile's noise
        mine, reward, _, result = stepped_rows(env, 2)
        self.assertGreater(len(rows), 20)
        self.assertEqual(mine, rows)
        self.assertEqual(episode_line(2, result), line)
        self.assertEqual(reward, result["R"])

    def test_network_policy_on_a_generated_world_is_the_same_row_for_row(self):
        policy_file = os.path.join(self.work, "net.policy")
        make_network(policy_file)
        args = ("--env", "gen:pocket:4", "--robot", "tekbot", "--sectors", "24", "--policy", policy_file,
                "--seed", "9", "--episode", "1", "--sensor-noise", "0.02", "--actuation-noise", "0.02")
        rows, line = qnav_sim_trace(self.work, *args)
        env = qnavpy.Env("gen:pocket:4", "tekbot", sectors=24, policy=policy_file, seed=9, sensor_noise=0.02,
                         actuation_noise=0.02)
        mine, _, _, result = stepped_rows(env, 1)
        self.assertEqual(mine, rows)
        self.assertEqual(episode_line(1, result), line)

    def test_the_maps_grid_turned_as_qnav_sim_turns_it(self):
        for frame in (None, 30):
            with self.subTest(map_frame_deg=frame):
                extra = () if frame is None else ("--map-frame", str(frame))
                rows, line = qnav_sim_trace(self.work, "--env", "gen:rooms:4", "--robot", "tekbot", "--seed", "3",
                                            "--episode", "1", *extra)
                env = qnavpy.Env("gen:rooms:4", "tekbot", seed=3, map_frame_deg=frame)
                mine, _, _, result = stepped_rows(env, 1)
                self.assertEqual(mine, rows)
                self.assertEqual(episode_line(1, result), line)
        turned, _ = qnav_sim_trace(self.work, "--env", "gen:rooms:4", "--robot", "tekbot", "--seed", "3",
                                   "--episode", "1", "--map-frame", "0")
        self.assertNotEqual(turned, rows)  # the turn reaches the episode

    def test_a_known_world_as_qnav_sim_surveys_it(self):
        args = ("--env", "gen:rooms:4", "--robot", "tekbot", "--seed", "3", "--episode", "1")
        plain, _ = qnav_sim_trace(self.work, *args)
        rows, line = qnav_sim_trace(self.work, *args, "--survey", "0.4")
        env = qnavpy.Env("gen:rooms:4", "tekbot", seed=3, survey_m=0.4)
        mine, _, _, result = stepped_rows(env, 1)
        self.assertEqual(mine, rows)
        self.assertEqual(episode_line(1, result), line)
        self.assertNotEqual(rows, plain)  # the survey reaches the episode
        with self.assertRaisesRegex(qnavpy.QnavError, "survey_m"):
            qnavpy.Env("gen:rooms:4", "tekbot", survey_m=0.01)

    def test_python_controller_deciding_from_observations_is_the_c_step(self):
        # the controller stepped on each observation from Python, its decision given back
        # as (heading, speed): every decision must equal the one qnav-sim run made (VFH+
        # with its histogram; the path-quality controller leaving a U-pocket with its
        # escape memory; and with a map, whose verdicts on that memory, cleared or grown,
        # come with each observation)
        map_profile = os.path.join(self.work, "tekbot-map.toml")
        with open(os.path.join(SRC, "data", "robots", "tekbot.toml")) as f, open(map_profile, "w") as out:
            # the profile's own [map] (off, its last section) replaced by one that is on
            out.write(f.read().split("\n[map]")[0] + "\n\n[map]\ncell_m = 0.1\n")
        cases = [("vfh", "dense", "pioneer3dx", 4, 0), ("body", "gen:pocket:2", "tekbot", 6, 3),
                 ("body", "gen:rooms:3000038:0.5:tekbot", map_profile, 1, 0)]
        verdicts = 0
        for name, world, robot, seed, episode in cases:
            with self.subTest(controller=name, world=world):
                rows, line = qnav_sim_trace(self.work, "--seed", str(seed), "--controller", name, "--env", world,
                                            "--robot", robot, "--episode", str(episode))
                env = qnavpy.Env(world, robot, seed=seed, controller=name)
                ctrl = qnavpy.Controller(controller=name, env=env)
                flags = []

                def decide(obs):
                    nonlocal verdicts
                    verdicts += obs["escape_clear"] + (obs["escape_grow_mm"] > 0)
                    d = ctrl.decide(obs)
                    flags.append(d.flags)
                    return d.heading_deg, d.speed

                ctrl.reset()
                mine, _, _, result = stepped_rows(env, episode, decide)
                self.assertEqual(mine, rows)
                self.assertEqual(episode_line(episode, result), line)
                self.assertEqual(len(flags), len(rows) - 1)
        self.assertGreater(verdicts, 0)  # the map did clear or grow the memory

    def test_run_episode_in_c_equals_the_stepped_episode(self):
        env = qnavpy.Env("dense", "tekbot", seed=2)
        stepped, _, _, result = stepped_rows(env, 5)
        ep = env.run_episode(seed=5)
        t = ep.trajectory
        rows = [TRACE_ROW % tuple(t[k][name] for name in t.dtype.names) for k in range(len(t))]
        self.assertEqual(rows, stepped)
        self.assertEqual(ep.result, result)


class EvaluateEqualsSimevoEval(unittest.TestCase):
    @staticmethod
    def simevo_figures(*args):
        st, out, err = run_tool(SIMEVO, "eval", *args)
        assert st == 0, err
        m = re.match(r"episodes (\d+)  mean R (\S+) ± \S+ \(95% CI\)  sd (\S+)  reached (\d+)% .*mean tau_c (\S+) ±",
                     out)
        assert m, out
        return m.groups()

    @staticmethod
    def figures(ev, p):
        R = ev.R[p]
        return (str(len(R)), "%.3f" % R.mean(), "%.3f" % R.std(ddof=1), "%.0f" % (100.0 * ev.reached[p].mean()),
                "%.1f" % ev.tau_c[p].mean())

    def test_probabilistic_and_network_policies_score_as_simevo_eval(self):
        with tempfile.TemporaryDirectory() as work:
            net = os.path.join(work, "net.policy")
            make_network(net, hidden=8, seed=11)
            opts = dict(world="dense", robot="tekbot", sectors=16, noise=0.05, seed=7)
            ev = qnavpy.evaluate(["prob", net], episodes=12, jobs=2, **opts)
            self.assertEqual(ev.R.shape, (2, 12))
            for p, name in enumerate(["prob", net]):
                expected = self.simevo_figures(name, "--episodes", "12", "--env", "dense", "--robot", "tekbot",
                                               "--sectors", "16", "--noise", "0.05", "--seed", "7")
                self.assertEqual(self.figures(ev, p), expected)

    def test_results_do_not_depend_on_threads_or_batch(self):
        rng = np.random.default_rng(3)
        weights = rng.uniform(-3, 3, (5, 4 * 4 + 1))
        one = qnavpy.evaluate(weights, episodes=4, world="gen:gaps:3", jobs=1)
        two = qnavpy.evaluate(weights, episodes=4, world="gen:gaps:3", jobs=2)
        alone = qnavpy.evaluate(weights[3:4], episodes=4, world="gen:gaps:3", jobs=1)
        np.testing.assert_array_equal(one.R, two.R)
        np.testing.assert_array_equal(one.tau_c, two.tau_c)
        np.testing.assert_array_equal(one.R[3], alone.R[0])
        self.assertGreater(len(np.unique(one.R)), 1)  # five different networks, not one answer


class ControllersEqualSharedVectors(unittest.TestCase):
    """tests/target/expected_vectors.txt: the probabilistic policy's lines for the scans that
    need no random numbers (libqnav's default configuration and policy)."""

    SHAPES = {"v1": (8, 5000, "wall", 0), "v3": (16, 5000, "open", -4550), "v4": (16, 3000, "corridor", 17999),
              "v5": (16, 5000, "zero", 0), "v9": (32, 2000, "over", -32768), "v11": (180, 5000, "corridor", -9050)}

    @staticmethod
    def scan(n, max_mm, shape):
        def near(c, axis, half):
            d = (c + 360 - axis) % 360
            return min(d, 360 - d) <= half
        out = []
        for i in range(n):
            c = i * 360 // n
            out.append({"wall": max_mm // 10 if near(c, 0, 45) else max_mm,
                        "corridor": max_mm * 15 // 100 if near(c, 90, 30) or near(c, 270, 30) else max_mm,
                        "open": max_mm, "zero": 0, "over": 65535}[shape])
        return out

    @staticmethod
    def fnv(qualities):
        h = 2166136261
        for q in qualities.astype(np.uint16):
            h = ((h ^ (int(q) & 0xFF)) * 16777619) & 0xFFFFFFFF
            h = ((h ^ (int(q) >> 8)) * 16777619) & 0xFFFFFFFF
        return h

    def test_probabilistic_policy_lines_match_the_committed_vectors(self):
        with open(os.path.join(SRC, "tests", "target", "expected_vectors.txt")) as f:
            lines = {ln.split()[0]: ln for ln in f if re.match(r"v\d+ prob ", ln)}
        for name, (n, max_mm, shape, goal) in self.SHAPES.items():
            ctrl = qnavpy.Controller(qnavpy.Policy.probabilistic(), sectors=n, max_range_mm=max_mm)
            d = ctrl.step(self.scan(n, max_mm, shape), goal, qualities=True)
            got = (f"{name} prob  n={n} max={max_mm} goal={goal} heading={d.heading_deg} speed={d.speed_q15} "
                   f"quality={d.quality_q15} flags=0x{d.flags:02x} qhash=0x{self.fnv(d.qualities):08x}")
            self.assertEqual(got, lines[name].strip())

    def test_table_mode_decides_as_the_network(self):
        rng = np.random.default_rng(8)
        policy = qnavpy.Policy.network(rng.uniform(-5, 5, 4 * 12 + 1))
        net = qnavpy.Controller(policy, robot="tekbot", sectors=16)
        table = qnavpy.Controller(policy, robot="tekbot", sectors=16, table=True)
        for _ in range(200):
            ranges = rng.integers(0, 6000, 16)
            goal = int(rng.integers(-18000, 18000))
            self.assertEqual(net.step(ranges, goal, 0, 3000)[:4], table.step(ranges, goal, 0, 3000)[:4])

    def test_grid_ranks_by_preactivation_where_qualities_saturate(self):
        policy = qnavpy.Policy.network(np.r_[np.tile([-20.0, 30.0, 5.0, 40.0], 4), 10.0])
        keys, qualities, rank = qnavpy.Controller(policy, robot="tekbot").grid()
        self.assertEqual(rank, "preact")
        self.assertEqual(keys.shape, (32, 181))
        saturated = qualities == qualities.max()
        self.assertGreater(saturated.sum(), 100)                # many cells read as "1.0"
        self.assertGreater(len(np.unique(keys[saturated])), 10)  # the keys still tell them apart


class PolicyMapShowsWhatDecides(unittest.TestCase):
    def test_simevo_quality_writes_the_preactivation_the_controller_ranks_by(self):
        # a network whose quality reads 1.0 almost everywhere (issue 21's flat policy.png)
        policy = qnavpy.Policy.network(np.r_[np.tile([-20.0, 30.0, 5.0, 40.0], 4), 10.0])
        keys, qualities, rank = qnavpy.Controller(policy).grid()
        with tempfile.TemporaryDirectory() as work:
            path = os.path.join(work, "sat.policy")
            policy.write(path)
            st, _, err = run_tool(SIMEVO, "quality", path, "--out", work)
            self.assertEqual(st, 0, err)
            with open(os.path.join(work, "quality.csv")) as f:
                header = f.readline().strip().split(",")
                rows = [dict(zip(header, line.strip().split(","))) for line in f]
        self.assertEqual(header, ["policy", "level", "distance_m", "dtheta_deg", "quality", "rank", "key"])
        net = [r for r in rows if r["policy"] != "probabilistic"]
        self.assertEqual(len(net), 32 * 181)
        k = keys.astype(np.int64)
        z = np.where(np.abs(k) < 16384, k / 2048.0, np.sign(k) * (8.0 + (np.abs(k) - 16384) / 128.0))
        for r in net:
            lvl, dt = int(r["level"]), int(r["dtheta_deg"])
            self.assertEqual(r["rank"], "preact")
            self.assertEqual(r["key"], "%.6f" % z[lvl, dt])
            self.assertEqual(r["quality"], "%.6f" % (qualities[lvl, dt] / 32768.0))
        flat = [r for r in net if r["quality"] == "0.999969"]
        self.assertGreater(len(flat), 1000)
        self.assertGreater(len({r["key"] for r in flat}), 100)


class BadInputRaisesTheToolsLine(unittest.TestCase):
    def assert_same_line(self, call, tool_args, program):
        st, _, err = run_tool(*tool_args)
        self.assertNotEqual(st, 0)
        with self.assertRaises(qnavpy.QnavError) as cm:
            call()
        self.assertEqual(str(cm.exception), tool_line(err, program))
        self.assertNotIn("\n", str(cm.exception))

    def test_evaluate_refuses_what_simevo_eval_refuses(self):
        bad_file = os.path.join(SRC, "README.md")
        cases = [
            (dict(policies=["prob"], world="no-such-world"), ["prob", "--env", "no-such-world"]),
            (dict(policies=["prob"], world="gen:bogus:1"), ["prob", "--env", "gen:bogus:1"]),
            (dict(policies=["prob"], robot="no-such-robot"), ["prob", "--robot", "no-such-robot"]),
            (dict(policies=["/no/such.policy"]), ["/no/such.policy"]),
            (dict(policies=[bad_file]), [bad_file]),
            (dict(policies=["prob"], fitness="fast"), ["prob", "--fitness", "fast"]),
            (dict(policies=["prob"], sectors=400), ["prob", "--sectors", "400"]),
            (dict(policies=["prob"], noise=2), ["prob", "--noise", "2"]),
            (dict(policies=["prob"], episodes=0), ["prob", "--episodes", "0"]),
        ]
        for kwargs, args in cases:
            with self.subTest(args=args):
                self.assert_same_line(lambda: qnavpy.evaluate(**kwargs), [SIMEVO, "eval", *args], "simevo")

    def test_env_refuses_what_qnav_sim_run_refuses(self):
        bad_file = os.path.join(SRC, "README.md")
        cases = [
            (dict(world="no-such-world"), ["--env", "no-such-world"]),
            (dict(robot="no-such-robot"), ["--robot", "no-such-robot"]),
            (dict(world="gen:clutter:x"), ["--env", "gen:clutter:x"]),
            (dict(controller="bug2"), ["--controller", "bug2"]),
            (dict(policy=bad_file), ["--policy", bad_file]),
            (dict(fitness="fast"), ["--fitness", "fast"]),
            (dict(map_frame_deg=400), ["--map-frame", "400"]),
        ]
        for kwargs, args in cases:
            with self.subTest(args=args):
                self.assert_same_line(lambda: qnavpy.Env(**kwargs), [QNAV_SIM, "run", *args], "qnav-sim")

    def test_a_step_after_the_end_is_refused(self):
        env = qnavpy.Env("open", "tekbot", episode_limit_s=0.5)
        env.reset(seed=0)
        for _ in range(5):
            env.step((0.0, 0.0))
        with self.assertRaisesRegex(qnavpy.QnavError, "^step: the episode is over"):
            env.step((0.0, 0.0))


class Policies(unittest.TestCase):
    def test_a_written_policy_reads_back_equal(self):
        with tempfile.TemporaryDirectory() as work:
            path = os.path.join(work, "p.policy")
            p = make_network(path, hidden=3)
            q = qnavpy.Policy.read(path)
            self.assertEqual(q, p)
            st, out, err = run_tool(os.path.join(os.path.dirname(QNAV_SIM), "..", "host", "policyio",
                                                 "qnav-policy"), "check", path)
            self.assertEqual(st, 0, err)

    def test_a_generated_world_is_named_by_its_full_spec_and_repeats(self):
        a = qnavpy.World.generated("rooms", 12, 0.25, "tekbot")
        self.assertEqual(a.name, "gen:rooms:12:0.25:tekbot")
        b = qnavpy.World("gen:rooms:12:0.25")
        self.assertEqual((b.name, b.n_obstacles, b.dest), (a.name, a.n_obstacles, a.dest))
        self.assertIn("rooms", qnavpy.world_families())

    def test_weights_round_half_away_from_zero_as_evolution_does(self):
        p = qnavpy.Policy.network([0.5 / 256, -0.5 / 256, 1.5 / 256, -1.5 / 256, 200.0])
        np.testing.assert_array_equal(p.raw, [1, -1, 2, -2, 32767])


class NameListsAreTheTables(unittest.TestCase):
    """Issue 22: every list of controller names that people read is libqnav's table (the CLI
    help prints it) or is checked against it here (the docs and the header's comment)."""

    def test_docs_and_header_list_exactly_the_controller_table(self):
        names = qnavpy.controller_names()
        with open(os.path.join(SRC, "docs", "architecture.md"), encoding="utf-8") as f:
            seam = f.read().split("## Controllers: the seam", 1)[1].split("\n### ", 1)[0]
        self.assertEqual(re.findall(r"^\| `([a-z0-9_-]+)` \|", seam, re.M), names)
        with open(os.path.join(SRC, "firmware", "include", "qnav", "nav.h"), encoding="utf-8") as f:
            header = f.read().split("*/", 1)[0]
        self.assertEqual(re.findall(r'^ \*   "([a-z0-9_-]+)"', header, re.M), names)

    def test_qnav_sim_help_names_every_controller_of_the_table(self):
        out = subprocess.run([QNAV_SIM, "run", "--help"], capture_output=True, text=True,
                             check=True).stdout
        help_text = " ".join(out.split("--controller", 1)[1].split("--limit-factor", 1)[0].split())
        for name in qnavpy.controller_names():
            self.assertIn(name + ":", help_text)


if __name__ == "__main__":
    unittest.main()
