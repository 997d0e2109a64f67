#!/usr/bin/env python3
"""The KITTI 00 segment errors of ORB-SLAM2 and S-PTAM (../shared/data/trajectories), as
`swarmpose evaluate --kitti-segments` gives them, checked against this folder's numpy
implementation, as one Markdown section: printed, or written into a RESULTS file with
`--update FILE` (between the section's markers; see tools/generated).

    python3 tools/kitti_segments/results.py [--data DIR] [--swarmpose BIN] [--update FILE]
"""

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "generated"))
from generated import common_arguments, provenance, publish  # noqa: E402

import kitti_segments  # noqa: E402  (this folder: the independent implementation)

COMMAND = "python3 tools/kitti_segments/results.py --update crates/swarmpose-odometry/RESULTS.md"
SYSTEMS = (("ORB-SLAM2", "KITTI_00_ORB.txt"), ("S-PTAM", "KITTI_00_SPTAM.txt"))
KEYS = ("translation_percent", "rotation_deg_per_100m")


def swarmpose_segments(binary, est, gt):
    out = subprocess.run([binary, "evaluate", est, gt, "--format", "kitti", "--kitti-segments",
                          "--json"], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"swarmpose evaluate failed on {est}: {out.stderr.strip()}")
    return json.loads(out.stdout)


def largest_difference(a, b):
    rows = list(zip(a["per_length"], b["per_length"], strict=True)) + [(a, b)]
    rows += list(zip(a["segments"], b["segments"], strict=True))
    return max(abs(x[k] - y[k]) for x, y in rows for k in KEYS)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    common_arguments(p)
    a = p.parse_args()
    d = os.path.join(a.data, "trajectories")
    gt = os.path.join(d, "KITTI_00_gt.txt")
    results, worst = [], 0.0
    for name, f in SYSTEMS:
        est = os.path.join(d, f)
        ours = swarmpose_segments(a.swarmpose, est, gt)
        worst = max(worst, largest_difference(ours, kitti_segments.evaluate(est, gt)))
        results.append((name, ours))
    poses = kitti_segments.read_kitti(gt)
    path_m = kitti_segments.trajectory_distances(poses)[-1]
    if worst > 1e-6:
        sys.exit(f"swarmpose and the numpy implementation differ by {worst:.2e} (> 1e-6)")
    lines = [
        f"KITTI odometry sequence 00 ({len(poses)} frames, {path_m / 1000:.2f} km): the KITTI devkit's "
        "segment errors of the "
        "ORB-SLAM2 and S-PTAM estimates published with evo (`../shared/data/trajectories`), by "
        "`swarmpose evaluate EST KITTI_00_gt.txt --kitti-segments`; translation error in % of the "
        "segment length, rotation error in degrees per 100 m, segments starting every 10 frames. "
        f"The numpy implementation of `tools/kitti_segments` gives the same segments and figures "
        f"within {worst:.1e} (generated {provenance()}).",
        "",
        "| segment length | segments | " + " | ".join(f"{n} translation | {n} rotation" for n, _ in results) + " |",
        "|---|---|" + "---|---|" * len(results),
    ]
    first = results[0][1]
    for i, row in enumerate(first["per_length"]):
        cells = " | ".join(f"{r['per_length'][i]['translation_percent']:.3f} % | "
                           f"{r['per_length'][i]['rotation_deg_per_100m']:.4f} deg/100 m" for _, r in results)
        lines.append(f"| {row['length_m']:.0f} m | {row['n']} | {cells} |")
    cells = " | ".join(f"**{r['translation_percent']:.3f} %** | **{r['rotation_deg_per_100m']:.4f} deg/100 m**"
                       for _, r in results)
    lines.append(f"| all | {len(first['segments'])} | {cells} |")
    text = "\n".join(lines) + "\n"
    publish(a.update, "kitti-segments", COMMAND, text)


if __name__ == "__main__":
    main()
