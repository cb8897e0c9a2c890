"""What tools/family-eval and tools/gap-sweep share: running qnav-sim with its failure as
one line, and the interval they report arrival with. Standard library only."""
import math
import subprocess


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

