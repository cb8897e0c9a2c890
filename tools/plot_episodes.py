#!/usr/bin/python3
"""Held-out episodes of each condition's best policy, drawn in the target environment.

Usage: plot_episodes.py EXPERIMENT_DIR [OUT.png]

Reads EXPERIMENT_DIR/summary.json (the environment file and the robot's radius) and
EXPERIMENT_DIR/episodes.csv (written by `simevo run`: the trajectories of every
condition's best policy, and of the probabilistic policy, on the first held-out episodes)
and the environment's TOML file; draws one row per condition and one panel per episode:
obstacles (grey), start zones (dashed), destination (orange), the path (blue, red while
recovering from a collision), collisions (red crosses), start (black dot) and the robot's
body at the end, with a legend of these marks below the panels and the arena's scale in
metres on the axes. Writes EXPERIMENT_DIR/episodes.png unless OUT.png is given.
"""
import math
import os
import sys

from plotcommon import PlotError, import_pyplot, parse_args, read_csv, read_json, read_toml, run, save

plt = import_pyplot("plot_episodes.py")
import matplotlib.lines as mlines  # noqa: E402
import matplotlib.patches as mpatches  # noqa: E402


def draw_env(ax, env):
    w, h = env["arena"]["width_m"], env["arena"]["height_m"]
    ax.add_patch(mpatches.Rectangle((0, 0), w, h, fill=False, lw=1.5, ec="black"))
    for z in env.get("start_zone", []):
        ax.add_patch(mpatches.Rectangle((z["x_m"], z["y_m"]), z["w_m"], z["h_m"], fill=False, ls="--",
                                        ec="tab:green", lw=0.8))
    for c in env.get("circle", []):
        ax.add_patch(mpatches.Circle((c["x_m"], c["y_m"]), c["r_m"], fc="0.6", ec="0.3", lw=0.5))
    for b in env.get("box", []):
        a = math.radians(b.get("angle_deg", 0.0))
        # lower-left corner of the rotated box, from its centre
        dx, dy = -b["w_m"] / 2, -b["h_m"] / 2
        x = b["x_m"] + dx * math.cos(a) - dy * math.sin(a)
        y = b["y_m"] + dx * math.sin(a) + dy * math.cos(a)
        ax.add_patch(mpatches.Rectangle((x, y), b["w_m"], b["h_m"], angle=math.degrees(a), fc="0.6", ec="0.3",
                                        lw=0.5))
    d = env["destination"]
    ax.add_patch(mpatches.Circle((d["x_m"], d["y_m"]), d["radius_m"], fc="tab:orange", alpha=0.6, ec="tab:red"))
    ax.set_xlim(-0.2, w + 0.2)
    ax.set_ylim(-0.2, h + 0.2)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=7, length=2, pad=1)


def draw_path(ax, ep, radius):
    xs, ys, rec = ep["x"], ep["y"], ep["recovering"]
    for i in range(1, len(xs)):
        ax.plot(xs[i - 1:i + 1], ys[i - 1:i + 1], color="tab:red" if rec[i] else "tab:blue", lw=1.2)
    cx = [x for x, c in zip(xs, ep["collided"]) if c]
    cy = [y for y, c in zip(ys, ep["collided"]) if c]
    ax.plot(cx, cy, "x", color="red", ms=6, mew=1.5)
    ax.plot(xs[:1], ys[:1], "o", color="black", ms=4)
    ax.add_patch(mpatches.Circle((xs[-1], ys[-1]), radius, fill=False, ec="tab:blue", lw=1))


def legend_handles():
    """What each mark of draw_env and draw_path means, for the figure's legend."""
    return [
        mpatches.Patch(fc="0.6", ec="0.3", label="obstacle"),
        mpatches.Patch(fill=False, ls="--", ec="tab:green", label="start zone"),
        mpatches.Patch(fc="tab:orange", alpha=0.6, ec="tab:red", label="destination"),
        mlines.Line2D([], [], color="tab:blue", lw=1.2, label="path"),
        mlines.Line2D([], [], color="tab:red", lw=1.2, label="path while recovering from a collision"),
        mlines.Line2D([], [], ls="", marker="x", color="red", ms=6, mew=1.5, label="collision"),
        mlines.Line2D([], [], ls="", marker="o", color="black", ms=4, label="start"),
        mlines.Line2D([], [], ls="", marker="o", mfc="none", mec="tab:blue", ms=8, label="robot at the end"),
    ]


def draw(summary, env, episodes):
    """The figure: one row per condition, one panel per held-out episode."""
    radius = summary["robot_radius_m"]
    rows = len(episodes)
    cols = max(len(e) for e in episodes.values())
    fig = plt.figure(figsize=(3.2 * cols, 3.4 * rows + 0.6), dpi=100, layout="constrained")
    # a last, low row holds the legend (a figure legend is not placed by constrained layout
    # before matplotlib 3.7, Debian 12 has 3.6)
    grid = fig.add_gridspec(rows + 1, cols, height_ratios=[3.4] * rows + [0.6])
    axes = [[fig.add_subplot(grid[r, c]) for c in range(cols)] for r in range(rows)]
    # the lowest panel of each column carries the x axis's name
    last_row = [max(r for r, eps in enumerate(episodes.values()) if c in eps) for c in range(cols)]
    for r, (cond, eps) in enumerate(episodes.items()):
        for c in range(cols):
            ax = axes[r][c]
            if c not in eps:
                ax.axis("off")
                continue
            ep = eps[c]
            draw_env(ax, env)
            draw_path(ax, ep, radius)
            verdict = "arrived" if ep["reached"] else "did not arrive"
            ax.set_title(f"{cond}\nheld-out episode {c + 1}: {verdict}, R {ep['R']:.2f}, tau_c {ep['tau_c']}",
                         fontsize=8)
            if r == last_row[c]:
                ax.set_xlabel("x (m)", fontsize=8)
            if c == 0:
                ax.set_ylabel("y (m)", fontsize=8)
    key = fig.add_subplot(grid[rows, :])
    key.axis("off")
    key.legend(handles=legend_handles(), loc="center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle(f"{summary['title'] or summary['name']}: best policies on held-out episodes", fontsize=10)
    return fig


def main(argv):
    args = parse_args(argv, "plot_episodes.py", "episodes.png")
    if args is None:
        return 2
    exp, out = args
    summary = read_json(os.path.join(exp, "summary.json"))
    env = read_toml(summary["environment_file"])
    episodes = {}  # condition -> episode -> columns

    def add(row):
        cond = episodes.setdefault(row["condition"], {})
        ep = cond.setdefault(int(row["episode"]), {"x": [], "y": [], "recovering": [], "collided": []})
        ep["x"].append(float(row["x_m"]))
        ep["y"].append(float(row["y_m"]))
        ep["recovering"].append(row["recovering"] == "1")
        ep["collided"].append(row["collided"] == "1")
        ep["R"], ep["reached"], ep["tau_c"] = float(row["R"]), row["reached"] == "1", int(row["tau_c"])

    path = os.path.join(exp, "episodes.csv")
    read_csv(path, add)
    if not episodes:
        raise PlotError(f"{path}: no episodes")
    save(draw(summary, env, episodes), out)
    return 0


if __name__ == "__main__":
    sys.exit(run(main, sys.argv, "plot_episodes.py"))
