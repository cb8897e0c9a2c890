#!/usr/bin/python3
"""How fast qnav runs from Python (docs/python.md, "Measured"): simulator steps per second
stepped from Python (the controller in C, or deciding from Python), whole episodes in C,
and evaluate()'s episodes per second beside `simevo eval`'s on the same cores. Each figure
is measured --repeats times; min / median / max are printed.

    PYTHONPATH=$HOME/qnav/share/qnav/python python3 benchmark.py --simevo $HOME/qnav/bin/simevo
"""

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import time

import qnavpy


def spread(values):
    return f"min {min(values):9.0f}  median {statistics.median(values):9.0f}  max {max(values):9.0f}"


def stepped(env, episodes, action):
    """Steps per second of episodes stepped one tick per call."""
    steps = 0
    t0 = time.perf_counter()
    for e in range(episodes):
        env.reset(seed=e)
        while True:
            _, _, terminated, truncated, _ = env.step(action)
            steps += 1
            if terminated or truncated:
                break
    return steps / (time.perf_counter() - t0)


def python_decides(env, ctrl, episodes):
    """Steps per second when the controller is stepped from Python on each observation."""
    steps = 0
    t0 = time.perf_counter()
    for e in range(episodes):
        obs, _ = env.reset(seed=e)
        ctrl.reset()
        while True:
            d = ctrl.decide(obs)
            obs, _, terminated, truncated, _ = env.step((d.heading_deg, d.speed))
            steps += 1
            if terminated or truncated:
                break
    return steps / (time.perf_counter() - t0)


def in_c(env, episodes):
    steps = 0
    t0 = time.perf_counter()
    for e in range(episodes):
        steps += env.run_episode(seed=e).result["ticks"]
    return steps / (time.perf_counter() - t0)


def simevo_rate(simevo, processes, episodes, args):
    """Episodes per second of `processes` simevo eval runs at once, episodes each."""
    t0 = time.perf_counter()
    procs = [subprocess.Popen([simevo, "eval", "prob", "--episodes", str(episodes), "--env", args.world, "--robot",
                               args.robot, "--seed", str(1 + k)], stdout=subprocess.DEVNULL)
             for k in range(processes)]
    if any(p.wait() != 0 for p in procs):
        sys.exit("benchmark: simevo eval failed")
    return processes * episodes / (time.perf_counter() - t0)


def evaluate_rate(jobs, episodes, args):
    t0 = time.perf_counter()
    qnavpy.evaluate(["prob"] * jobs, episodes, world=args.world, robot=args.robot, jobs=jobs)
    return jobs * episodes / (time.perf_counter() - t0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--world", default="dense")
    ap.add_argument("--robot", default="tekbot")
    ap.add_argument("--episodes", type=int, default=20, help="episodes per stepped measurement")
    ap.add_argument("--eval-episodes", type=int, default=200, help="episodes per evaluate/simevo measurement")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--simevo", default=shutil.which("simevo"), help="simevo program (default: on PATH)")
    args = ap.parse_args()
    if not args.simevo or not os.access(args.simevo, os.X_OK):
        sys.exit("benchmark: --simevo: no simevo program (give its path)")
    env = qnavpy.Env(args.world, args.robot, sensor_noise=0.0, actuation_noise=0.0)
    ctrl = qnavpy.Controller(env=env)
    print(f"qnavpy {qnavpy.__version__}, {args.robot} in {args.world}, {os.cpu_count()} cores, "
          f"{args.repeats} repeats")
    rows = [("steps/s, env.step() (controller in C)", lambda: stepped(env, args.episodes, None)),
            ("steps/s, env.step((heading, speed))", lambda: stepped(env, args.episodes, (0.0, 0.5))),
            ("steps/s, Controller.decide + env.step", lambda: python_decides(env, ctrl, args.episodes)),
            ("steps/s, env.run_episode() (all in C)", lambda: in_c(env, args.episodes))]
    for jobs in (1, 2):
        rows.append((f"episodes/s, evaluate(jobs={jobs})", lambda j=jobs: evaluate_rate(j, args.eval_episodes, args)))
        rows.append((f"episodes/s, {jobs} x simevo eval", lambda j=jobs: simevo_rate(args.simevo, j,
                                                                                      args.eval_episodes, args)))
    for label, fn in rows:
        print(f"{label:42s} {spread([fn() for _ in range(args.repeats)])}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
