#!/usr/bin/env python3
"""The measured rotations of the EuRoC clip against its own gyroscope: does the camera
turn, and is the rotation part of the covariance honest against a reference that
measures that turn?

The Vicon and vicon2gt ground truths disagree by more than the estimate's error on this
clip (docs/covariance.md), so this check takes the third, independent sensor the clip
ships: the IMU (ADIS16448, 200 Hz, hardware-synchronised with the cameras). For each row
of motion_covariance.csv (frame k measured from reference r), the gyroscope's rates less
their bias are integrated from the time of r to the time of k (trapezoids, quaternion
products, the ends interpolated) and turned into the camera's frame (cam0's T_BS). The
bias is the mean rate over the whole IMU record (which begins 1 s before the first image
and ends 1 s after the last); vicon2gt's own bias estimate is printed next to it.

Printed per axis: the correlation of the measured rotations with the gyroscope's, the
RMS of each (mdeg), and the mean and median NEES of the rotation's error against the
gyroscope (3 degrees of freedom: 3 when the covariance is honest) under the claimed
rotation covariance plus the gyroscope's white noise over the interval (its noise
density squared times the interval; sensor.yaml).

    python3 tools/covariance/gyro.py RUN_DIR DATA/euroc_v1_01_easy_micro \
        [--update crates/swarmpose-odometry/RESULTS.md --name NAME]

Standard library only.
"""

import argparse
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from nees import cholesky_solve, motion_error, publish, quat_log, quat_mul, read_covariance  # noqa: E402,I001


def read_rows(path):
    """Numeric rows of a EuRoC csv (comment lines skipped)."""
    with open(path) as f:
        return [[float(x) for x in line.split(",")[:7]] for line in f
                if line.strip() and not line.startswith("#")]


def yaml_value(path, key):
    """The text after `key:` in a EuRoC sensor.yaml, with its continuation lines."""
    with open(path) as f:
        text = f.read()
    start = text.index(key + ":") + len(key) + 1
    end = text.find("\n", text.find("]", start)) if "[" in text[start:start + 200] else \
        text.find("\n", start)
    return text[start:end]


def matrix_3x3(path):
    """The rotation of cam0's T_BS (camera to body)."""
    body = yaml_value(path, "T_BS")
    data = body[body.index("[") + 1:body.index("]")]
    v = [float(x) for x in data.replace("\n", " ").split(",")]
    return [v[0:3], v[4:7], v[8:11]]


def exp_quat(w):
    """Unit quaternion (w, x, y, z) of a rotation vector."""
    a = math.sqrt(sum(x * x for x in w))
    if a < 1e-15:
        return (1.0, 0.5 * w[0], 0.5 * w[1], 0.5 * w[2])
    s = math.sin(0.5 * a) / a
    return (math.cos(0.5 * a), w[0] * s, w[1] * s, w[2] * s)


def rate_at(imu, t):
    """Gyroscope rate (rad/s, IMU frame) at time t (ns), interpolated."""
    lo, hi = 0, len(imu) - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if imu[mid][0] <= t:
            lo = mid
        else:
            hi = mid
    a, b = imu[lo], imu[hi]
    f = 0.0 if b[0] == a[0] else min(max((t - a[0]) / (b[0] - a[0]), 0.0), 1.0)
    return [a[i] + f * (b[i] - a[i]) for i in range(1, 4)]


def integrate(imu, bias, t0, t1):
    """Rotation vector (IMU frame, radians) from t0 to t1 (ns): trapezoids of the rates
    less `bias`, composed as quaternions."""
    times = [t0] + [s[0] for s in imu if t0 < s[0] < t1] + [t1]
    q = (1.0, 0.0, 0.0, 0.0)
    prev = [r - b for r, b in zip(rate_at(imu, t0), bias)]
    for ta, tb in zip(times, times[1:]):
        cur = [r - b for r, b in zip(rate_at(imu, tb), bias)]
        dt = (tb - ta) * 1e-9
        q = quat_mul(q, exp_quat([0.5 * (x + y) * dt for x, y in zip(prev, cur)]))
        prev = cur
    return quat_log(q)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", help="output directory of `swarmpose odometry` on the clip")
    ap.add_argument("data", help="the clip's directory (mav0/ inside)")
    ap.add_argument("--update", metavar="FILE",
                    help="write the figures as the generated section --name of FILE")
    ap.add_argument("--name", default="covariance-gyro", help="the section's name")
    a = ap.parse_args()
    mav = os.path.join(a.data, "mav0")
    with open(os.path.join(mav, "cam0", "data.csv")) as f:
        images = [int(line.split(",")[0]) for line in f
                  if line.strip() and not line.startswith("#")]
    imu = read_rows(os.path.join(mav, "imu0", "data.csv"))
    r_bc = matrix_3x3(os.path.join(mav, "cam0", "sensor.yaml"))
    density = float(yaml_value(os.path.join(mav, "imu0", "sensor.yaml"),
                               "gyroscope_noise_density").split("#")[0])
    bias = [statistics.fmean(s[i] for s in imu) for i in range(1, 4)]
    rows = read_covariance(os.path.join(a.run, "motion_covariance.csv"))
    measured, gyro, nees = [], [], []
    for frame, ref, motion, c in rows:
        w_b = integrate(imu, bias, images[ref], images[frame])
        # Camera frame: w_c = R_BC' w_b.
        w_c = tuple(sum(r_bc[i][k] * w_b[i] for i in range(3)) for k in range(3))
        truth = (exp_quat(w_c), motion[1])
        err = motion_error(motion, truth)[3:]
        dt = (images[frame] - images[ref]) * 1e-9
        cov = [[c[3 + i][3 + j] + (density * density * dt if i == j else 0.0)
                for j in range(3)] for i in range(3)]
        v = cholesky_solve(cov, err)
        if v is not None:
            nees.append(v)
        measured.append(quat_log(motion[0]))
        gyro.append(w_c)
    if len(rows) < 3:
        sys.exit("gyro.py: fewer than 3 motions")
    mdeg = 1e3 * 180.0 / math.pi
    lines = [f"{len(rows)} motions ({a.run}); gyroscope bias (mean rate), rad/s: "
             + ", ".join(f"{b:.5f}" for b in bias)]
    for k, axis in enumerate("xyz"):
        m = [x[k] for x in measured]
        g = [x[k] for x in gyro]
        rms = [mdeg * math.sqrt(statistics.fmean(v * v for v in s)) for s in (m, g)]
        lines.append(f"omega {axis}: correlation {statistics.correlation(m, g):.2f}, RMS "
                     f"measured {rms[0]:.2f} mdeg, gyroscope {rms[1]:.2f} mdeg")
    lines.append(f"gyroscope white noise over {1e-9 * (images[1] - images[0]):.3f} s: "
                 f"{mdeg * density * math.sqrt(1e-9 * (images[1] - images[0])):.2f} mdeg per axis")
    lines.append(f"rotation NEES against the gyroscope (3 when honest): mean "
                 f"{statistics.fmean(nees):.2f}, median {statistics.median(nees):.2f} over "
                 f"{len(nees)} motions")
    text = "\n".join(f"    {line}" for line in lines) + "\n"
    if a.update:
        publish(a.update, a.name, " ".join(["python3 tools/covariance/gyro.py", *sys.argv[1:]]),
                text)
    else:
        print(text, end="")


if __name__ == "__main__":
    main()
