#!/usr/bin/python3
"""Learning curves of a simevo experiment, like the paper's Figs. 7-11.

Usage: plot_learning.py EXPERIMENT_DIR [OUT.png]

Reads EXPERIMENT_DIR/curves.csv and summary.json (written by `simevo run`) and draws, per
condition, the mean over runs with its 95% confidence band of (left) the population's best
fitness and (right) the episode R of the candidates (binned); the probabilistic policy is a
horizontal reference band (its held-out mean and 95% CI). Writes EXPERIMENT_DIR/learning.png unless OUT.png is given. Needs matplotlib only.
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from plotcommon import PlotError, parse_args, read_csv, run, save  # noqa: E402


def main(argv):
    args = parse_args(argv, "plot_learning.py", "learning.png")
    if args is None:
        return 2
    exp, out = args
    keys = ("mean", "ci_low", "ci_high", "best_mean", "best_ci_low", "best_ci_high")
    summary_path = os.path.join(exp, "summary.json")
    try:
        with open(summary_path) as f:
            summary = json.load(f)
    except OSError as e:
        raise PlotError(f"{summary_path}: {e.strerror}") from e
    except json.JSONDecodeError as e:
        raise PlotError(f"{summary_path}:{e.lineno}: {e.msg}") from e
    curves = {}

    def add(row):
        c = curves.setdefault(row["condition"], {k: [] for k in ("episode",) + keys})
        c["episode"].append(int(row["episode"]))
        for k in keys:
            c[k].append(float(row[k]) if row[k] != "null" else float("nan"))

    read_csv(os.path.join(exp, "curves.csv"), add)

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), dpi=110, layout="constrained")
    colors = {"direct": "tab:red", "probabilistic": "tab:gray"}
    palette = ["tab:blue", "tab:green", "tab:purple", "tab:orange"]
    conds = {c["label"]: c for c in summary["conditions"]}
    transfer = [k for k in curves if k.startswith("transfer-")]
    for i, k in enumerate(transfer):
        colors[k] = palette[i % len(palette)]
    panels = (
        (axes[0], "best", "population's best fitness R (mean over runs)"),
        (axes[1], "", f"candidates' episode R ({summary['curve_bin']}-episode bins, mean over runs)"),
    )
    for ax, prefix, ylabel in panels:
        m_key, lo_key, hi_key = (prefix + "_mean", prefix + "_ci_low", prefix + "_ci_high") if prefix else keys[:3]
        for k in transfer + ["direct"]:
            if k not in curves:
                continue
            c = curves[k]
            label = k.replace("transfer-", "transfer from ") if k != "direct" else "direct (random population)"
            ax.plot(c["episode"], c[m_key], color=colors[k], lw=1.8, label=label)
            ax.fill_between(c["episode"], c[lo_key], c[hi_key], color=colors[k], alpha=0.2, lw=0)
        p = conds.get("probabilistic")
        if p and p["final_mean"] is not None:
            mean = p["final_mean"]
            ci = p["final_ci95"] or 0.0
            ax.axhline(mean, color=colors["probabilistic"], ls="--", lw=1.5, label="probabilistic (held out)")
            ax.axhspan(mean - ci, mean + ci, color=colors["probabilistic"], alpha=0.15, lw=0)
        ax.set_xlabel("episode in the target situation")
        ax.set_ylabel(ylabel, fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, loc="lower right")
    fig_ref = f" ({summary['figure']})" if summary.get("figure") else ""
    fig.suptitle(f"{summary['title'] or summary['name']}{fig_ref}: "
                 f"{summary['runs']} runs, preset {summary['preset']}; bands: 95% CI", fontsize=10)
    save(fig, out)
    return 0


if __name__ == "__main__":
    sys.exit(run(main, sys.argv, "plot_learning.py"))
