"""What simevo's plot scripts share: their command line, reading a CSV or JSON file with
one-line errors (FILE:LINE: problem), and writing a PNG atomically (no half-written plot)."""
import csv
import json
import os
import sys


class PlotError(Exception):
    """A problem with an input file; str() is the one-line message."""


def parse_args(argv, prog, default_png):
    """EXPERIMENT_DIR [OUT.png] -> (exp_dir, out_png); None after printing usage."""
    if len(argv) not in (2, 3):
        print(f"usage: {prog} EXPERIMENT_DIR [OUT.png]", file=sys.stderr)
        return None
    exp = argv[1]
    return exp, argv[2] if len(argv) == 3 else os.path.join(exp, default_png)


def read_csv(path, on_row):
    """Call on_row(dict) for every data row of path; raise PlotError naming the line."""
    reader = None
    try:
        with open(path) as f:
            reader = csv.DictReader(f)
            for row in reader:
                on_row(row)
    except OSError as e:
        raise PlotError(f"{path}: {e.strerror}") from e
    except KeyError as e:
        raise PlotError(f"{path}:1: missing column {e}") from e
    except (ValueError, TypeError) as e:
        raise PlotError(f"{path}:{reader.line_num if reader else 0}: {e}") from e


def read_json(path):
    """The parsed JSON file at path; raise PlotError naming the file (and line)."""
    try:
        with open(path) as f:
            return json.load(f)
    except OSError as e:
        raise PlotError(f"{path}: {e.strerror}") from e
    except json.JSONDecodeError as e:
        raise PlotError(f"{path}:{e.lineno}: {e.msg}") from e


def save(fig, out):
    """Write fig to out through a temporary file, so out is whole or absent."""
    tmp = out + ".tmp.png"
    fig.savefig(tmp)
    os.replace(tmp, out)


def run(main, argv, prog):
    """Run main(argv); a PlotError becomes one line on stderr and exit status 1."""
    try:
        return main(argv)
    except PlotError as e:
        print(f"{prog}: {e}", file=sys.stderr)
        return 1
