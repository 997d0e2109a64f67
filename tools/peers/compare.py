#!/usr/bin/env python3
"""Runs swarmpose's odometry and the OpenCV peer (opencv_vo.py) on the shared sequences,
one after the other in the same run, and prints one Markdown table.

KITTI and EuRoC are scored by `swarmpose evaluate --json` on both pipelines' KITTI-format
trajectories against the ground truth swarmpose writes (the same code for both). Karlsruhe
has only rough INS positions of the vehicle: the camera positions are aligned onto them
by an SE(3) Umeyama fit and the ATE and final error are reported as a share of the INS
path, as `swarmpose odometry` prints them (the same formula, re-implemented here with
numpy for the peer and checked against swarmpose's line for swarmpose).

    python3 tools/peers/compare.py [--data DIR] [--out DIR] [--swarmpose BIN]
"""

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SEQUENCES = ["kitti_vo_seq2", "karlsruhe_2010_03_09_drive_0023", "euroc_v1_01_easy_micro"]


def kitti_positions(path):
    a = np.loadtxt(path, ndmin=2)
    return a[:, [3, 7, 11]]


def umeyama_se3(x, y):
    """R, t minimising sum |y - (R x + t)|^2 (no scale)."""
    mx, my = x.mean(0), y.mean(0)
    cov = (y - my).T @ (x - mx) / len(x)
    u, _, vt = np.linalg.svd(cov)
    s = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        s[2, 2] = -1
    r = u @ s @ vt
    return r, my - r @ mx


def ins_errors(traj, seq_dir):
    """Per-frame position errors (metres) of TRAJ's cameras after an SE(3) alignment onto
    the Karlsruhe INS positions, and the INS path length (metres)."""
    ins_file = [os.path.join(seq_dir, d, "insdata.txt") for d in os.listdir(seq_dir)
                if d.endswith("_Images")][0]
    y = np.loadtxt(ins_file)[:, 4:7]
    x = kitti_positions(traj)
    r, t = umeyama_se3(x, y)
    return np.linalg.norm(y - (x @ r.T + t), axis=1), np.linalg.norm(np.diff(y, axis=0), axis=1).sum()


def ins_metrics(traj, seq_dir):
    err, length = ins_errors(traj, seq_dir)
    return 100 * np.sqrt((err ** 2).mean()) / length, 100 * err[-1] / length, np.sqrt((err ** 2).mean())


def evaluate(swarmpose, est, gt):
    out = subprocess.run([swarmpose, "evaluate", est, gt, "--json"], capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    root = os.path.dirname(os.path.dirname(HERE))
    p.add_argument("--data", default=os.environ.get("SWARMPOSE_DATA", os.path.join(root, "..", "shared", "data")))
    p.add_argument("--out", default="/tmp/swarmpose-peers")
    p.add_argument("--swarmpose", default=os.path.join(root, "target", "release", "swarmpose"))
    a = p.parse_args()
    rows = []
    for name in SEQUENCES:
        seq = os.path.join(a.data, name)
        if not os.path.isdir(seq):
            print(f"skipped {name}: {seq} not found", file=sys.stderr)
            continue
        ours = os.path.join(a.out, name, "swarmpose")
        peer = os.path.join(a.out, name, "opencv")
        t = time.perf_counter()
        log = subprocess.run([a.swarmpose, "odometry", seq, "--out", ours, "--quiet"],
                             capture_output=True, text=True)
        ours_s = time.perf_counter() - t
        if log.returncode not in (0, 3):
            sys.exit(f"swarmpose odometry failed on {name}: {log.stderr}")
        t = time.perf_counter()
        info = json.loads(subprocess.run([sys.executable, os.path.join(HERE, "opencv_vo.py"), seq, peer],
                                         capture_output=True, text=True, check=True).stdout)
        peer_s = time.perf_counter() - t
        n = info["frames"]
        for label, d, secs, fallbacks in (("swarmpose (default)", ours, ours_s, None),
                                          ("OpenCV PnP peer", peer, peer_s, info["fallbacks"])):
            traj = os.path.join(d, "trajectory.kitti.txt")
            row = {"sequence": name, "pipeline": label, "fps": n / secs}
            gt = os.path.join(ours, "groundtruth.kitti.txt")
            if os.path.exists(gt):
                e = evaluate(a.swarmpose, traj, gt)
                row.update(drift=e["final_drift_percent"], final_m=e["final_drift_m"],
                           eq20=e["eq20_rms"], ate=e["ate_aligned"]["rmse"])
            else:
                ate_pct, final_pct, ate_m = ins_metrics(traj, seq)
                row.update(ins_ate_pct=ate_pct, ins_final_pct=final_pct, ate=ate_m)
            if fallbacks is not None:
                row["fallbacks"] = fallbacks
            rows.append(row)
    print("| sequence | pipeline | final drift | RMS eq. (20) | ATE aligned | frames/s (whole run) |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        if "ins_ate_pct" in r:
            drift = f"{r['ins_final_pct']:.2f} % (final, vs INS)"
            eq20 = "n/a"
            ate = f"{r['ate']:.3f} m = {r['ins_ate_pct']:.2f} % (vs INS)"
        else:
            drift = f"{r['drift']:.3f} %" if r["drift"] is not None else f"{1e3 * r['final_m']:.1f} mm"
            eq20 = f"{r['eq20']:.5f}"
            ate = f"{r['ate']:.3f} m"
        print(f"| {r['sequence']} | {r['pipeline']} | {drift} | {eq20} | {ate} | {r['fps']:.1f} |")


if __name__ == "__main__":
    main()
