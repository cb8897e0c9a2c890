#!/usr/bin/python3
"""The plot scripts on a real (tiny) experiment: simevo writes learning.png with three
panels (best fitness, candidates' R, candidates' arrival) and episodes.png with one row per
condition and one panel per held-out episode; a malformed episodes.csv gets one line naming
the file and line and exit status 1.

Usage: test_plots.py SIMEVO_EXE SOURCE_DIR
"""
import csv
import os
import struct
import subprocess
import sys
import tempfile


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG"
    return struct.unpack(">II", head[16:24])


def main(exe, src):
    out = tempfile.mkdtemp(prefix="simevo-plots-")
    env = dict(os.environ, QNAV_DATA_DIR=os.path.join(src, "data"), QNAV_TOOLS_DIR=os.path.join(src, "tools"))
    r = subprocess.run([exe, "run", os.path.join(src, "tests/simevo/tiny.toml"), "--out", out, "--no-progress",
                        "-j", "2"], env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    exp = os.path.join(out, "tiny")
    w, h = png_size(os.path.join(exp, "learning.png"))
    assert w > 3 * h, f"learning.png {w}x{h}: expected three panels side by side"
    with open(os.path.join(exp, "episodes.csv")) as f:
        rows = list(csv.DictReader(f))
    conditions = sorted({row["condition"].split(" (")[0] for row in rows})
    assert conditions == ["direct", "probabilistic", "transfer-open", "vfh"], conditions
    episodes = {(row["condition"], row["episode"]) for row in rows}
    assert len(episodes) == 4 * 3, episodes  # 4 conditions (with VFH+) x 3 held-out episodes
    w, h = png_size(os.path.join(exp, "episodes.png"))
    assert h > w, f"episodes.png {w}x{h}: expected 3 rows of 3 panels (taller than wide)"

    bad = os.path.join(out, "bad")
    os.makedirs(bad)
    for name in ("summary.json",):
        with open(os.path.join(exp, name)) as f, open(os.path.join(bad, name), "w") as g:
            g.write(f.read())
    with open(os.path.join(bad, "episodes.csv"), "w") as g:
        g.write("condition,episode,tick,x_m,y_m,recovering,collided,R,reached,tau_c\n"
                "direct,0,0,1.0,1.0,0,0,1.0,0,0\ndirect,0,1,one,1.0,0,0,1.0,0,0\n")
    r = subprocess.run(["/usr/bin/python3", os.path.join(src, "tools/plot_episodes.py"), bad], capture_output=True,
                       text=True)
    assert r.returncode == 1, r
    assert r.stderr.count("\n") == 1 and "episodes.csv:3:" in r.stderr, r.stderr
    assert not os.path.exists(os.path.join(bad, "episodes.png"))
    print("plots ok")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
