#!/usr/bin/env python3
"""NEES of the motion covariance that `swarmpose odometry` writes (motion_covariance.csv),
against a known motion, and of the split-feature check (split_check.csv), per sequence.

Each row of motion_covariance.csv is a measured motion T (pose of camera k in its
reference camera) with the 6x6 covariance of xi = (nu, omega) in T_true = T o E(xi). The
normalised estimation error squared of a row is xi' C^-1 xi with xi the error of T
against the truth: either zero motion (`zero`: a camera that stands still, the EuRoC
clip) or the ground truth the run wrote (`groundtruth`: groundtruth.kitti.txt in the
output directory, T_true = G_ref^-1 G_k). An honest covariance gives a mean of 6.

split_check.csv (written by `swarmpose odometry --split-check`) holds each frame's NEES of
the difference of two motions estimated from spatially disjoint halves of its matches,
weighed by the sum of their covariances (no ground truth needed; 6 when honest).

    cargo build --release -p swarmpose-cli
    python3 tools/covariance/nees.py [--binary target/release/swarmpose] [--data DIR] \
        [--out DIR] [SEQUENCE ...] > nees.md

Standard library only (no numpy).
"""

import argparse
import math
import os
import platform
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                "generated"))
from generated import publish  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
# (name, truth of the measured motions). None: the built-in synthetic street.
SEQUENCES = [
    ("euroc_v1_01_easy_micro", ["zero", "groundtruth"]),
    ("kitti_vo_seq2", ["groundtruth"]),
    ("karlsruhe_2010_03_09_drive_0023", [None]),
    ("synthetic", ["groundtruth"]),
]
MODES = [("frame to frame", ["--window", "0"]), ("window (default)", [])]


def quat_mul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw)


def quat_conj(q):
    return (q[0], -q[1], -q[2], -q[3])


def quat_rotate(q, v):
    w = quat_mul(quat_mul(q, (0.0, *v)), quat_conj(q))
    return w[1:]


def quat_log(q):
    """Rotation vector (radians) of a unit quaternion (w, x, y, z)."""
    w, x, y, z = q
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    k = 2.0 * math.atan2(s, w) / s if s > 1e-12 else 2.0 / w
    return (x * k, y * k, z * k)


def quat_of_matrix(m):
    """Unit quaternion (w, x, y, z) of a 3x3 rotation matrix (rows)."""
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = (0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s)
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        q = ((m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s)
    elif m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        q = ((m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s)
    else:
        s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
        q = ((m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s)
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def pose_inverse(p):
    q, t = p
    qi = quat_conj(q)
    return (qi, tuple(-c for c in quat_rotate(qi, t)))


def pose_compose(a, b):
    qa, ta = a
    qb, tb = b
    rb = quat_rotate(qa, tb)
    return (quat_mul(qa, qb), tuple(x + y for x, y in zip(ta, rb)))


def motion_error(estimate, truth):
    """xi = (nu, omega) with truth = estimate o E(xi) (the engine's convention)."""
    qe, te = estimate
    qt, tt = truth
    qi = quat_conj(qe)
    nu = quat_rotate(qi, tuple(a - b for a, b in zip(tt, te)))
    omega = quat_log(quat_mul(qi, qt))
    return list(nu) + list(omega)


def cholesky_solve(c, x):
    """x' C^-1 x for a symmetric positive definite C (lists), or None."""
    n = len(x)
    lo = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i + 1):
            s = c[i][j] - sum(lo[i][k] * lo[j][k] for k in range(j))
            if i == j:
                if s <= 0:
                    return None
                lo[i][i] = math.sqrt(s)
            else:
                lo[i][j] = s / lo[j][j]
    y = []
    for i in range(n):
        y.append((x[i] - sum(lo[i][k] * y[k] for k in range(i))) / lo[i][i])
    return sum(v * v for v in y)


def read_covariance(path):
    """Rows of motion_covariance.csv: (frame, reference, motion, covariance)."""
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or line.startswith("frame"):
                continue
            v = line.strip().split(",")
            if len(v) != 30:
                continue
            frame, ref = int(v[0]), int(v[1])
            t = tuple(float(x) for x in v[2:5])
            q = tuple(float(x) for x in v[5:9])
            upper = [float(x) for x in v[9:]]
            c = [[0.0] * 6 for _ in range(6)]
            k = 0
            for i in range(6):
                for j in range(i, 6):
                    c[i][j] = c[j][i] = upper[k]
                    k += 1
            rows.append((frame, ref, (q, t), c))
    return rows


def read_kitti(path):
    poses = []
    with open(path) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            if len(v) != 12:
                continue
            m = [v[0:3], v[4:7], v[8:11]]
            poses.append((quat_of_matrix(m), (v[3], v[7], v[11])))
    return poses


def covariance_figures(out, truth):
    """Mean and median NEES, count, and the claimed standard deviations' ranges
    (translation mm, rotation mdeg), or None without rows."""
    rows = read_covariance(os.path.join(out, "motion_covariance.csv"))
    gt = None
    if truth == "groundtruth":
        path = os.path.join(out, "groundtruth.kitti.txt")
        if not os.path.exists(path):
            return None
        gt = read_kitti(path)
    nees, sd_t, sd_r = [], [], []
    identity = ((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    for frame, ref, motion, c in rows:
        if gt is None:
            true = identity
        else:
            true = pose_compose(pose_inverse(gt[ref]), gt[frame])
        e = motion_error(motion, true)
        v = cholesky_solve(c, e)
        if v is None:
            continue
        nees.append(v)
        sd_t += [1e3 * math.sqrt(c[i][i]) for i in range(3)]
        sd_r += [1e3 * math.degrees(math.sqrt(c[i][i])) for i in range(3, 6)]
    if not nees:
        return None
    return {
        "mean": statistics.fmean(nees),
        "median": statistics.median(nees),
        "n": len(nees),
        "sd_t": (min(sd_t), max(sd_t)),
        "sd_r": (min(sd_r), max(sd_r)),
    }


def motion_correlation(out):
    """Per axis (nu x, y, z, omega x, y, z), the correlation of the measured motions with
    the ground truth's over the rows of motion_covariance.csv, or None without ground
    truth: near 1 when the camera really moves by more than the estimate's error."""
    path = os.path.join(out, "groundtruth.kitti.txt")
    if not os.path.exists(path):
        return None
    gt = read_kitti(path)
    identity = ((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    measured, truth = [], []
    for frame, ref, motion, _ in read_covariance(os.path.join(out, "motion_covariance.csv")):
        measured.append(motion_error(identity, motion))
        truth.append(motion_error(identity, pose_compose(pose_inverse(gt[ref]), gt[frame])))
    if len(measured) < 3:
        return None
    return [statistics.correlation([m[k] for m in measured], [t[k] for t in truth])
            for k in range(6)]


def split_figures(out):
    path = os.path.join(out, "split_check.csv")
    if not os.path.exists(path):
        return None
    values, model = [], []
    with open(path) as f:
        for line in f:
            v = line.strip().split(",")
            if len(v) < 2 or not v[0].isdigit():
                continue
            values.append(float(v[1]))
            # model_nees (the model's covariance without the systematic floor), when the
            # binary writes it.
            if len(v) > 10:
                model.append(float(v[10]))
    if not values:
        return None
    return {"mean": statistics.fmean(values), "median": statistics.median(values),
            "n": len(values), "model_mean": statistics.fmean(model) if model else None}


def run(binary, seq_dir, out, extra):
    cmd = [binary, "odometry"] + ([seq_dir] if seq_dir else []) + [
        "--out", out, "--quiet", "--split-check", *extra]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode not in (0, 3):
        sys.exit(f"nees.py: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()}")


def machine():
    cpu = platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores"


def commit():
    p = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                       capture_output=True, text=True)
    # Changes to documentation (the file being regenerated) do not change a figure.
    dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no",
                            "--", ".", ":!*.md"], capture_output=True, text=True).stdout.strip()
    return p.stdout.strip() + (" (with uncommitted changes)" if dirty else "")


def fmt(x):
    return "—" if x is None else (f"{x:.0f}" if x >= 100 else f"{x:.2f}" if x < 10 else f"{x:.1f}")


def row(name, label, truth, c, s):
    """One line of the table (text)."""
    cells = [name, label, truth or "none (INS positions only)"]
    if c:
        cells += [str(c["n"]), fmt(c["mean"]), fmt(c["median"]),
                  f"{c['sd_t'][0]:.3g}-{c['sd_t'][1]:.3g}",
                  f"{c['sd_r'][0]:.3g}-{c['sd_r'][1]:.3g}"]
    else:
        cells += ["—"] * 5
    if s:
        cells += [str(s["n"]), fmt(s["mean"]), fmt(s["median"]), fmt(s.get("model_mean"))]
    else:
        cells += ["—"] * 4
    return "| " + " | ".join(cells) + " |"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sequences", nargs="*", help="names among " + ", ".join(s for s, _ in SEQUENCES))
    ap.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "swarmpose"))
    ap.add_argument("--data", default=os.environ.get("SWARMPOSE_DATA",
                                                     os.path.join(ROOT, "..", "shared", "data")))
    ap.add_argument("--out", default="/tmp/swarmpose-nees",
                    help="output directory of the runs")
    ap.add_argument("--reuse", action="store_true",
                    help="read the outputs already in --out instead of running")
    ap.add_argument("--update", metavar="FILE",
                    help="write the table as the generated section --name of FILE")
    ap.add_argument("--name", default="covariance-nees",
                    help="the generated section's name (with --update)")
    a = ap.parse_args()
    chosen = [s for s in SEQUENCES if not a.sequences or s[0] in a.sequences]
    unknown = set(a.sequences) - {s for s, _ in SEQUENCES}
    if unknown:
        sys.exit(f"nees.py: unknown sequence(s) {', '.join(sorted(unknown))}")
    lines = []
    if a.reuse:
        lines.append(f"Runs read from {a.out} (made earlier: their binary's commit is not "
                     f"recorded; this tree: {commit()}); {machine()}.\n")
    else:
        lines.append(f"Commit {commit()}; {machine()}; `python3 tools/covariance/nees.py`.\n")
    lines.append("| sequence | mode | truth | motions | mean NEES | median NEES | claimed sd, mm "
                 "| claimed sd, mdeg | split frames | split mean NEES | split median NEES "
                 "| split mean NEES, model alone |")
    lines.append("|---|---|---|---:|---:|---:|---|---|---:|---:|---:|---:|")
    notes = []
    for name, truths in chosen:
        seq_dir = None if name == "synthetic" else os.path.join(a.data, name)
        if seq_dir and not os.path.isdir(seq_dir):
            print(f"nees.py: {seq_dir} absent, skipped", file=sys.stderr)
            continue
        for label, extra in MODES:
            out = os.path.join(a.out, f"{name}-{'f2f' if extra else 'window'}")
            if not a.reuse:
                run(a.binary, seq_dir, out, extra)
            s = split_figures(out)
            for truth in truths:
                lines.append(row(name, label, truth,
                                 covariance_figures(out, truth) if truth else None, s))
            if "zero" in truths:
                corr = motion_correlation(out)
                if corr:
                    notes.append(f"{name}, {label}: correlation of the measured motions with the "
                                 "ground truth's, nu x y z, omega x y z: "
                                 + ", ".join(f"{c:.2f}" for c in corr))
    for n in notes:
        lines.append(f"\n{n}")
    text = "\n".join(lines) + "\n"
    if a.update:
        command = " ".join(["python3 tools/covariance/nees.py", *sys.argv[1:]])
        publish(a.update, a.name, command, text)
    else:
        print(text, end="")


if __name__ == "__main__":
    main()
