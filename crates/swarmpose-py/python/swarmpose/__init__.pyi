"""Type stubs of swarmpose (the Rust extension swarmpose._swarmpose)."""

import os
import pathlib
from typing import Any, ClassVar, Dict, List, Optional, Sequence as Seq, Tuple, Union

import numpy as np
import numpy.typing as npt
from typing_extensions import TypedDict, Unpack

__version__: str
METHODS: List[str]
"""Estimator names for ``method=``: ``pso``, ``pso-paper``, ``svd``, ``msac``, ``wls``."""

_Points = Union[npt.NDArray[np.float32], npt.NDArray[np.float64], Seq[Seq[float]]]
_Path = Union[str, "os.PathLike[str]"]
_Poses = Union[npt.NDArray[np.float32], npt.NDArray[np.float64]]

class EstimationError(RuntimeError):
    """The estimator ran but found no pose with enough support."""

class NotUsableError(EstimationError):
    """A run finished but fewer than half of its motions were tracked; ``run`` holds it."""
    run: OdometryRun

class RunnerUp:
    """A second rigid motion found among the correspondences the estimate left over."""
    @property
    def rotation(self) -> npt.NDArray[np.float64]: ...
    @property
    def quaternion_wxyz(self) -> npt.NDArray[np.float64]: ...
    @property
    def translation(self) -> npt.NDArray[np.float64]: ...
    @property
    def transform(self) -> npt.NDArray[np.float64]: ...
    @property
    def inliers(self) -> npt.NDArray[np.int64]: ...

class Registration:
    """The motion ``dst ~ R @ src + t`` (metres), its inliers and diagnostics."""
    @property
    def rotation(self) -> npt.NDArray[np.float64]:
        """Rotation matrix R, (3, 3)."""
    @property
    def quaternion_wxyz(self) -> npt.NDArray[np.float64]:
        """Rotation as a unit quaternion [w, x, y, z], w >= 0."""
    @property
    def translation(self) -> npt.NDArray[np.float64]:
        """Translation t, metres, (3,)."""
    @property
    def transform(self) -> npt.NDArray[np.float64]:
        """4x4 homogeneous transform [[R, t], [0, 1]]."""
    @property
    def inliers(self) -> npt.NDArray[np.int64]:
        """0-based indices of the inlier correspondences, ascending."""
    @property
    def inlier_ratio(self) -> float: ...
    @property
    def ambiguous(self) -> bool:
        """A second motion with comparable support was found (pso only)."""
    @property
    def runner_up(self) -> Optional[RunnerUp]: ...
    @property
    def method(self) -> Optional[str]: ...
    @property
    def seed(self) -> Optional[int]: ...
    @property
    def n_correspondences(self) -> int: ...
    @property
    def noise_model(self) -> str:
        """"covariance", "range", "threshold" or "none"."""
    @property
    def threshold(self) -> Optional[float]:
        """Inlier threshold used, metres."""
    @property
    def final_cost(self) -> float:
        """Truncated quadratic cost over all correspondences, m^2."""
    @property
    def residual_rms(self) -> float:
        """RMS of the inlier residuals, metres."""
    @property
    def iterations(self) -> int: ...
    @property
    def cost_evaluations(self) -> int: ...
    @property
    def elapsed_s(self) -> float:
        """Time of the estimation in Rust, seconds."""

def register(
    src: _Points,
    dst: _Points,
    *,
    method: str = "pso",
    threshold: Optional[float] = None,
    seed: int = 0,
    src_cov: Optional[npt.ArrayLike] = None,
    dst_cov: Optional[npt.ArrayLike] = None,
) -> Registration:
    """Estimates ``dst ~ R @ src + t`` from (N, 3) float32/float64 point sets (metres)
    with optional (N, 3, 3) covariances (m^2). Releases the GIL while estimating.

    Raises ValueError (shapes, NaN, too few or degenerate points, bad options),
    TypeError (dtype), EstimationError (no pose with enough support)."""

def _register_timing(
    src: _Points, dst: _Points, *, method: str = "pso", seed: int = 0, repeats: int = 1
) -> List[float]:
    """Seconds of each of ``repeats`` Rust estimator calls on the same data."""

class Frame:
    """The odometry engine's answer for one frame."""
    @property
    def index(self) -> int: ...
    @property
    def timestamp(self) -> float: ...
    @property
    def pose(self) -> npt.NDArray[np.float64]:
        """4x4 pose of the left camera in the first frame's (x right, y down, z forward, metres)."""
    @property
    def motion(self) -> npt.NDArray[np.float64]:
        """4x4 motion from the previous frame."""
    @property
    def reference(self) -> Optional[int]:
        """The frame this one was measured from: the previous one, or with window=K the window's oldest keyframe."""
    @property
    def measured_motion(self) -> npt.NDArray[np.float64]:
        """4x4 motion measured from `reference` (this camera's pose in the reference camera)."""
    @property
    def covariance(self) -> Optional[npt.NDArray[np.float64]]:
        """6x6 covariance of `measured_motion` (metres, radians), the self-calibration's uncertainty included."""
    @property
    def status(self) -> str:
        """"first", "tracked", "constant-velocity (REASON)" or "lost (REASON)"."""
    @property
    def tracked(self) -> bool: ...
    @property
    def predicted(self) -> bool: ...
    @property
    def counts(self) -> Dict[str, int]: ...
    @property
    def times_ms(self) -> Dict[str, float]: ...
    @property
    def correction(self) -> Dict[str, float]: ...
    @property
    def focal_correction_px(self) -> float: ...
    @property
    def correction_model(self) -> str: ...
    @property
    def split(self) -> Optional[Dict[str, Any]]:
        """The split-feature check of ``covariance`` (``split_check=True``): ``difference``
        (6,), ``covariance`` (6, 6), ``nees``, ``inliers``; ``None`` without it."""
    @property
    def keyframe(self) -> bool: ...
    @property
    def window_poses(self) -> List[Tuple[int, npt.NDArray[np.float64]]]:
        """The window's current (index, 4x4 pose) of each frame it holds, this frame last."""
    @property
    def ambiguous(self) -> bool:
        """Two distinct motions had comparable support; the one nearer the constant-velocity prediction was taken."""

class OdometryConfig:
    """The odometry engine's settings, checked when made (ValueError for a bad value).
    The entry points (``Odometry``, ``Odometry.from_sequence``, ``Odometry.rgbd``,
    ``odometry``) take one as ``config=``, or these keywords themselves."""
    def __init__(
        self,
        *,
        method: Optional[str] = None,
        threshold: Optional[float] = None,
        detector: Optional[str] = None,
        refine: Optional[bool] = None,
        calibrate: Optional[str] = None,
        disparity_correction: Optional[Union[Tuple[float, float], Tuple[float, float, float]]] = None,
        min_inliers: Optional[int] = None,
        seed: Optional[int] = None,
        window: Optional[int] = None,
        marginalise: Optional[str] = None,
        correction_per_frame: Optional[bool] = None,
        guided_radius_px: Optional[float] = None,
        max_working_pixels: Optional[int] = None,
        min_working_pixels: Optional[int] = None,
        split_check: Optional[bool] = None,
        config_file: Optional[_Path] = None,
    ) -> None: ...
    def __eq__(self, other: object) -> bool: ...
    __hash__: ClassVar[None]  # type: ignore[assignment]
    @property
    def method(self) -> Optional[str]: ...
    @property
    def threshold(self) -> Optional[float]: ...
    @property
    def detector(self) -> Optional[str]: ...
    @property
    def refine(self) -> Optional[bool]: ...
    @property
    def calibrate(self) -> Optional[str]: ...
    @property
    def disparity_correction(self) -> Optional[Union[Tuple[float, float], Tuple[float, float, float]]]: ...
    @property
    def min_inliers(self) -> Optional[int]: ...
    @property
    def seed(self) -> Optional[int]: ...
    @property
    def window(self) -> Optional[int]: ...
    @property
    def marginalise(self) -> Optional[str]: ...
    @property
    def correction_per_frame(self) -> Optional[bool]: ...
    @property
    def guided_radius_px(self) -> Optional[float]: ...
    @property
    def max_working_pixels(self) -> Optional[int]: ...
    @property
    def min_working_pixels(self) -> Optional[int]: ...
    @property
    def split_check(self) -> Optional[bool]: ...
    @property
    def config_file(self) -> Optional["os.PathLike[str]"]: ...

# OdometryConfig's keywords as the entry points' ``**options`` (all optional); the
# tests check that they are the constructor's.
_OdometryOptions = TypedDict(
    "_OdometryOptions",
    {
        "method": Optional[str],
        "threshold": Optional[float],
        "detector": Optional[str],
        "refine": Optional[bool],
        "calibrate": Optional[str],
        "disparity_correction": Optional[Union[Tuple[float, float], Tuple[float, float, float]]],
        "min_inliers": Optional[int],
        "seed": Optional[int],
        "window": Optional[int],
        "marginalise": Optional[str],
        "correction_per_frame": Optional[bool],
        "guided_radius_px": Optional[float],
        "max_working_pixels": Optional[int],
        "min_working_pixels": Optional[int],
        "split_check": Optional[bool],
        "config_file": Optional[_Path],
    },
    total=False,
)

class Odometry:
    """Streaming stereo visual odometry: one rectified pair in, its pose out."""
    def __init__(
        self,
        fx: float,
        fy: float,
        cx: float,
        cy: float,
        baseline: float,
        width: int,
        height: int,
        *,
        config: Optional[OdometryConfig] = None,
        **options: Unpack[_OdometryOptions],
    ) -> None:
        """Settings: ``config`` or ``OdometryConfig``'s keywords, not both."""
    @staticmethod
    def from_sequence(
        sequence_dir: _Path,
        *,
        config: Optional[OdometryConfig] = None,
        **options: Unpack[_OdometryOptions],
    ) -> "Odometry":
        """Settings: ``config`` or ``OdometryConfig``'s keywords, not both."""
    def track(
        self, left: npt.NDArray[np.uint8], right: npt.NDArray[np.uint8], timestamp: float
    ) -> Frame:
        """Takes the next (height, width) uint8 stereo pair at ``timestamp`` seconds."""
    @staticmethod
    def rgbd(
        fx: float,
        fy: float,
        cx: float,
        cy: float,
        width: int,
        height: int,
        *,
        depth_coefficient: Optional[float] = None,
        config: Optional[OdometryConfig] = None,
        **options: Unpack[_OdometryOptions],
    ) -> "Odometry":
        """An engine for an RGB-D camera; frames go to ``track_rgbd``. Settings:
        ``config`` or ``OdometryConfig``'s keywords, not both (ORB only; no calibrate,
        disparity_correction or working pixels)."""
    def track_rgbd(
        self, gray: npt.NDArray[np.uint8], depth: npt.NDArray[np.float32], timestamp: float
    ) -> Frame:
        """Takes the next gray image and its depth (float32 metres; 0 or NaN: none)."""
    @property
    def camera(self) -> Dict[str, float]: ...
    @property
    def working_camera(self) -> Dict[str, float]:
        """``camera`` halved above ``max_working_pixels`` pixels, doubled below ``min_working_pixels``."""
    @property
    def detector(self) -> Optional[str]: ...
    @property
    def method(self) -> Optional[str]: ...
    @property
    def calibration(self) -> Dict[str, Any]: ...
    @property
    def state_bytes(self) -> int: ...

class OdometryRun:
    """Every frame of a ``swarmpose.odometry`` run."""
    @property
    def config_json(self) -> str:
        """The run's configuration as a configuration file's text (``config.json``):
        saved and given as ``config_file=``, it reruns this run exactly."""
    @property
    def poses(self) -> npt.NDArray[np.float64]: ...
    @property
    def smoothed_poses(self) -> npt.NDArray[np.float64]:
        """Each frame's last estimate by the sliding window (fixed-lag smoothed), (N, 4, 4)."""
    @property
    def timestamps(self) -> npt.NDArray[np.float64]: ...
    @property
    def statuses(self) -> List[str]: ...
    @property
    def frames(self) -> List[Frame]: ...
    @property
    def ground_truth(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def calibration(self) -> Dict[str, Any]: ...
    def __len__(self) -> int: ...

def odometry(
    sequence_dir: _Path,
    *,
    frame_period: Optional[float] = None,
    left: Optional[str] = None,
    right: Optional[str] = None,
    depth: Optional[str] = None,
    stamp_tolerance: float = 0.0,
    config: Optional[OdometryConfig] = None,
    **options: Unpack[_OdometryOptions],
) -> OdometryRun:
    """Runs a whole KITTI, Karlsruhe, EuRoC or TUM RGB-D sequence directory or a ROS 2 bag
    (``.mcap``, ``.db3`` or a rosbag2 folder; stereo, or RGB-D: one colour and one depth
    camera; ``left``/``right`` topics, or ``left`` (colour) and ``depth`` topics, found
    when not given; ``stamp_tolerance`` in milliseconds), as ``swarmpose odometry``.
    Settings: ``config`` or ``OdometryConfig``'s keywords, not both. A frame that cannot be
    read (or Ctrl-C) stops the run: the exception's ``run`` attribute is the
    ``OdometryRun`` of the frames done."""

class Sequence:
    """A recorded sequence directory or ROS 2 bag, stereo or RGB-D.

    Stereo (KITTI, Karlsruhe, EuRoC, a stereo bag): ``seq[i]`` is frame i's rectified
    ``(left, right)`` images, each a (height, width) ``uint8`` array.

    RGB-D (a TUM RGB-D folder, an RGB-D bag: ``rgbd`` is True): ``seq[i]`` is frame i's
    ``(gray, depth)``: the colour image as gray, a (height, width) ``uint8`` array, and
    the depth registered to it, a (height, width) ``float32`` array in metres along the
    optical axis (0 where there is no depth; a bag's ``16UC1`` millimetres and ``32FC1``
    metres, a TUM folder's 5000 units per metre, all converted to metres). ``camera``'s
    ``baseline`` is then ``None``."""
    def __init__(
        self,
        path: _Path,
        *,
        left: Optional[str] = None,
        right: Optional[str] = None,
        depth: Optional[str] = None,
        stamp_tolerance: float = 0.0,
    ) -> None: ...
    def __len__(self) -> int: ...
    def __getitem__(
        self, i: int
    ) -> Union[
        Tuple[npt.NDArray[np.uint8], npt.NDArray[np.uint8]],
        Tuple[npt.NDArray[np.uint8], npt.NDArray[np.float32]],
    ]: ...
    @property
    def layout(self) -> str: ...
    @property
    def rgbd(self) -> bool: ...
    @property
    def stamps_ns(self) -> Optional[List[int]]: ...
    @property
    def topics(self) -> Optional[Tuple[str, str]]: ...
    @property
    def unpaired(self) -> List[str]: ...
    @property
    def root(self) -> pathlib.Path: ...
    @property
    def camera(self) -> Dict[str, Optional[float]]: ...
    @property
    def ground_truth(self) -> Optional[npt.NDArray[np.float64]]: ...

def evaluate(
    estimate: Union[_Poses, _Path],
    ground_truth: Union[_Poses, _Path],
    *,
    format: Optional[str] = None,
    max_diff: float = 0.01,
    segment_scale: float = 1.0,
) -> Dict[str, Any]:
    """Trajectory metrics (as ``swarmpose evaluate --json``) of (N, 4, 4) poses or files;
    ``["kitti"]``: the KITTI devkit's segment errors, lengths x ``segment_scale``."""

