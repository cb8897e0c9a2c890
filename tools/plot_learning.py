#!/usr/bin/python3
"""Learning curves of a simevo experiment, like the paper's Figs. 7-11.

Usage: plot_learning.py EXPERIMENT_DIR [OUT.png]

Reads EXPERIMENT_DIR/curves.csv and summary.json (written by `simevo run`) and draws, per
condition, the mean over runs with its 95% confidence band of (left) the population's best
fitness (an evolution strategy's centre's R), (middle) the R of the candidates (binned) and (right) the fraction of the
candidates' episodes that reached the destination (binned); the references (summary.json
"references": simevo's reference table, e.g. the probabilistic policy dashed and VFH+
dotted) are horizontal bands (their mean and 95% CI on the held-out episodes). The legends and the arrival panel's title say which line is
the candidates' (training episodes) and which a reference's (held-out episodes). Writes EXPERIMENT_DIR/learning.png
unless OUT.png is given. Needs matplotlib only.
"""
import os
import sys

from plotcommon import import_pyplot, parse_args, read_csv, read_json, run, save

plt = import_pyplot("plot_learning.py")


KEYS = ("mean", "ci_low", "ci_high", "best_mean", "best_ci_low", "best_ci_high",
        "arrival_mean", "arrival_ci_low", "arrival_ci_high")


def draw(summary, curves):
    """The figure of summary.json and curves.csv's columns ({condition: {column: [values]}}).
    The curves are the candidates' during evolution; the horizontal lines are the references
    on the held-out episodes. Each panel says which is which in its legend, the arrival panel
    also in its title, since its two kinds of arrival are read against each other."""
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.9), dpi=110, layout="constrained")
    # the references, one row each in simevo's table (summary.json "references", written
    # from kReferences in host/simevo/src/task.h): no list of them is kept here
    references = summary.get("references", [])
    colors = {"direct": "tab:red"}
    colors.update({r["label"]: r["plot_color"] for r in references})
    palette = ["tab:blue", "tab:green", "tab:purple", "tab:orange"]
    conds = {c["label"]: c for c in summary["conditions"]}
    transfer = [k for k in curves if k.startswith("transfer-")]
    for i, k in enumerate(transfer):
        colors[k] = palette[i % len(palette)]
    per_candidate = summary.get("episodes_per_candidate", 1)
    es = summary.get("algorithm") == "es"  # an evolution strategy: a centre, no population
    panels = (
        (axes[0], "best", ("centre's R on its iteration's episodes" if es else "population's best fitness R")
         + " (mean over runs)", "final_mean", 1.0,
         "evolution strategy's centre during evolution" if es else "best fitness during evolution",
         "R on held-out episodes"),
        (axes[1], "", f"candidates' R ({summary['curve_bin']}-episode bins, k = {per_candidate}, mean over runs)",
         "final_mean", 1.0, "candidates' R during evolution", "R on held-out episodes"),
        (axes[2], "arrival", "episodes that arrived (%)", "arrival", 100.0,
         "arrival: candidates' training episodes (curves, binned, mean over runs)\n"
         "vs. the references on held-out episodes (horizontal lines)", "arrival on held-out episodes"),
    )
    for ax, prefix, ylabel, ref, scale, title, ref_what in panels:
        m_key, lo_key, hi_key = (prefix + "_mean", prefix + "_ci_low", prefix + "_ci_high") if prefix else KEYS[:3]
        for k in transfer + ["direct"]:
            if k not in curves:
                continue
            c = curves[k]
            label = (k.replace("transfer-", "transfer from ") if k != "direct"
                     else "direct (random network)" if es else "direct (random population)")
            if prefix == "arrival":
                label += ": candidates"
            ax.plot(c["episode"], [v * scale for v in c[m_key]], color=colors[k], lw=1.8, label=label)
            ax.fill_between(c["episode"], [v * scale for v in c[lo_key]], [v * scale for v in c[hi_key]],
                            color=colors[k], alpha=0.2, lw=0)
        for r in references:
            ref_label, ls = r["label"], r["plot_style"]
            # the table's plot name ends in "(held out)"; the legend says on what
            name = r["plot_name"].replace(" (held out)", "") + ": " + ref_what
            p = conds.get(ref_label)
            if p and ref == "final_mean" and p["final_mean"] is not None:
                mean = p["final_mean"]
                ci = p["final_ci95"] or 0.0
                ax.axhline(mean, color=colors[ref_label], ls=ls, lw=1.5, label=name)
                ax.axhspan(mean - ci, mean + ci, color=colors[ref_label], alpha=0.15, lw=0)
            elif p and ref == "arrival" and p.get("arrival"):
                a = p["arrival"]
                ax.axhline(100 * a["mean"], color=colors[ref_label], ls=ls, lw=1.5, label=name)
                ax.axhspan(100 * a["ci95_low"], 100 * a["ci95_high"], color=colors[ref_label], alpha=0.15, lw=0)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("episode in the target situation")
        ax.set_ylabel(ylabel, fontsize=9)
        ax.grid(alpha=0.3)
    axes[2].set_ylim(-2, 102)
    axes[0].legend(fontsize=7, loc="lower right")
    axes[2].legend(fontsize=7, loc="lower right")
    fig_ref = f" ({summary['figure']})" if summary.get("figure") else ""
    fig.suptitle(f"{summary['title'] or summary['name']}{fig_ref}: "
                 f"{summary['runs']} runs, preset {summary['preset']}; bands: 95% CI", fontsize=10)
    return fig


def main(argv):
    args = parse_args(argv, "plot_learning.py", "learning.png")
    if args is None:
        return 2
    exp, out = args
    summary = read_json(os.path.join(exp, "summary.json"))
    curves = {}

    def add(row):
        c = curves.setdefault(row["condition"], {k: [] for k in ("episode",) + KEYS})
        c["episode"].append(int(row["episode"]))
        for k in KEYS:
            c[k].append(float(row[k]) if row[k] != "null" else float("nan"))

    read_csv(os.path.join(exp, "curves.csv"), add)
    save(draw(summary, curves), out)
    return 0


if __name__ == "__main__":
    sys.exit(run(main, sys.argv, "plot_learning.py"))
