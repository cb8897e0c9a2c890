#!/usr/bin/python3
"""Evolve a navigation network with a small evolution strategy written against
qnavpy.evaluate, run the best in one episode and plot its trajectory (docs/python.md).

The strategy is an elitist (1 + lambda) ES: each generation mutates the parent's real-valued
weights with Gaussian noise, scores parent and children on the same training episodes in
one evaluate() call, and keeps the best. Training and the final comparison use different
episode seeds, so the printed held-out figures are not the ones it was selected on.

    PYTHONPATH=$HOME/qnav/share/qnav/python python3 evolve_policy.py --out runs/py
"""

import argparse
import os
import sys

import numpy as np

import qnavpy


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--world", default="dense", help="environment name, file or gen: spec (default dense)")
    ap.add_argument("--robot", default="tekbot", help="robot profile (default tekbot)")
    ap.add_argument("--hidden", type=int, default=6, help="hidden units (default 6)")
    ap.add_argument("--generations", type=int, default=30, help="generations (default 30)")
    ap.add_argument("--children", type=int, default=15, help="children per generation, lambda (default 15)")
    ap.add_argument("--episodes", type=int, default=6, help="training episodes per candidate (default 6)")
    ap.add_argument("--sigma", type=float, default=1.0, help="mutation standard deviation, weight units")
    ap.add_argument("--held-out", type=int, default=40, help="held-out episodes of the final comparison")
    ap.add_argument("--seed", type=int, default=1, help="seed of the strategy and of the training episodes")
    ap.add_argument("--jobs", type=int, default=0, help="evaluation threads (0: every core)")
    ap.add_argument("--out", default="runs/python-es", help="folder for best.policy and trajectory.png")
    return ap.parse_args(argv)


def evolve(args, rng):
    """The best weight vector and its training mean R after each generation."""
    n = 4 * args.hidden + 1
    parent = rng.normal(0.0, 1.0, n)
    history = []
    score = None
    for gen in range(args.generations):
        children = parent + rng.normal(0.0, args.sigma, (args.children, n))
        batch = np.vstack([parent, children])
        ev = qnavpy.evaluate(batch, args.episodes, world=args.world, robot=args.robot, seed=args.seed,
                             jobs=args.jobs)
        mean_r = ev.mean_R()
        best = int(np.argmax(mean_r))  # ties keep the parent (row 0)
        parent, score = batch[best], float(mean_r[best])
        history.append(score)
        print(f"generation {gen + 1:3d}: best training R {score:6.3f}  arrival {ev.arrival()[best]:4.0%}",
              flush=True)
    return parent, history


def plot_episode(env, episode, title, path):
    """The world, the destination and the robot's path (red crosses: collisions)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Rectangle
    from matplotlib.transforms import Affine2D

    fig, ax = plt.subplots(figsize=(6.4, 6.4 * env.world.height_m / env.world.width_m + 0.6))
    ax.add_patch(Rectangle((0, 0), env.world.width_m, env.world.height_m, fill=False, lw=2, color="black"))
    circles, boxes = env.obstacles()
    for x, y, r in circles:
        ax.add_patch(Circle((x, y), r, color="0.55"))
    for x, y, w, h, a in boxes:
        box = Rectangle((x - w / 2, y - h / 2), w, h, color="0.55")
        box.set_transform(Affine2D().rotate_deg_around(x, y, a) + ax.transData)
        ax.add_patch(box)
    dx, dy = env.world.dest
    ax.add_patch(Circle((dx, dy), env.world.dest_radius_m, color="tab:green", alpha=0.4, label="destination"))
    t = episode.trajectory
    ax.plot(t["x_m"], t["y_m"], color="tab:blue", lw=1.5, label="robot centre")
    ax.add_patch(Circle((t["x_m"][0], t["y_m"][0]), env.robot.radius_m, fill=False, color="tab:blue"))
    hits = t[t["collided"]]
    if len(hits):
        ax.plot(hits["x_m"], hits["y_m"], "x", color="tab:red", ms=9, mew=2, label="collision")
    ax.set_xlim(-0.2, env.world.width_m + 0.2)
    ax.set_ylim(-0.2, env.world.height_m + 0.2)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title, fontsize=9)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    args = parse_args(argv)
    rng = np.random.default_rng(args.seed)
    os.makedirs(args.out, exist_ok=True)
    weights, _ = evolve(args, rng)
    best = qnavpy.Policy.network(weights)
    policy_path = os.path.join(args.out, "best.policy")
    best.write(policy_path, comment=f"evolve_policy.py: (1+{args.children}) ES, {args.generations} generations "
                                    f"on {args.world}, {args.robot}")

    held_out_seed = args.seed + 1000
    ev = qnavpy.evaluate([best, "prob"], args.held_out, world=args.world, robot=args.robot, seed=held_out_seed,
                         jobs=args.jobs)
    for name, r, a in zip(("evolved", "probabilistic"), ev.mean_R(), ev.arrival()):
        print(f"held-out ({args.held_out} episodes, seed {held_out_seed}): {name:13s} mean R {r:6.3f}  "
              f"arrival {a:4.0%}")

    env = qnavpy.Env(args.world, args.robot, policy=best, sensor_noise=0.0, actuation_noise=0.0, seed=held_out_seed)
    episode = env.run_episode(seed=0)
    r = episode.result
    title = (f"{env.robot.name}, {env.world.name}, evolved network (H = {args.hidden}): "
             f"{'reached' if r['reached'] else 'not reached'} in {r['ticks'] / 10:.1f} s, R {r['R']:.2f}")
    picture = os.path.join(args.out, "trajectory.png")
    plot_episode(env, episode, title, picture)
    print(f"policy {policy_path}; trajectory {picture} ({title})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
