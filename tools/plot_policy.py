#!/usr/bin/python3
"""Path quality of policies over (angular distance to the destination, obstacle distance),
like the paper's Figs. 2 (probabilistic) and 3 (evolved network).

Usage: plot_policy.py EXPERIMENT_DIR [OUT.png]

Reads EXPERIMENT_DIR/quality.csv (written by `simevo run`: the fixed-point quality that
libqnav computes, qnav_ctrl_quality, for every distance level and every degree of
dtheta) and draws one panel per policy: x = dtheta (deg), y = distance (m), colour =
quality. Writes EXPERIMENT_DIR/policy.png unless OUT.png is given.
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(argv):
    if len(argv) not in (2, 3):
        print("usage: plot_policy.py EXPERIMENT_DIR [OUT.png]", file=sys.stderr)
        return 2
    exp = argv[1]
    out = argv[2] if len(argv) == 3 else os.path.join(exp, "policy.png")
    path = os.path.join(exp, "quality.csv")
    data = {}
    try:
        with open(path) as f:
            reader = csv.DictReader(f)
            for row in reader:
                data.setdefault(row["policy"], []).append(
                    (int(row["level"]), float(row["distance_m"]), int(row["dtheta_deg"]), float(row["quality"])))
    except OSError as e:
        print(f"plot_policy.py: {path}: {e.strerror}", file=sys.stderr)
        return 1
    except KeyError as e:
        print(f"plot_policy.py: {path}:1: missing column {e}", file=sys.stderr)
        return 1
    except (ValueError, TypeError) as e:
        print(f"plot_policy.py: {path}:{reader.line_num}: {e}", file=sys.stderr)
        return 1
    if not data:
        print(f"plot_policy.py: {path}: no rows", file=sys.stderr)
        return 1
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
    tmp = out + ".tmp.png"
    fig.savefig(tmp)
    os.replace(tmp, out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
