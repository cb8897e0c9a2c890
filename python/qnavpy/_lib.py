"""libqnavpy through ctypes: where the shared library is, its functions' signatures, and
the one error type. The library's calls fill arrays the caller owns; ctypes releases the
GIL during each call, so environments in different threads step in parallel."""

import ctypes
import os
from ctypes import POINTER, c_char_p, c_double, c_int16, c_int32, c_int64, c_size_t, c_uint64, c_void_p

_HERE = os.path.dirname(os.path.abspath(__file__))

ERRLEN = 512
MAX_WEIGHTS = 161      # QPY_MAX_WEIGHTS: a 3-input network of 32 hidden units
KIND_ROBOT_PROB = 0    # QPY_KIND_ROBOT_PROB: the robot's tuned probabilistic policy
KIND_NONE = -1         # no policy (VFH+)
KIND_PROB = 1          # QNAV_POLICY_PROB
KIND_NET = 2           # QNAV_POLICY_NET
OBS_INT_EXTRA = 5
OBS_FLOAT = 5
INFO = 10
TRACE_COLS = 9
RESULT = 16
LEVELS = 32            # QNAV_DIST_LEVELS
DTHETA = 181           # dtheta 0..180 deg


class QnavError(ValueError):
    """qnav refused its input. ``str(error)`` is the one line the command-line tools
    print for the same input, without their ``PROGRAM:`` prefix (``qnav-sim:``,
    ``simevo:``); ``status`` is the library's negative status."""

    def __init__(self, message, status=-1):
        super().__init__(message)
        self.status = status


def _load():
    path = os.environ.get("QNAVPY_LIBRARY") or os.path.join(_HERE, "libqnavpy.so")
    try:
        return ctypes.CDLL(path)
    except OSError as e:
        raise ImportError(f"qnavpy: cannot load {path} ({e}); build it with cmake "
                          "(docs/python.md)") from None


lib = _load()

_P = c_void_p  # arrays cross as addresses (numpy's .ctypes.data)
_ERR = [c_char_p, c_size_t]
_SIGNATURES = {
    "qpy_version": (c_char_p, []),
    "qpy_world_families": (c_char_p, []),
    "qpy_controller_names": (c_char_p, []),
    "qpy_robot_info": (c_int32, [c_char_p, _P, c_char_p, c_size_t, _P] + _ERR),
    "qpy_world_info": (c_int32, [c_char_p, _P, c_char_p, c_size_t] + _ERR),
    "qpy_policy_check": (c_int32, [c_int32, c_int32, c_int32, _P, c_int32] + _ERR),
    "qpy_policy_read": (c_int32, [c_char_p, _P, _P, _P, _P, _P] + _ERR),
    "qpy_policy_write": (c_int32, [c_char_p, c_int32, c_int32, c_int32, _P, c_int32, c_char_p] + _ERR),
    "qpy_env_create": (c_int32, [c_char_p, c_char_p, c_int32, c_double, c_double, c_uint64, c_double,
                                 c_char_p, c_double, c_double, POINTER(c_void_p)] + _ERR),
    "qpy_env_free": (None, [c_void_p]),
    "qpy_env_params": (None, [c_void_p, _P]),
    "qpy_env_reset": (c_int32, [c_void_p, c_uint64, c_void_p, _P, _P, _P] + _ERR),
    "qpy_env_step": (c_int32, [c_void_p, c_void_p, c_double, c_double, _P, _P, _P] + _ERR),
    "qpy_env_result": (c_int32, [c_void_p, _P] + _ERR),
    "qpy_env_run_episode": (c_int32, [c_void_p, c_void_p, c_uint64, _P] + _ERR),
    "qpy_env_trace": (c_int64, [c_void_p, _P]),
    "qpy_env_shapes": (None, [c_void_p, _P, _P, _P, _P]),
    "qpy_ctrl_create": (c_int32, [c_char_p, c_void_p, c_char_p, c_int32, c_int32, c_int32, c_int32, c_int32,
                                  _P, c_int32, c_int32, POINTER(c_void_p)] + _ERR),
    "qpy_ctrl_free": (None, [c_void_p]),
    "qpy_ctrl_sensors": (None, [c_void_p, _P, _P]),
    "qpy_ctrl_reset": (None, [c_void_p]),
    "qpy_ctrl_step": (c_int32, [c_void_p, _P, c_int32, c_int32, c_int32, c_int32, c_int32, c_int32, _P, _P] + _ERR),
    "qpy_ctrl_grid": (c_int32, [c_void_p, _P, _P, _P] + _ERR),
    "qpy_evaluate": (c_int32, [c_char_p, c_char_p, c_int32, c_double, c_uint64, c_char_p, c_int32, _P, _P, _P,
                               _P, ctypes.c_uint32, c_int32, _P, _P, _P, _P, _P] + _ERR),
}
for _name, (_res, _args) in _SIGNATURES.items():
    _fn = getattr(lib, _name)
    _fn.restype = _res
    _fn.argtypes = _args


class ErrorBuffer:
    """A reusable buffer for the library's one-line messages."""

    def __init__(self):
        self.buf = ctypes.create_string_buffer(ERRLEN)

    def check(self, status):
        if status != 0:
            raise QnavError(self.buf.value.decode("utf-8", "replace"), status)


def call(fn, *args):
    """fn(*args, err, ERRLEN); QnavError with its message when it fails."""
    e = ErrorBuffer()
    e.check(fn(*args, e.buf, ERRLEN))


def encode(text):
    """A str or path as the library's bytes (None stays None)."""
    return None if text is None else os.fsencode(text)


def version():
    return lib.qpy_version().decode()
