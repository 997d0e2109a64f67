"""swarmpose: rigid 3D-3D registration by a particle swarm over unit quaternions, and
streaming stereo visual odometry, on numpy arrays.

Built from the same Rust crates as the ``swarmpose`` command line:

* ``register(src, dst, ...)`` estimates ``dst ~ R @ src + t`` from matched (N, 3)
  point sets with wrong matches among them (a ``Registration``).
* ``Odometry(...)`` / ``Odometry.from_sequence(dir)`` is the streaming engine:
  ``track(left, right, timestamp)`` returns each frame's pose (a ``Frame``). Its
  settings are an ``OdometryConfig(...)`` given as ``config=``, or that class's keywords
  (``method=``, ``window=``, ...) given directly.
* ``odometry(dir)`` runs a whole KITTI, Karlsruhe or EuRoC sequence directory;
  ``Sequence(dir)`` reads its frames as numpy images.
* ``evaluate(estimate, ground_truth)`` returns the trajectory metrics as a dict.
* ``swarmpose.batch.run(manifest, out)`` runs the items of a ``swarmpose batch``
  manifest in a process pool or on Ray; ``swarmpose.batch.merge`` makes their table.

Units: metres, radians unless a name says otherwise.
"""

from ._swarmpose import (
    METHODS,
    EstimationError,
    Frame,
    NotUsableError,
    Odometry,
    OdometryConfig,
    OdometryRun,
    Registration,
    RunnerUp,
    Sequence,
    __version__,
    _register_timing,
    evaluate,
    odometry,
    register,
)
from . import batch  # noqa: E402,F401  (the submodule swarmpose.batch)

__all__ = [
    "METHODS",
    "EstimationError",
    "Frame",
    "NotUsableError",
    "Odometry",
    "OdometryConfig",
    "OdometryRun",
    "Registration",
    "RunnerUp",
    "Sequence",
    "__version__",
    "evaluate",
    "odometry",
    "register",
]
