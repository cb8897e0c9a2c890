"""Robots, worlds, policies and libqnav's controllers from Python.

Units follow the C side: ranges in millimetres and angles in 0.01 degrees in a
controller's input (as ``qnav_ctrl_input_t``), policy weights in Q8.8 (``raw``, integers)
or as real numbers (``weights`` = raw / 256)."""

import collections
import ctypes

import numpy as np

from . import _lib
from ._lib import QnavError, call, encode, lib

__all__ = ["Robot", "World", "Policy", "Controller", "Decision", "world_families",
           "controller_names"]


def world_families():
    """The generated world families, for ``gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]]`` specs
    (docs/sim.md, "World families")."""
    return [f.strip() for f in lib.qpy_world_families().decode().split(",")]


def controller_names():
    """The controllers of libqnav's table (qnav/nav.h), in its order, e.g. ``body``."""
    return [f.strip() for f in lib.qpy_controller_names().decode().split(",")]


class Robot:
    """A robot profile: a name in data/robots (``"tekbot"``, ``"pioneer3dx"``) or a TOML
    file. Attributes are the profile's figures (SI units, as qnav_sim_robot_info_t)."""

    _FIELDS = ("radius_m", "v_max_mps", "accel_mps2", "decel_mps2", "turn_rate_max_dps",
               "range_min_m", "range_max_m", "default_sectors", "sonar_offset_m", "wheel_base_m",
               "sensor_noise", "actuation_noise")

    def __init__(self, spec="tekbot"):
        self.spec = str(spec)
        info = np.zeros(len(self._FIELDS))
        name = ctypes.create_string_buffer(256)
        prob = np.zeros(2, dtype=np.int16)
        call(lib.qpy_robot_info, encode(self.spec), info.ctypes.data, name, 256, prob.ctypes.data)
        self.name = name.value.decode()
        for field, value in zip(self._FIELDS, info):
            setattr(self, field, float(value))
        self.default_sectors = int(self.default_sectors)
        self._prob = prob

    def probabilistic_policy(self):
        """The probabilistic policy hand-tuned for this robot: its profile's k_goal, and k_safe
        (given, or range_max_m / safe_m and at least 4)."""
        return Policy("prob", self._prob.copy())

    def __repr__(self):
        return f"Robot({self.spec!r}: {self.name}, radius {self.radius_m} m, v_max {self.v_max_mps} m/s)"


class World:
    """An environment: a name in data/envs (``"dense"``), a TOML file, or a generated world
    ``"gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]]"`` (docs/sim.md). Attributes: ``name`` (a
    generated world's spec with every field spelled out), ``width_m``, ``height_m``,
    ``dest`` (x, y, m), ``dest_radius_m``, ``episode_limit_s``, ``n_obstacles``,
    ``n_start_zones``."""

    def __init__(self, spec="dense"):
        self.spec = str(spec)
        info = np.zeros(9)
        name = ctypes.create_string_buffer(512)
        call(lib.qpy_world_info, encode(self.spec), info.ctypes.data, name, 512)
        self.name = name.value.decode()
        (self.width_m, self.height_m, dx, dy, self.dest_radius_m, self.episode_limit_s,
         n_obst, n_zones, _) = (float(v) for v in info)
        self.dest = (dx, dy)
        self.n_obstacles, self.n_start_zones = int(n_obst), int(n_zones)

    @classmethod
    def generated(cls, family, seed, difficulty=None, robot=None):
        """The generated world of ``family`` (one of :func:`world_families`) with this seed,
        difficulty in [0, 1] (default 0.5) made passable for ``robot`` (default tekbot):
        ``World("gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]]")``. The same arguments give the same world."""
        spec = f"gen:{family}:{seed}"
        if difficulty is not None or robot is not None:
            spec += f":{0.5 if difficulty is None else difficulty}"
        if robot is not None:
            spec += f":{getattr(robot, 'spec', robot)}"
        return cls(spec)

    def __repr__(self):
        return f"World({self.name!r}, {self.width_m} x {self.height_m} m, {self.n_obstacles} obstacles)"


def _q8_8(values):
    """Real numbers to Q8.8 as evolution does: round half away from zero, saturate."""
    x = np.asarray(values, dtype=np.float64) * 256.0
    if not np.all(np.isfinite(x)):
        raise QnavError("policy: weights must be finite numbers")
    r = np.sign(x) * np.floor(np.abs(x) + 0.5)
    return np.clip(r, -32768, 32767).astype(np.int16)


# The policy kinds, one row each: the name qnavpy spells and libqnav's code for it
# (qnav_policy_kind_t through qnavpy_capi.h). A new kind is a row here.
_KIND_CODES = {"prob": _lib.KIND_PROB, "net": _lib.KIND_NET}


class Policy:
    """A navigation policy as libqnav holds it.

    ``kind`` is ``"prob"`` (``raw`` = [k_goal, k_safe], Q8.8) or ``"net"`` (``raw`` = the
    network's Q8.8 weights in the policy files' flat order: for each hidden unit
    w_theta, w_dist, [w_prev,] b_hidden, w_out; then b_out). Make one with
    :meth:`network`, :meth:`probabilistic`, :meth:`read` or ``Robot(...).probabilistic_policy()``.
    """

    def __init__(self, kind, raw, hidden=0, inputs=2):
        if kind not in _KIND_CODES:
            raise QnavError(f"policy: kind '{kind}' is not " + " or ".join(f"'{k}'" for k in _KIND_CODES))
        self.kind = kind
        self.raw = np.array(raw, dtype=np.int16).reshape(-1)
        self.hidden = int(hidden) if kind == "net" else 0
        self.inputs = int(inputs) if kind == "net" else 0
        call(lib.qpy_policy_check, self._kind_code, self.hidden, self.inputs, self.raw.ctypes.data,
             len(self.raw))

    @property
    def _kind_code(self):
        return _KIND_CODES[self.kind]

    @property
    def weights(self):
        """The weights (or k_goal, k_safe) as real numbers: raw / 256."""
        return self.raw.astype(np.float64) / 256.0

    @classmethod
    def network(cls, weights, inputs=2):
        """A network from real-valued weights in the flat order (rounded to Q8.8 half away
        from zero and saturated, as evolution does); the hidden units follow from the
        count, (inputs + 2) * hidden + 1."""
        w = np.asarray(weights, dtype=np.float64).reshape(-1)
        hidden, rest = divmod(len(w) - 1, int(inputs) + 2)
        if rest or hidden < 1:
            raise QnavError(f"policy: {len(w)} weights are not (inputs + 2) * hidden + 1 "
                            f"for {inputs} inputs")
        return cls("net", _q8_8(w), hidden=hidden, inputs=inputs)

    @classmethod
    def probabilistic(cls, k_goal=1.0, k_safe=4.0):
        """The probabilistic policy X = P_goal * P_safe with these parameters (Q8.8, (0, 64])."""
        return cls("prob", _q8_8([k_goal, k_safe]))

    @classmethod
    def read(cls, path):
        """A policy file (docs/policy-format.md). QnavError with simevo's line for a missing
        or bad file ("FILE:LINE: problem")."""
        kind, hidden, inputs, nw = (np.zeros(1, dtype=np.int32) for _ in range(4))
        w = np.zeros(_lib.MAX_WEIGHTS, dtype=np.int16)
        call(lib.qpy_policy_read, encode(path), kind.ctypes.data, hidden.ctypes.data, inputs.ctypes.data,
             w.ctypes.data, nw.ctypes.data)
        names = [name for name, code in _KIND_CODES.items() if code == kind[0]]
        if not names:
            raise QnavError(f"{path}: policy kind {int(kind[0])} unknown to qnavpy")
        return cls(names[0], w[:nw[0]], int(hidden[0]), int(inputs[0]))

    def write(self, path, comment=None):
        """Write the policy file at path (the format simevo writes)."""
        call(lib.qpy_policy_write, encode(path), self._kind_code, self.hidden, self.inputs, self.raw.ctypes.data,
             len(self.raw), encode(comment))

    def __eq__(self, other):
        return (isinstance(other, Policy) and self.kind == other.kind and self.hidden == other.hidden
                and self.inputs == other.inputs and np.array_equal(self.raw, other.raw))

    def __repr__(self):
        if self.kind == "prob":
            return f"Policy('prob', k_goal={self.weights[0]}, k_safe={self.weights[1]})"
        return f"Policy('net', hidden={self.hidden}, inputs={self.inputs}, {len(self.raw)} weights)"


class Decision(collections.namedtuple("Decision", "heading_deg speed_q15 quality_q15 flags qualities")):
    """One controller step's output (qnav_ctrl_output_t): the chosen path (robot frame,
    degrees, -179..180), the speed and quality in Q1.15, the QNAV_FLAG_* bits, and the 360
    path qualities (Q1.15, path i at i degrees) when asked for."""

    @property
    def speed(self):
        """Speed as a fraction of the robot's maximum."""
        return self.speed_q15 / 32768.0

    @property
    def quality(self):
        return self.quality_q15 / 32768.0


class Controller:
    """A controller of libqnav's table (qnav/nav.h) with its memory between ticks.

    ``controller``: ``"body"`` (the path-quality controller with the robot's clearance),
    ``"literal"`` (the paper read literally) or ``"vfh"`` (VFH+, no policy). ``policy``: a
    :class:`Policy`, a policy file, or None (the robot's tuned probabilistic policy; libqnav's
    default without a robot). Sensors: those of ``env`` (an :class:`~qnavpy.Env`), else of
    ``robot`` at ``sectors`` (0: the robot's default), else libqnav's defaults with
    ``sectors`` and ``max_range_mm``. ``table=True`` compiles the policy into a quality
    table first (the firmware's table mode; the same decisions).

    :meth:`step` is ``qnav_nav_step`` itself, bit for bit: the escape memory (and VFH+'s
    histogram) carries over from one call to the next until :meth:`reset`.
    """

    def __init__(self, policy=None, controller="body", *, env=None, robot=None, sectors=0, max_range_mm=0,
                 table=False):
        if policy is not None and not isinstance(policy, Policy):
            policy = Policy.read(policy)
        kind = _lib.KIND_ROBOT_PROB if policy is None else policy._kind_code
        raw = np.zeros(_lib.MAX_WEIGHTS, dtype=np.int16) if policy is None else policy.raw
        robot_spec = None if robot is None else str(getattr(robot, "spec", robot))
        handle = ctypes.c_void_p()
        call(lib.qpy_ctrl_create, encode(controller), None if env is None else env._handle, encode(robot_spec),
             int(sectors), int(max_range_mm), kind, 0 if policy is None else policy.hidden,
             0 if policy is None else policy.inputs, raw.ctypes.data, len(raw) if policy is not None else 0,
             1 if table else 0, ctypes.byref(handle))
        self._handle = handle
        self.name = controller
        self.policy = policy
        n, r = np.zeros(1, dtype=np.int32), np.zeros(1, dtype=np.int32)
        lib.qpy_ctrl_sensors(handle, n.ctypes.data, r.ctypes.data)
        self.n_sectors, self.max_range_mm = int(n[0]), int(r[0])
        self._out = np.zeros(4, dtype=np.int32)
        self._err = _lib.ErrorBuffer()

    def __del__(self):
        if getattr(self, "_handle", None):
            lib.qpy_ctrl_free(self._handle)
            self._handle = None

    def reset(self):
        """Forget the memory kept between ticks (start of an episode)."""
        lib.qpy_ctrl_reset(self._handle)

    def step(self, ranges_mm, goal_bearing_cdeg, prev_heading_cdeg=0, goal_range_mm=0, qualities=False, *,
             escape_clear=0, escape_grow_mm=0):
        """One control tick on a scan: ``ranges_mm`` (n_sectors readings, mm, sector k
        centred k*360/N degrees counter-clockwise of straight ahead), the destination's
        bearing and the previous tick's heading in 0.01 degrees (robot frame, CCW), the
        destination's distance in mm (0: unknown, no escape). ``escape_clear`` (1: forget the
        escape memory first) and ``escape_grow_mm`` (grow its distances by this much) carry a
        map's verdicts (an :class:`~qnavpy.Env` observation's). Returns a :class:`Decision`;
        with ``qualities=True`` also the 360 path qualities (path-quality controllers)."""
        r = np.ascontiguousarray(ranges_mm, dtype=np.uint16)
        q = np.zeros(360, dtype=np.int16) if qualities else None
        self._err.check(lib.qpy_ctrl_step(self._handle, r.ctypes.data, len(r), int(goal_bearing_cdeg),
                                          int(prev_heading_cdeg), int(goal_range_mm), int(escape_clear),
                                          int(escape_grow_mm), self._out.ctypes.data,
                                          None if q is None else q.ctypes.data, self._err.buf, _lib.ERRLEN))
        o = self._out
        return Decision(int(o[0]), int(o[1]), int(o[2]), int(o[3]), q)

    def decide(self, observation, qualities=False):
        """:meth:`step` on an :class:`~qnavpy.Env` observation."""
        return self.step(observation["ranges_mm"], observation["goal_bearing_cdeg"],
                         observation["prev_heading_cdeg"], observation["goal_range_mm"], qualities,
                         escape_clear=observation.get("escape_clear", 0),
                         escape_grow_mm=observation.get("escape_grow_mm", 0))

    def grid(self):
        """What the path-quality controller ranks by and what it drives with, over its
        inputs: (keys, qualities, rank) with keys and qualities 32 distance levels x 181
        dtheta (degrees) arrays. rank is "preact" when keys are the network output's
        pre-activation (Q5.11 below |z| = 8, docs/qformats.md) or "quality" when they are
        the Q1.15 quality itself."""
        keys = np.zeros((_lib.LEVELS, _lib.DTHETA), dtype=np.int16)
        qual = np.zeros((_lib.LEVELS, _lib.DTHETA), dtype=np.int16)
        rank = np.zeros(1, dtype=np.int32)
        call(lib.qpy_ctrl_grid, self._handle, keys.ctypes.data, qual.ctypes.data, rank.ctypes.data)
        return keys, qual, ("preact" if rank[0] == 1 else "quality")

    def __repr__(self):
        return f"Controller({self.name!r}, {self.policy!r}, {self.n_sectors} sectors, {self.max_range_mm} mm)"
