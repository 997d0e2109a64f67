"""swarmpose.OdometryConfig: the one list of the odometry engine's keywords. Each entry
point takes a config object or the same keywords (the same engine either way), never
both; an unknown keyword names itself and the options; bad values raise the messages
they raised as keywords."""

import ast
import inspect
from pathlib import Path

import numpy as np
import pytest

import swarmpose
from swarmpose import OdometryConfig
from test_odometry import KITTI_CAMERA
from test_rgbd import CX, CY, DEPTH_M, FX, H, W, texture

STUB = Path(__file__).resolve().parents[1] / "python" / "swarmpose" / "__init__.pyi"
STEREO_ONLY = dict(calibrate="none", disparity_correction=(0.1, 0.0),
                   max_working_pixels=2_000_000, min_working_pixels=1000)


def keywords():
    """The constructor's keywords, as Python sees its signature."""
    return list(inspect.signature(OdometryConfig).parameters)


def entry_points(tmp_path):
    """Each entry point as a call taking the settings (and nothing else that could fail
    first: the directory does not exist, and the settings are checked before it is
    opened)."""
    missing = tmp_path / "no-such-sequence"
    return {
        "Odometry": lambda **kw: swarmpose.Odometry(**KITTI_CAMERA, **kw),
        "Odometry.from_sequence": lambda **kw: swarmpose.Odometry.from_sequence(missing, **kw),
        "Odometry.rgbd": lambda **kw: swarmpose.Odometry.rgbd(FX, FX, CX, CY, W, H, **kw),
        "odometry": lambda **kw: swarmpose.odometry(missing, **kw),
    }


def test_the_keywords_are_declared_once():
    """Keyword-only, with the command line's defaults; a read-only property each; the
    stubs' constructor and ``**options`` type name the same keywords."""
    names = keywords()
    assert names[:3] == ["method", "threshold", "detector"] and len(names) == 16
    params = inspect.signature(OdometryConfig).parameters.values()
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in params)
    default = OdometryConfig()
    for p in params:
        assert getattr(default, p.name) == p.default, p.name
        with pytest.raises(AttributeError):
            setattr(default, p.name, p.default)
    # None: the command line's default, or the configuration file's setting.
    assert (default.method, default.detector, default.refine, default.seed) == (None,) * 4
    for call in (swarmpose.Odometry, swarmpose.Odometry.from_sequence, swarmpose.Odometry.rgbd,
                 swarmpose.odometry):
        sig = inspect.signature(call)
        assert not set(names) & set(sig.parameters), call
        assert list(sig.parameters)[-2:] == ["config", "options"], call

    tree = ast.parse(STUB.read_text(encoding="utf-8"))
    (cls,) = [n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "OdometryConfig"]
    init = next(f for f in cls.body if isinstance(f, ast.FunctionDef) and f.name == "__init__")
    assert [a.arg for a in init.args.kwonlyargs] == names
    properties = [f.name for f in cls.body if isinstance(f, ast.FunctionDef) and f.decorator_list]
    assert properties == names
    (typed,) = [n for n in tree.body if isinstance(n, ast.Assign)
                and getattr(n.targets[0], "id", None) == "_OdometryOptions"]
    assert [k.value for k in typed.value.args[1].keys] == names


def test_a_config_is_the_same_keywords(kitti_seq2):
    """``config=OdometryConfig(...)`` gives the trajectory of the same keywords (and not
    the default one), streaming and over a whole sequence."""
    config = OdometryConfig(window=5, seed=3)
    by_config = swarmpose.odometry(kitti_seq2, config=config)
    by_keywords = swarmpose.odometry(kitti_seq2, window=5, seed=3)
    assert np.array_equal(by_config.poses, by_keywords.poses)
    assert np.max(np.abs(by_config.poses - swarmpose.odometry(kitti_seq2).poses)) > 1e-6

    seq = swarmpose.Sequence(kitti_seq2)
    engines = [swarmpose.Odometry.from_sequence(kitti_seq2, config=config),
               swarmpose.Odometry(**seq.camera, config=config),
               swarmpose.Odometry(**seq.camera, window=5, seed=3)]
    for i in range(4):
        poses = [e.track(*seq[i], 0.1 * i).pose for e in engines]
        assert all(np.array_equal(p, by_keywords.poses[i]) for p in poses)


def test_an_rgbd_config_is_the_same_keywords():
    """Without data: the RGB-D wall of test_rgbd, frame to frame with another seed."""
    wall = texture()
    depth = np.full((H, W), DEPTH_M, np.float32)
    engines = [swarmpose.Odometry.rgbd(FX, FX, CX, CY, W, H, window=0, seed=7),
               swarmpose.Odometry.rgbd(FX, FX, CX, CY, W, H,
                                       config=OdometryConfig(window=0, seed=7))]
    for i, shift in enumerate((0, 8, 16)):
        gray = np.ascontiguousarray(wall[:, shift:W + shift])
        a, b = (e.track_rgbd(gray, depth, 0.1 * i) for e in engines)
        assert a.status == b.status and np.array_equal(a.pose, b.pose)
    assert b.tracked and b.reference == 1


def test_config_and_keywords_together(tmp_path):
    for name, call in entry_points(tmp_path).items():
        with pytest.raises(TypeError) as e:
            call(config=OdometryConfig(), window=5)
        assert str(e.value) == (f"{name}() takes config= or option keywords, not both "
                                "(given: config and window)")
        with pytest.raises(TypeError):
            call(config={"window": 5})


def test_unknown_keyword(tmp_path):
    """The keyword is named, and the options listed are the constructor's."""
    for name, call in entry_points(tmp_path).items():
        with pytest.raises(TypeError) as e:
            call(windw=5)
        assert str(e.value) == (f"{name}() got an unexpected keyword argument 'windw' "
                                f"(the options are {', '.join(keywords())})")
    with pytest.raises(TypeError, match="depth_coefficient"):
        OdometryConfig(depth_coefficient=1e-3)
    with pytest.raises(TypeError, match="frame_period"):
        swarmpose.Odometry(**KITTI_CAMERA, frame_period=0.1)
    with pytest.raises(TypeError):
        OdometryConfig("pso")


def test_repr_and_equality():
    config = OdometryConfig(method="svd", window=5, disparity_correction=(0.25, 0.0),
                            marginalise="finished")
    assert repr(config) == (
        "OdometryConfig(method='svd', threshold=None, detector=None, refine=None, "
        "calibrate=None, disparity_correction=(0.25, 0.0), min_inliers=None, seed=None, "
        "window=5, marginalise='finished', correction_per_frame=None, guided_radius_px=None, "
        "max_working_pixels=None, "
        "min_working_pixels=None, "
        "split_check=None, config_file=None)")
    assert config == eval(repr(config), {"OdometryConfig": OdometryConfig})
    assert config != OdometryConfig(method="svd", window=5)
    assert OdometryConfig(seed=0) == OdometryConfig(seed=0)


@pytest.mark.parametrize("options, message", [
    (dict(method="icp"), 'unknown method "icp": one of pso, pso-paper, svd, msac, wls'),
    (dict(method="svd", threshold=0.1), "threshold does not apply to method svd"),
    (dict(threshold=-1.0), "threshold -1: it must be a positive, finite number of metres"),
    (dict(marginalise="sometimes"), 'marginalise "sometimes": expected one of off, finished, all'),
    (dict(min_inliers=2), "min_inliers 2: at least 3 are needed for a motion"),
    (dict(max_working_pixels=5), "camera: max_working_pixels 5: at least 10000 are needed"),
    (dict(min_working_pixels=400_000),
     "camera: min_working_pixels 400000: at most a quarter of max_working_pixels 1500000"),
    (dict(disparity_correction=(1e9, 0.0)), "disparity_correction offset 1e9 px is outside"),
])
def test_bad_values(options, message, tmp_path):
    """The constructor raises; so does each entry point given the same keywords."""
    with pytest.raises(ValueError) as e:
        OdometryConfig(**options)
    assert str(e.value).startswith(message)
    for call in entry_points(tmp_path).values():
        with pytest.raises(ValueError) as again:
            call(**options)
        assert str(again.value) == str(e.value)


def test_bad_names_raise_as_keywords_did():
    """Detector, calibration and the type of a value: as before the config class."""
    for options in (dict(detector="sift"), dict(calibrate="everything")):
        with pytest.raises(ValueError) as e:
            OdometryConfig(**options)
        with pytest.raises(ValueError) as again:
            swarmpose.Odometry(**KITTI_CAMERA, **options)
        assert str(again.value) == str(e.value) and "\n" not in str(e.value)
    with pytest.raises(OverflowError):
        OdometryConfig(window=-1)


def test_rgbd_refuses_what_only_stereo_uses():
    """An RGB-D engine has no disparity to correct and never resamples its frames."""
    for name, value in STEREO_ONLY.items():
        with pytest.raises(ValueError) as e:
            swarmpose.Odometry.rgbd(FX, FX, CX, CY, W, H, config=OdometryConfig(**{name: value}))
        assert str(e.value).startswith(f"{name} does not apply to an RGB-D camera")
    with pytest.raises(ValueError, match="detector surf is not available for RGB-D input"):
        swarmpose.Odometry.rgbd(FX, FX, CX, CY, W, H, detector="surf")
    swarmpose.Odometry(**KITTI_CAMERA, **STEREO_ONLY)
