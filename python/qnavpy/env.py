"""The simulator as an environment with Gymnasium's calling convention (without depending
on Gymnasium): ``reset(seed=...) -> (observation, info)`` and
``step(action) -> (observation, reward, terminated, truncated, info)``."""

import ctypes

import numpy as np

from . import _lib
from ._lib import encode, lib
from .core import Controller, Robot, World

__all__ = ["Env", "Episode"]

_TRACE_DTYPE = np.dtype([("tick", np.uint32), ("x_m", np.float64), ("y_m", np.float64),
                         ("heading_rad", np.float64), ("speed_mps", np.float64), ("cmd_heading_deg", np.int32),
                         ("cmd_speed", np.float64), ("recovering", np.bool_), ("collided", np.bool_)])
_RESULT_FIELDS = ("R", "f1", "f2", "tau_c", "reached", "ticks", "collisions", "l", "beta_l", "tau_l", "beta_tau",
                  "d_start_m", "d_end_m", "start_x_m", "start_y_m", "start_heading_rad")


def _result_dict(values):
    d = dict(zip(_RESULT_FIELDS, (float(v) for v in values)))
    for k in ("tau_c", "ticks", "collisions"):
        d[k] = int(d[k])
    d["reached"] = bool(d["reached"])
    return d


class Episode:
    """A whole episode run in C (:meth:`Env.run_episode`): ``result`` (the figures
    ``qnav-sim run`` prints: R, f1, f2, tau_c, reached, ticks, collisions, l, beta_l, ...)
    and ``trajectory``, one row per tick from tick 0 (a numpy structured array with the
    columns of ``qnav-sim run --trace``: tick, x_m, y_m, heading_rad, speed_mps,
    cmd_heading_deg, cmd_speed, recovering, collided)."""

    def __init__(self, result, trajectory):
        self.result = result
        self.trajectory = trajectory

    def __repr__(self):
        r = self.result
        return (f"Episode({'reached' if r['reached'] else 'not reached'} in {r['ticks']} ticks, "
                f"R {r['R']:.3f}, tau_c {r['tau_c']})")


class Env:
    """One simulation context, as ``qnav-sim run`` makes it.

    ``world``: an environment name, TOML file or ``gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]]``;
    ``robot``: a profile name or file; ``sectors``: sonar sectors (0: the robot's default);
    ``sensor_noise``/``actuation_noise``: p in [0, 1] (None: the profile's typical, as
    qnav-sim); ``seed``: the context seed; ``episode_limit_s`` (0: the world's);
    ``fitness``: "progress" or "paper"; ``map_frame_deg``: a profile's map's grid against the
    world's walls, deg in [0, 360) (None: drawn per episode, as ``qnav-sim run --map-frame``'s
    default; docs/sim.md, "The map's grid"); ``survey_m``: a profile's map starts each episode
    with what the sonar shows from every point of a grid this many metres apart (0: not, the
    default; ``qnav-sim run --survey``; docs/sim.md, "A known world").
    ``controller``/``policy``/``table``: the controller
    that decides when :meth:`step` is given no action (default: the robot's tuned
    probabilistic policy on the "body" controller).

    Observation (a dict, fresh arrays every tick): ``ranges_mm`` (n_sectors int32, the sonar
    scan as the controller reads it), ``goal_bearing_cdeg`` and ``prev_heading_cdeg`` (robot
    frame, 0.01 deg, CCW), ``goal_range_mm``, ``escape_clear`` and ``escape_grow_mm`` (what a
    profile's map did to the escape memory a controller carries: cleared, or grown by this
    many mm; 0 without a map), and ``pose`` (x_m, y_m, heading_rad; world frame, the true
    pose). Reward: 0 on every tick but the last, which gets the episode's
    fitness R (Eq. 1-3), so an episode's rewards sum to R. ``terminated``: the destination
    was reached; ``truncated``: the time limit ran out.
    """

    metadata = {"render_modes": []}

    def __init__(self, world="dense", robot="pioneer3dx", *, sectors=0, sensor_noise=None, actuation_noise=None,
                 seed=1, episode_limit_s=0.0, fitness="progress", controller="body", policy=None, table=False,
                 map_frame_deg=None, survey_m=0.0):
        handle = ctypes.c_void_p()
        _lib.call(lib.qpy_env_create, encode(robot), encode(world), int(sectors),
                  -1.0 if sensor_noise is None else float(sensor_noise),
                  -1.0 if actuation_noise is None else float(actuation_noise), int(seed), float(episode_limit_s),
                  encode(fitness), -1.0 if map_frame_deg is None else float(map_frame_deg), float(survey_m),
                  ctypes.byref(handle))
        self._handle = handle
        self.world = World(world)
        self.robot = Robot(robot)
        params = np.zeros(5)
        lib.qpy_env_params(handle, params.ctypes.data)
        self.n_sectors, self.max_range_mm, self.limit_ticks = (int(v) for v in params[:3])
        self.sensor_noise, self.actuation_noise = float(params[3]), float(params[4])
        self.seed = int(seed)
        self.controller = Controller(policy, controller, env=self, table=table)
        n = self.n_sectors
        self._obs_i = np.zeros(n + _lib.OBS_INT_EXTRA, dtype=np.int32)
        self._obs_f = np.zeros(_lib.OBS_FLOAT)
        self._info = np.zeros(_lib.INFO)
        self._addr = (self._obs_i.ctypes.data, self._obs_f.ctypes.data, self._info.ctypes.data)
        self._err = _lib.ErrorBuffer()
        self._next_episode = 0
        self._step = lib.qpy_env_step

    def __del__(self):
        if getattr(self, "_handle", None):
            lib.qpy_env_free(self._handle)
            self._handle = None

    def _observation(self):
        oi, of, n = self._obs_i, self._obs_f, self.n_sectors
        return {"ranges_mm": oi[:n].copy(), "goal_bearing_cdeg": int(oi[n]), "prev_heading_cdeg": int(oi[n + 1]),
                "goal_range_mm": int(oi[n + 2]), "escape_clear": int(oi[n + 3]), "escape_grow_mm": int(oi[n + 4]),
                "pose": of[:3].copy()}

    def _info_dict(self):
        i = self._info
        return {"tick": int(i[0]), "reached": bool(i[2]), "recovering": bool(i[3]), "collisions": int(i[4]),
                "collided": bool(i[5]), "cmd_heading_deg": float(i[6]), "cmd_speed": float(i[7]),
                "flags": int(i[8]), "speed_mps": float(self._obs_f[3]),
                "goal_distance_m": float(self._obs_f[4])}

    def reset(self, seed=None, options=None):
        """Start an episode with episode seed ``seed`` (None: 0, 1, 2, ... in turn, as
        ``qnav-sim run --episodes``). The start point and every noise sample depend only on
        (context seed, episode seed). The env's controller forgets its memory."""
        if seed is None:
            seed = self._next_episode
        self._next_episode = int(seed) + 1
        self._err.check(lib.qpy_env_reset(self._handle, int(seed), self.controller._handle, *self._addr,
                                          self._err.buf, _lib.ERRLEN))
        return self._observation(), self._info_dict()

    def step(self, action=None):
        """Advance one 0.1 s control tick.

        ``action``: None (the env's controller decides from this tick's scan, exactly as
        in ``qnav-sim run``), a :class:`Controller` (that one decides; it must have been
        made for this env's sensors), or (heading_deg, speed): a heading in the robot frame
        (degrees, CCW) and a speed as a fraction of v_max in [0, 1]."""
        if action is None:
            ctrl, heading, speed = self.controller._handle, 0.0, 0.0
        elif isinstance(action, Controller):
            ctrl, heading, speed = action._handle, 0.0, 0.0
        else:
            heading, speed = action
            ctrl = None
        self._err.check(self._step(self._handle, ctrl, float(heading), float(speed), *self._addr, self._err.buf,
                                   _lib.ERRLEN))
        i = self._info
        done = i[1] != 0.0
        reached = i[2] != 0.0
        info = self._info_dict()
        reward = 0.0
        if done:
            reward = float(i[9])
            info["result"] = self.result()
        return self._observation(), reward, reached, done and not reached, info

    def result(self):
        """The episode's figures so far (final once it is over), as a dict."""
        res = np.zeros(_lib.RESULT)
        _lib.call(lib.qpy_env_result, self._handle, res.ctypes.data)
        return _result_dict(res)

    def run_episode(self, seed=None, controller=None):
        """A whole episode in C (qnav_sim_run_episode_nav, as ``qnav-sim run``) with the env's
        controller or ``controller``; returns an :class:`Episode` with its trajectory."""
        if seed is None:
            seed = self._next_episode
        self._next_episode = int(seed) + 1
        ctrl = self.controller if controller is None else controller
        res = np.zeros(_lib.RESULT)
        _lib.call(lib.qpy_env_run_episode, self._handle, ctrl._handle, int(seed), res.ctypes.data)
        n = lib.qpy_env_trace(self._handle, None)
        rows = np.zeros((n, _lib.TRACE_COLS))
        lib.qpy_env_trace(self._handle, rows.ctypes.data)
        traj = np.zeros(n, dtype=_TRACE_DTYPE)
        for k, name in enumerate(_TRACE_DTYPE.names):
            traj[name] = rows[:, k]
        return Episode(_result_dict(res), traj)

    def obstacles(self):
        """The world's obstacles for plotting: (circles, boxes), circles an (n, 3) array of
        x_m, y_m, r_m and boxes an (m, 5) array of centre x_m, y_m, width_m, height_m,
        angle_deg."""
        nc, nb = np.zeros(1, dtype=np.int32), np.zeros(1, dtype=np.int32)
        lib.qpy_env_shapes(self._handle, None, nc.ctypes.data, None, nb.ctypes.data)
        circles, boxes = np.zeros((nc[0], 3)), np.zeros((nb[0], 5))
        lib.qpy_env_shapes(self._handle, circles.ctypes.data, nc.ctypes.data, boxes.ctypes.data, nb.ctypes.data)
        return circles, boxes

    def __repr__(self):
        return (f"Env({self.world.name!r}, {self.robot.name!r}, {self.n_sectors} sectors, "
                f"noise {self.sensor_noise}/{self.actuation_noise}, seed {self.seed})")
