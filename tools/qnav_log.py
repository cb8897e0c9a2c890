#!/usr/bin/python3
"""Turn a qnav LCM log (navbridge --log, lcm-logger) into CSV files and a picture of the
trial: trajectory (QNAV_POSE), commands (QNAV_COMMAND: heading and speed over time) and
link status (QNAV_LINK_STATUS: frames dropped, heartbeat age).

Usage: qnav_log.py LOG [--csv DIR] [--plot OUT.png|.pdf|.svg] [--types DIR]

--csv DIR writes one file per channel, DIR/<channel>.csv (qnav_scan.csv, qnav_command.csv,
...): a column log_utime (the log's receive time, microseconds) and one column per field
of the message in its .lcm order; arrays are one column of space-separated values. The
messages are decoded by the Python classes that lcm-gen makes from host/lcmtypes/*.lcm
(no python3-lcm needed): --types DIR names the folder holding their package qnav/
(build/.../host/lcmtypes/python), default QNAV_PYTHON_DIR, then the installed
share/qnav/python. Without --csv or --plot it prints the count of messages per channel.
Exit status: 0, 1 when a file cannot be written, 2 for bad usage or a file that is not an
LCM log of qnav messages (docs/cli.md).
"""
import argparse
import csv
import importlib
import os
import struct
import sys

import plotcommon
from plotcommon import PlotError

SYNC = 0xEDA1DA01
# channel -> generated type (host/navbridge/bridge.h)
CHANNELS = {
    "QNAV_SCAN": "scan_t",
    "QNAV_GOAL": "goal_t",
    "QNAV_COMMAND": "command_t",
    "QNAV_QUALITIES": "path_qualities_t",
    "QNAV_POSE": "pose_t",
    "QNAV_LINK_STATUS": "link_status_t",
    "QNAV_WAYPOINTS": "waypoints_t",
    "QNAV_ODOMETRY": "odometry_t",
    "QNAV_NAV_INPUT": "nav_input_t",
}
# navbridge --lcm-goals takes goals and routes on QNAV_GOAL_<token> and
# QNAV_WAYPOINTS_<token> (docs/hil.md): the same types as the plain channels
TOKEN_CHANNELS = ("QNAV_GOAL", "QNAV_WAYPOINTS")


class LogError(Exception):
    """The input is not what it should be; str() is the one-line message (exit 2)."""


def read_events(path):
    """(log_utime, channel, data) of every event of an LCM log (lcm's eventlog format:
    sync word, event number, timestamp, channel and data lengths, big-endian)."""
    try:
        with open(path, "rb") as f:
            blob = f.read()
    except IsADirectoryError as e:
        raise LogError(f"{path}: is a directory, not a file") from e
    except OSError as e:
        raise LogError(f"{path}: cannot open ({e.strerror})") from e
    events, off, head = [], 0, struct.Struct(">Iqqii")
    while off + head.size <= len(blob):
        sync, _, utime, clen, dlen = head.unpack_from(blob, off)
        if sync != SYNC or clen < 0 or dlen < 0:
            raise LogError(f"{path}: byte {off}: not an LCM log event (bad sync word)")
        off += head.size
        if off + clen + dlen > len(blob):
            break  # a last event cut short (the logger was killed): the whole ones count
        channel = blob[off:off + clen].decode("utf-8", "replace")
        events.append((utime, channel, blob[off + clen:off + clen + dlen]))
        off += clen + dlen
    if not events:
        raise LogError(f"{path}: not an LCM log (no events)")
    return events


def load_types(types_dir):
    """{channel: class} from the generated package qnav in types_dir."""
    if types_dir is None:
        here = os.path.dirname(os.path.abspath(__file__))
        types_dir = os.environ.get("QNAV_PYTHON_DIR") or os.path.join(here, "..", "python")
    if not os.path.isfile(os.path.join(types_dir, "qnav", "pose_t.py")):
        raise LogError(f"{types_dir}: no generated qnav LCM types there (see --types)")
    sys.path.insert(0, types_dir)
    return {ch: getattr(importlib.import_module("qnav." + t), t) for ch, t in CHANNELS.items()}


def decode(path, events, types):
    """{channel: [(log_utime, message)]} for the qnav channels; other channels are skipped."""
    out = {}
    for k, (utime, channel, data) in enumerate(events):
        base = next((t for t in TOKEN_CHANNELS if channel.startswith(t + "_")), channel)
        cls = types.get(base)
        if cls is None:
            continue
        try:
            msg = cls.decode(data)
        except (ValueError, struct.error) as e:
            raise LogError(f"{path}: event {k} on {channel}: not a {CHANNELS[base]} ({e})") from e
        out.setdefault(channel, []).append((utime, msg))
    if not out:
        raise LogError(f"{path}: no qnav channel in this log")
    return out


def cell(v):
    if isinstance(v, (list, tuple)):
        return " ".join(cell(x) for x in v)
    if isinstance(v, bool):
        return "1" if v else "0"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def write_csv(folder, decoded):
    """One CSV per channel, written whole or not at all (through a temporary file)."""
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as e:
        raise PlotError(f"{folder}: cannot create ({e.strerror})") from e
    written = []
    for channel, rows in sorted(decoded.items()):
        fields = list(type(rows[0][1]).__slots__)
        target = os.path.join(folder, channel.lower() + ".csv")
        lines = []

        class Sink:
            def write(self, s):
                lines.append(s)

        w = csv.writer(Sink(), lineterminator="\n")
        w.writerow(["log_utime"] + fields)
        for utime, msg in rows:
            w.writerow([utime] + [cell(getattr(msg, f)) for f in fields])
        plotcommon.write_text_atomic(target, "".join(lines))
        written.append(target)
    return written


def span(values, least_m=1.0, margin=0.08):
    """Axis limits around values: a margin on each side, and at least least_m wide so that
    a robot that hardly moved is not drawn at a microscopic scale."""
    lo, hi = min(values), max(values)
    half = max(hi - lo, least_m) * (0.5 + margin)
    mid = (lo + hi) / 2
    return mid - half, mid + half


def plot(out, decoded):
    plt = plotcommon.import_pyplot("qnav_log.py")  # one line, not a traceback, without matplotlib

    # The trajectory gets the left half at equal scale in x and y (a route is often long and
    # narrow: fitted into a third of a wide strip it became a sliver); the time series share
    # the right half.
    fig = plt.figure(figsize=(13, 6.5), dpi=110, layout="constrained")
    grid = fig.add_gridspec(2, 2, width_ratios=[1, 1.1])
    ax_xy = fig.add_subplot(grid[:, 0])
    ax_cmd = fig.add_subplot(grid[0, 1])
    ax_link = fig.add_subplot(grid[1, 1], sharex=ax_cmd)
    t0 = min(rows[0][0] for rows in decoded.values())
    poses = decoded.get("QNAV_POSE", [])
    if poses:
        xs = [m.x_m for _, m in poses]
        ys = [m.y_m for _, m in poses]
        ax_xy.plot(xs, ys, "-", lw=1.2, label="robot centre")
        ax_xy.plot(xs[0], ys[0], "go", label="start")
        ax_xy.plot(xs[-1], ys[-1], "r^" if poses[-1][1].reached else "rx",
                   label="reached" if poses[-1][1].reached else "end")
        ax_xy.legend(fontsize=8, loc="best")
        ax_xy.set_xlim(*span(xs))
        ax_xy.set_ylim(*span(ys))
        ax_xy.grid(alpha=0.3)
    else:
        ax_xy.text(0.5, 0.5, "no QNAV_POSE in this log", ha="center", transform=ax_xy.transAxes)
    # equal scale; the limits (not the box) grow to fill the panel
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.set(title="trajectory (world frame)", xlabel="x (m)", ylabel="y (m)")
    cmds = decoded.get("QNAV_COMMAND", [])
    if cmds:
        ts = [(u - t0) / 1e6 for u, _ in cmds]
        ax_cmd.plot(ts, [m.heading_deg for _, m in cmds], lw=1, label="heading (deg)")
        ax_sp = ax_cmd.twinx()
        ax_sp.plot(ts, [m.speed for _, m in cmds], "C1", lw=1, label="speed (fraction)")
        ax_sp.set_ylim(-0.05, 1.05)
        ax_sp.set_ylabel("speed (fraction of full)")
        stops = [t for t, (_, m) in zip(ts, cmds) if m.stop_reason != 0]
        if stops:
            ax_cmd.plot(stops, [0] * len(stops), "rx", label="stop")
        # one legend for both y axes, on the twin (drawn above the heading's axes)
        handles = ax_cmd.get_legend_handles_labels()[0] + ax_sp.get_legend_handles_labels()[0]
        ax_sp.legend(handles=handles, fontsize=7, loc="lower left", framealpha=0.9)
    ax_cmd.set(title="commands", xlabel="time (s)", ylabel="heading (deg)")
    status = decoded.get("QNAV_LINK_STATUS", [])
    if status:
        ts = [(u - t0) / 1e6 for u, _ in status]
        dropped = [m.drop_cobs + m.drop_short + m.drop_overflow + m.drop_crc + m.drop_unknown
                   + m.drop_length + m.drop_seq for _, m in status]
        ax_link.plot(ts, dropped, label="frames dropped (total)")
        ax_link.plot(ts, [max(m.last_heartbeat_age_ms, 0) for _, m in status],
                     label="heartbeat age (ms)")
        ax_link.legend(fontsize=7)
    ax_link.set(title="link status", xlabel="time (s)")
    plotcommon.save(fig, out)
    plt.close(fig)


def main(argv):
    parser = argparse.ArgumentParser(prog="qnav_log.py", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("log", metavar="LOG")
    parser.add_argument("--csv", metavar="DIR", help="write DIR/<channel>.csv")
    parser.add_argument("--plot", metavar="OUT", help="draw the trial into OUT (.png, .pdf, .svg)")
    parser.add_argument("--types", metavar="DIR", help="folder of the generated Python LCM types")
    parser.add_argument("--version", action="version", version=f"qnav_log.py (qnav) {plotcommon.version()}")
    args = parser.parse_args(argv[1:])
    if args.plot is not None and plotcommon.plot_format(args.plot) is None:
        parser.error(f"{args.plot}: unknown plot format (the name must end in .png, .pdf or .svg)")
    try:
        types = load_types(args.types)
        decoded = decode(args.log, read_events(args.log), types)
    except LogError as e:
        print(f"qnav_log.py: {e}", file=sys.stderr)
        return 2
    if args.csv:
        for path in write_csv(args.csv, decoded):
            print(path)
    if args.plot:
        plot(args.plot, decoded)
        print(args.plot)
    if not args.csv and not args.plot:
        for channel, rows in sorted(decoded.items()):
            print(f"{channel} {len(rows)}")
    return 0


if __name__ == "__main__":
    sys.exit(plotcommon.run(main, sys.argv, "qnav_log.py"))
