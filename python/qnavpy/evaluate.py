"""Score a batch of policies over the same episodes, in parallel: the call an outside
optimiser (an evolution strategy, CMA-ES, an RL library's evaluation) needs. Each policy
runs exactly as ``simevo eval`` runs it (same context, same episode seeds, the network
compiled into its quality table), so the figures equal simevo's for the same seed."""

import os

import numpy as np

from . import _lib
from ._lib import QnavError, call, encode, lib
from .core import Policy

__all__ = ["evaluate", "Evaluation"]


class Evaluation:
    """Per-episode figures of each policy: arrays of shape (policies, episodes).

    ``R`` (fitness, Eq. 1), ``reached`` (bool), ``tau_c`` (ticks in collision recovery),
    ``f1``, ``f2`` (Eq. 2-3). :meth:`mean_R` and :meth:`arrival` summarise per policy."""

    def __init__(self, R, reached, tau_c, f1, f2):
        self.R, self.reached, self.tau_c, self.f1, self.f2 = R, reached, tau_c, f1, f2

    def mean_R(self):
        """Mean R of each policy over its episodes."""
        return self.R.mean(axis=1)

    def arrival(self):
        """Share of each policy's episodes that reached the destination, in [0, 1]."""
        return self.reached.mean(axis=1)

    def __repr__(self):
        return f"Evaluation({self.R.shape[0]} policies x {self.R.shape[1]} episodes)"


def _as_policies(policies, inputs):
    """Policy objects (or the marker "prob") from what evaluate accepts."""
    if isinstance(policies, np.ndarray):
        if policies.ndim != 2:
            raise QnavError(f"policies: an array of weight vectors must have 2 dimensions, not {policies.ndim}")
        return [Policy.network(row, inputs=inputs) for row in policies]
    if isinstance(policies, (str, os.PathLike, Policy)):
        policies = [policies]
    out = []
    for p in policies:
        if isinstance(p, Policy):
            out.append(p)
        elif isinstance(p, str) and p == "prob":
            out.append("prob")
        elif isinstance(p, (str, os.PathLike)):
            out.append(Policy.read(p))
        else:
            out.append(Policy.network(p, inputs=inputs))
    return out


def evaluate(policies, episodes=50, *, world="dense", robot="tekbot", sectors=0, noise=0.0, seed=1,
             fitness="progress", jobs=0, inputs=2):
    """Score every policy over the same ``episodes`` episodes and return an :class:`Evaluation`.

    ``policies``: a sequence of :class:`Policy` objects, policy files, ``"prob"`` (the
    robot's tuned probabilistic policy) or real-valued weight vectors (networks with
    ``inputs`` inputs, rounded to Q8.8); or a 2-D array with one weight vector per row.
    The rest are ``simevo eval``'s options with its defaults: ``world`` (--env), ``robot``,
    ``sectors`` (0: the robot's default), ``noise`` (sensor and actuation p), ``seed``
    (the context seed; episode i has seed mix_seed(seed, i)), ``fitness``. ``jobs``: worker
    threads (0: every core); results do not depend on it.

    Raises QnavError with simevo's line for a bad world, robot, policy or option."""
    pols = _as_policies(policies, inputs)
    # the checks simevo's command line makes, with its words
    if not (isinstance(episodes, (int, np.integer)) and 1 <= episodes <= 1000000):
        raise QnavError(f"--episodes: Value {episodes} not in range 1 to 1000000")
    if not (isinstance(sectors, (int, np.integer)) and 0 <= sectors <= 360):
        raise QnavError(f"--sectors: Value {sectors} not in range 0 to 360")
    if not (isinstance(noise, (int, float, np.floating)) and 0.0 <= noise <= 1.0):
        raise QnavError(f"--noise: expected a number in [0, 1], got '{noise}'")
    n = len(pols)
    kind = np.zeros(n, dtype=np.int32)
    hidden = np.zeros(n, dtype=np.int32)
    inp = np.zeros(n, dtype=np.int32)
    w = np.zeros((n, _lib.MAX_WEIGHTS), dtype=np.int16)
    for i, p in enumerate(pols):
        if p == "prob":
            kind[i] = _lib.KIND_ROBOT_PROB
            continue
        kind[i], hidden[i], inp[i] = p._kind_code, p.hidden, p.inputs
        w[i, :len(p.raw)] = p.raw
    shape = (n, episodes)
    R, f1, f2 = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    reached = np.zeros(shape, dtype=np.uint8)
    tau_c = np.zeros(shape, dtype=np.uint32)
    if n == 0:
        return Evaluation(R, reached.astype(bool), tau_c, f1, f2)
    call(lib.qpy_evaluate, encode(robot), encode(world), int(sectors), float(noise), int(seed), encode(fitness), n,
         kind.ctypes.data, hidden.ctypes.data, inp.ctypes.data, w.ctypes.data, episodes, int(jobs), R.ctypes.data,
         reached.ctypes.data, tau_c.ctypes.data, f1.ctypes.data, f2.ctypes.data)
    return Evaluation(R, reached.astype(bool), tau_c, f1, f2)
