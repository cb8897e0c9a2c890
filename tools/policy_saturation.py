#!/usr/bin/env python3
"""How saturated evolved network policies are, in double precision: for each policy file,
the output pre-activation y over the 32 x 181 (distance level, dtheta) grid, the share of
entries whose Q1.15 quality rounds to the top (32767: ranking by quality ties there) and
the share beyond libqnav's companded rank key (|y| >= 136: ranking by key ties there).
Used for docs/architecture.md ("Argmax on the pre-activation") and docs/results.md.

Usage: tools/policy_saturation.py POLICY [POLICY ...]
"""
import argparse
import math
import sys

LEVELS, DTHETA = 32, 181
KEY_LIMIT = 136.0  # docs/qformats.md, "Rank key"


def read_network(path):
    units, b_out = [], None
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            t = line.split("#")[0].split()
            if not t:
                continue
            if t[0] == "kind" and t[1:] != ["network"]:
                raise ValueError(f"{path}:{n}: not a network policy")
            try:
                if t[0] == "unit":
                    units.append([int(x) / 256.0 for x in t[2:6]])
                elif t[0] == "b_out":
                    b_out = int(t[1]) / 256.0
            except (ValueError, IndexError):
                raise ValueError(f"{path}:{n}: malformed '{t[0]}' line")
    if not units or b_out is None:
        raise ValueError(f"{path}:1: no network units or no b_out")
    return units, b_out


def sigmoid(z):
    return 1.0 / (1.0 + math.exp(-z)) if z > -700 else 0.0


def stats(path):
    units, b_out = read_network(path)
    ys = []
    for level in range(LEVELS):
        for dt in range(DTHETA):
            xt, xd = dt / 180.0, level / (LEVELS - 1.0)
            ys.append(b_out + sum(wo * sigmoid(wt * xt + wd * xd + bh) for wt, wd, bh, wo in units))
    pinned = sum(1 for y in ys if round(sigmoid(y) * 32768) >= 32767) / len(ys)
    beyond = sum(1 for y in ys if abs(y) >= KEY_LIMIT) / len(ys)
    return max(abs(y) for y in ys), pinned, beyond


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("policies", nargs="+", metavar="POLICY", help="network policy files")
    args = ap.parse_args()
    try:
        rows = [stats(p) for p in args.policies]
    except (OSError, ValueError) as e:
        print(f"policy_saturation: {e}", file=sys.stderr)
        return 2
    n = len(rows)
    ymax = sorted(r[0] for r in rows)
    print(f"{n} policies: max |y| median {ymax[n // 2]:.1f}, largest {ymax[-1]:.1f}; "
          f"quality pinned at the top on {100 * sum(r[1] for r in rows) / n:.1f}% of entries "
          f"(largest {100 * max(r[1] for r in rows):.1f}%); "
          f"beyond the rank key's range on {100 * sum(r[2] for r in rows) / n:.2f}% "
          f"(largest {100 * max(r[2] for r in rows):.2f}%)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
