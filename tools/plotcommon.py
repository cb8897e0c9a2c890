"""What qnav's Python tools share (the plot scripts, qnav_log.py): their command line
(argparse), the version, reading a CSV or JSON file with one-line errors (FILE:LINE:
problem), reading an environment's TOML file, and writing a plot (in the format its file
name asks for: .png, .pdf, .svg) or a text file atomically through an exclusively created
temporary file."""
import argparse
import csv
import json
import os
import sys
import tempfile

FORMATS = ("png", "pdf", "svg")


class PlotError(Exception):
    """A problem with an input file; str() is the one-line message."""


def import_pyplot(prog):
    """matplotlib.pyplot on the Agg backend. When the python3 running the script cannot
    import matplotlib (a virtualenv or pyenv python3 first on PATH), one line naming that
    interpreter and exit status 1, not a traceback."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        sys.stderr.write(f"{prog}: {sys.executable} cannot import {e.name or 'matplotlib'} "
                         "(install python3-matplotlib, or run the script with /usr/bin/python3)\n")
        sys.exit(1)
    return plt


def plot_format(path):
    """The plot format that path's extension asks for ('png', 'pdf', 'svg'), or None."""
    ext = os.path.splitext(path)[1].lower().lstrip(".")
    return ext if ext in FORMATS else None


def parse_args(argv, prog, default_png):
    """EXPERIMENT_DIR [OUT] -> (exp_dir, out). --help prints the calling script's docstring
    and exits 0; bad usage (an OUT whose extension is not .png, .pdf or .svg included)
    prints one line and exits 2."""
    main_doc = getattr(sys.modules.get("__main__"), "__doc__", None)
    parser = argparse.ArgumentParser(prog=prog, description=main_doc,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("experiment_dir", metavar="EXPERIMENT_DIR")
    parser.add_argument("out", metavar="OUT", nargs="?",
                        help=f"plot file, .png, .pdf or .svg (default EXPERIMENT_DIR/{default_png})")
    parser.add_argument("--version", action="version", version=f"{prog} (qnav) {version()}")
    args = parser.parse_args(argv[1:])
    out = args.out if args.out is not None else os.path.join(args.experiment_dir, default_png)
    if plot_format(out) is None:
        parser.error(f"{out}: unknown plot format (the name must end in .png, .pdf or .svg)")
    return args.experiment_dir, out


def version():
    """qnav's version: the VERSION file beside tools/ (source tree) or share/qnav/ (installed)."""
    here = os.path.dirname(os.path.abspath(__file__))
    for cand in (os.path.join(here, "..", "VERSION"), os.path.join(here, "VERSION")):
        try:
            with open(cand) as f:
                return f.read().strip()
        except OSError:
            continue
    return "unknown"


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


def _read(path, mode, parse, decode_error, where):
    """parse(file) of path opened in mode; PlotError naming the file (where(e): ':LINE')."""
    try:
        with open(path, mode) as f:
            return parse(f)
    except OSError as e:
        raise PlotError(f"{path}: {e.strerror}") from e
    except decode_error as e:
        raise PlotError(f"{path}{where(e)}") from e


def read_json(path):
    """The parsed JSON file at path; raise PlotError naming the file and line."""
    return _read(path, "r", json.load, json.JSONDecodeError, lambda e: f":{e.lineno}: {e.msg}")


def read_toml(path):
    """The parsed TOML file at path (an environment); raise PlotError naming the file."""
    import tomllib  # Python 3.11+; imported here so that the other tools run on older ones

    return _read(path, "rb", tomllib.load, tomllib.TOMLDecodeError, lambda e: f": {e}")


def _replace_atomically(out, write):
    """Call write(binary file) on a temporary file created exclusively (random name,
    O_EXCL) in out's folder, then rename it over out: out is whole or absent, a planted
    symlink is never followed and a leftover process never shares the temporary."""
    folder = os.path.dirname(out) or "."
    try:
        fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(out) + ".", suffix=".tmp", dir=folder)
    except OSError as e:
        raise PlotError(f"{out}: cannot write ({e.strerror})") from e
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.chmod(tmp, 0o644)
        os.replace(tmp, out)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def save(fig, out):
    """Write fig to out in the format out's name asks for (.png, .pdf, .svg), atomically."""
    fmt = plot_format(out)
    if fmt is None:
        raise PlotError(f"{out}: unknown plot format (the name must end in .png, .pdf or .svg)")
    _replace_atomically(out, lambda f: fig.savefig(f, format=fmt))


def write_text_atomic(path, text):
    """Write text (UTF-8) to path atomically, like save()."""
    _replace_atomically(path, lambda f: f.write(text.encode("utf-8")))


def run(main, argv, prog):
    """Run main(argv); a PlotError becomes one line on stderr and exit status 1."""
    try:
        return main(argv)
    except PlotError as e:
        print(f"{prog}: {e}", file=sys.stderr)
        return 1
