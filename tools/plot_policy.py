#!/usr/bin/python3
"""What decides, for each policy, over (angular distance to the destination, obstacle
distance), like the paper's Figs. 2 (probabilistic) and 3 (evolved network).

Usage: plot_policy.py EXPERIMENT_DIR [OUT.png]

Reads EXPERIMENT_DIR/quality.csv (written by `simevo run` and `simevo quality`: for every
distance level and every degree of dtheta, libqnav's fixed-point quality and the rank key
its argmax compares) and draws one panel per policy: x = dtheta (deg), y = distance (m),
colour = the rank key: the network output's pre-activation z where the controller ranks by
it (a saturated network's quality is flat at 1.0 over most cells while z still orders
them), the quality X for the probabilistic policy. The dashed line is where the quality
reaches 0.9 (full speed). Files without the rank columns are drawn by quality. Writes
EXPERIMENT_DIR/policy.png unless OUT.png is given.
"""
import os
import sys

from plotcommon import PlotError, import_pyplot, parse_args, read_csv, run, save

plt = import_pyplot("plot_policy.py")
import numpy as np  # noqa: E402  (a matplotlib dependency)


def read_quality(path):
    """quality.csv's rows by policy: (level, distance_m, dtheta_deg, quality, rank, key)."""
    data = {}

    def add(row):
        rank = row.get("rank") or "quality"
        if rank not in ("preact", "quality"):
            raise ValueError(f"rank '{rank}' is not preact or quality")
        quality = float(row["quality"])
        key = float(row["key"]) if row.get("key") else quality
        data.setdefault(row["policy"], []).append(
            (int(row["level"]), float(row["distance_m"]), int(row["dtheta_deg"]), quality, rank, key))

    read_csv(path, add)
    if not data:
        raise PlotError(f"{path}: no rows")
    return data


def draw(data):
    """One panel per policy coloured by what its argmax ranks; returns the figure."""
    n = len(data)
    fig, axes = plt.subplots(1, n, figsize=(3.3 * n + 0.6, 3.4), dpi=120, squeeze=False,
                             sharey=True, layout="constrained")
    for ax, (name, rows) in zip(axes[0], data.items()):
        levels = max(r[0] for r in rows) + 1
        dmax = max(r[1] for r in rows)
        q = np.zeros((levels, 181))
        k = np.zeros((levels, 181))
        for lvl, _, dt, qual, _, key in rows:
            q[lvl, dt] = qual
            k[lvl, dt] = key
        extent = (0, 180, 0, dmax)
        if rows[0][4] == "preact":
            lim = max(float(np.abs(k).max()), 1e-6)
            im = ax.imshow(k, origin="lower", aspect="auto", extent=extent, vmin=-lim, vmax=lim, cmap="RdBu_r")
            label = "output pre-activation z (ranked)"
        else:
            im = ax.imshow(k, origin="lower", aspect="auto", extent=extent, vmin=0, vmax=1, cmap="viridis")
            label = "path quality X (ranked)"
        if levels > 1 and q.min() < 0.9 < q.max():
            ax.contour(np.linspace(0, 180, 181), np.linspace(0, dmax, levels), q, levels=[0.9], colors="black",
                       linewidths=0.8, linestyles="dashed")
        fig.colorbar(im, ax=ax, shrink=0.9, label=label)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("Δθ to destination (deg)")
    axes[0][0].set_ylabel("distance to obstacle (m)")
    return fig


def main(argv):
    args = parse_args(argv, "plot_policy.py", "policy.png")
    if args is None:
        return 2
    exp, out = args
    save(draw(read_quality(os.path.join(exp, "quality.csv"))), out)
    return 0


if __name__ == "__main__":
    sys.exit(run(main, sys.argv, "plot_policy.py"))
