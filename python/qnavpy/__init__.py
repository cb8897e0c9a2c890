"""qnav from Python: the Box2D simulator, libqnav's fixed-point controllers, policy files
and simevo's batch evaluation, on numpy arrays (docs/python.md).

    import qnavpy
    env = qnavpy.Env("dense", "tekbot", sectors=16)
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step()           # the controller decides
    obs, reward, terminated, truncated, info = env.step((30.0, 0.5))  # or you do
    scores = qnavpy.evaluate(["prob", "runs/best.policy"], episodes=20)

Named after the project, not ``qnav``: that name is the LCM message classes' package.
Everything runs in the same C code as the command-line tools; errors raise
:class:`QnavError` with the tools' one-line messages.
"""

import os as _os

# Installed, the robots and environments are in PREFIX/share/qnav/data (_install.py says
# where from here); in a build tree there is no _install.py and the library knows its
# source tree's data/ folder. QNAV_DATA_DIR, when set, wins as for every qnav program.
try:
    from ._install import DATA_FROM_PACKAGE as _DATA_FROM_PACKAGE
except ImportError:
    _DATA_FROM_PACKAGE = None
if _DATA_FROM_PACKAGE and not _os.environ.get("QNAV_DATA_DIR"):
    _data = _os.path.join(_os.path.dirname(_os.path.abspath(__file__)), _DATA_FROM_PACKAGE)
    if _os.path.isdir(_os.path.join(_data, "robots")):
        _os.environ["QNAV_DATA_DIR"] = _os.path.normpath(_data)

from ._lib import QnavError, version  # noqa: E402
from .core import Controller, Decision, Policy, Robot, World, controller_names, world_families  # noqa: E402
from .env import Env, Episode  # noqa: E402
from .evaluate import Evaluation, evaluate  # noqa: E402

__version__ = version()
__all__ = ["Controller", "Decision", "Env", "Episode", "Evaluation", "Policy", "QnavError", "Robot", "World",
           "controller_names", "evaluate", "world_families", "__version__"]
