#!/usr/bin/python3
"""Path quality of policies over (angular distance to the destination, obstacle distance),
like the paper's Figs. 2 (probabilistic) and 3 (evolved network).

Usage: plot_policy.py EXPERIMENT_DIR [OUT.png]

Reads EXPERIMENT_DIR/quality.csv (written by `simevo run`: the fixed-point quality that
libqnav computes, qnav_ctrl_quality, for every distance level and every degree of
dtheta) and draws one panel per policy: x = dtheta (deg), y = distance (m), colour =
quality. Writes EXPERIMENT_DIR/policy.png unless OUT.png is given.
"""
import os
import sys

from plotcommon import PlotError, import_pyplot, parse_args, read_csv, run, save

plt = import_pyplot("plot_policy.py")
import numpy as np  # noqa: E402  (a matplotlib dependency)


def main(argv):
    args = parse_args(argv, "plot_policy.py", "policy.png")
    if args is None:
        return 2
    exp, out = args
    path = os.path.join(exp, "quality.csv")
    data = {}
    read_csv(path, lambda row: data.setdefault(row["policy"], []).append(
        (int(row["level"]), float(row["distance_m"]), int(row["dtheta_deg"]), float(row["quality"]))))
    if not data:
        raise PlotError(f"{path}: no rows")
    n = len(data)
    fig, axes = plt.subplots(1, n, figsize=(2.9 * n + 1.0, 3.2), dpi=120, squeeze=False,
                             sharey=True, layout="constrained")
    im = None
    for ax, (name, rows) in zip(axes[0], data.items()):
        levels = max(r[0] for r in rows) + 1
        dmax = max(r[1] for r in rows)
        q = np.zeros((levels, 181))
        for lvl, _, dt, val in rows:
            q[lvl, dt] = val
        im = ax.imshow(q, origin="lower", aspect="auto", extent=(0, 180, 0, dmax), vmin=0, vmax=1, cmap="viridis")
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("Δθ to destination (deg)")
    axes[0][0].set_ylabel("distance to obstacle (m)")
    fig.colorbar(im, ax=axes[0].tolist(), shrink=0.95, label="path quality X")
    save(fig, out)
    return 0


if __name__ == "__main__":
    sys.exit(run(main, sys.argv, "plot_policy.py"))
