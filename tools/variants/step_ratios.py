#!/usr/bin/env python3
"""Per-frame step lengths of the online poses against the smoothed trajectory and the ground
truth, and where the self-calibration changed its model.

A robot reads the online pose (`trajectory.kitti.txt`), not the window's smoothed one
(`trajectory.smoothed.kitti.txt`). For every frame i >= 1 this prints the online step length
|t_i - t_(i-1)| divided by the smoothed trajectory's and by the ground truth's (when the run
folder has `groundtruth.kitti.txt`), minus one, in percent, and marks the frames whose
correction model (frames.csv) differs from the previous frame's or the next one's. One
Markdown row per run gives the worst cases at the frames where the model changed and at the
other frames, so that what a calibration switch adds can be told from the window's own
online-against-smoothed differences. Standard library only.

    swarmpose odometry ../shared/data/kitti_vo_seq2 --out /tmp/run
    python3 tools/variants/step_ratios.py /tmp/run [more run folders...] [--frames]

Steps shorter than 1 % of the median step are left out: their ratio says nothing. On a still
camera (the EuRoC clip) every step is millimetres of noise and the ratios mean nothing.
"""

import argparse
import csv
import math
import os
import statistics


def positions(path):
    out = []
    with open(path) as f:
        for line in f:
            v = line.split()
            if len(v) == 12:
                out.append((float(v[3]), float(v[7]), float(v[11])))
    return out


def steps(p):
    return [math.dist(p[i], p[i - 1]) for i in range(1, len(p))]


def models(run):
    with open(os.path.join(run, "frames.csv")) as f:
        return [r["correction_model"] for r in csv.DictReader(f)]


def ratios(run):
    """Per frame i >= 1: (i, model changed, online/smoothed - 1, online/gt - 1) in %."""
    online = steps(positions(os.path.join(run, "trajectory.kitti.txt")))
    smoothed = steps(positions(os.path.join(run, "trajectory.smoothed.kitti.txt")))
    gt_path = os.path.join(run, "groundtruth.kitti.txt")
    gt = steps(positions(gt_path)) if os.path.exists(gt_path) else None
    m = models(run)
    floor = 0.01 * statistics.median(online) if online else 0.0
    rows = []
    for i in range(1, len(online) + 1):
        s = online[i - 1]
        if s <= floor or smoothed[i - 1] <= floor:
            continue
        changed = m[i] != m[i - 1] or (i + 1 < len(m) and m[i] != m[i + 1])
        r_sm = 100.0 * (s / smoothed[i - 1] - 1.0)
        r_gt = 100.0 * (s / gt[i - 1] - 1.0) if gt and gt[i - 1] > floor else None
        rows.append((i, changed, m[i], r_sm, r_gt))
    return rows


def worst(rows, col, changed=None):
    """Largest |ratio| in column `col`: over all frames (`changed` None), or over the frames
    where the model changed (True) or did not (False)."""
    v = [abs(r[col]) for r in rows if r[col] is not None and changed in (None, r[1])]
    return max(v) if v else None


def fmt(v):
    return "n/a" if v is None else f"{v:.2f} %"


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", nargs="+", help="output folders of `swarmpose odometry`")
    p.add_argument("--frames", action="store_true", help="print every frame too")
    a = p.parse_args()
    print("| run | frames at a model change | worst vs smoothed: at changes / elsewhere "
          "| worst vs ground truth: at changes / elsewhere |")
    print("|---|---|---|---|")
    for run in a.runs:
        rows = ratios(run)
        if a.frames:
            for i, changed, model, r_sm, r_gt in rows:
                print(f"  {i:4d} {'*' if changed else ' '} {model:32s} vs smoothed {r_sm:+7.2f} %"
                      f"  vs gt {fmt(r_gt) if r_gt is None else f'{r_gt:+7.2f} %'}")
        changes = sum(1 for r in rows if r[1])
        print(f"| {run} | {changes} | {fmt(worst(rows, 3, True))} / {fmt(worst(rows, 3, False))} "
              f"| {fmt(worst(rows, 4, True))} / {fmt(worst(rows, 4, False))} |")


if __name__ == "__main__":
    main()
