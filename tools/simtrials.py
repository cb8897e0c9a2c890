"""What tools/family-eval and tools/gap-sweep share: running qnav-sim with its failure as
one line, the interval they report arrival with, and a copy of a robot profile with --set
values. Standard library only."""
import math
import os
import re
import subprocess
import sys
import tempfile
import tomllib


def interval(lo, hi, width=13):
    """A 95 % interval as the tables print it, "[9.7, 23.1]" right-aligned in width: always two
    whitespace-separated fields, so that a script can take the table's columns by number."""
    return f"[{lo:.1f}, {hi:.1f}]".rjust(width)


def wilson(k, n, z=1.96):
    """95% Wilson score interval of k successes in n, as percentages."""
    if n == 0:
        return 0.0, 0.0
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return 100 * max(0.0, c - h), 100 * min(1.0, c + h)


def run(cmd):
    """cmd's stdout and stderr; RuntimeError with its last line when it fails."""
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        last = (r.stderr.strip() or r.stdout.strip()).splitlines()
        raise RuntimeError(f"{' '.join(cmd[:3])} ...: {last[-1] if last else 'exit %d' % r.returncode}")
    return r.stdout + r.stderr


def named_profile(name):
    """data/robots/NAME.toml (QNAV_DATA_DIR's data, else the source tree's)."""
    data = os.environ.get("QNAV_DATA_DIR",
                          os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data"))
    return os.path.join(data, "robots", name + ".toml")


def profile_file(prog, robot):
    """The profile file --robot names: itself, or data/robots/NAME.toml."""
    if os.path.isfile(robot):
        return robot
    if not re.fullmatch(r"[A-Za-z0-9_]+", robot):
        sys.exit(f"{prog}: --set edits a profile: name one in data/robots or a file "
                 f"({robot!r} is neither; for the map, --set map.on=false)")
    path = named_profile(robot)
    if not os.path.isfile(path):
        sys.exit(f"{prog}: {robot}: no such robot profile in data/robots")
    return os.path.normpath(path)


# Keys that say one thing two ways (a profile gives one): setting either drops the other.
ONE_OF = {("clearance", "wedge_pct"): "wedge_deg", ("clearance", "wedge_deg"): "wedge_pct"}


def set_value(lines, edit):
    """lines with one --set SECTION.KEY=VALUE applied: the key's value replaced (its comment
    kept), or the key added at the top of its section, after the header's comment; a key
    ONE_OF pairs with it is dropped. ValueError says what is wrong."""
    m = re.fullmatch(r"([A-Za-z0-9_]+)\.([A-Za-z0-9_]+)=(.+)", edit)
    if not m:
        raise ValueError(f"--set {edit}: expected SECTION.KEY=VALUE, e.g. map.cell_m=0.3")
    section, key, value = m.groups()
    head = next((i for i, l in enumerate(lines) if re.match(rf"\[{section}\]\s*(#.*)?$", l)), None)
    if head is None:
        raise ValueError(f"--set {edit}: the profile has no [{section}] section")
    end = next((i for i in range(head + 1, len(lines)) if lines[i].startswith("[")), len(lines))
    other = ONE_OF.get((section, key))
    at = next((i for i in range(head + 1, end) if other and re.match(rf"{other}\s*=", lines[i])), None)
    if at is not None:
        # the other way of saying it, and its comment's further lines, give way
        j = at + 1
        while j < end and re.match(r"\s+#", lines[j]):
            j += 1
        return lines[:at] + [f"{key} = {value}"] + lines[j:]
    for i in range(head + 1, end):
        k = re.match(rf"({key}\s*=\s*)(.*?)(\s+#.*)?$", lines[i])
        if k:
            lines[i] = k.group(1) + value + (k.group(3) or "")
            return lines
    at = head + 1
    while at < end and re.match(r"\s*#", lines[at]):  # the header's own comment goes on
        at += 1
    return lines[:at] + [f"{key} = {value}"] + lines[at:]


def edited_profile(prog, robot, edits):
    """A copy of the profile --robot names with every --set SECTION.KEY=VALUE applied, in a
    new temporary directory that is kept (the commands a tool prints may name it); its path.
    A bad edit: one line naming it, exit status 1."""
    src = profile_file(prog, robot)
    with open(src, encoding="utf-8") as f:
        lines = f.read().splitlines()
    for e in edits:
        try:
            lines = set_value(lines, e)
            tomllib.loads("\n".join(lines))
        except tomllib.TOMLDecodeError as err:
            key, _, value = e.partition("=")
            hint = ""
            if value and value.replace("_", "").replace("-", "").isalpha() and value not in ("true", "false"):
                hint = f"; a string takes quotes: --set '{key}=\"{value}\"'"
            sys.exit(f"{prog}: {src}: --set {e}: the value is not TOML ({err}){hint}")
        except ValueError as err:
            sys.exit(f"{prog}: {src}: {err}")
    out = os.path.join(tempfile.mkdtemp(prefix=f"{prog}-set-"), os.path.basename(src))
    with open(out, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    return out
