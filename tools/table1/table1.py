#!/usr/bin/env python3
"""Table I of crates/swarmpose-odometry/RESULTS.md: every estimator on every shared real
sequence, with the reprojection refinement (the pipeline) and without it (the estimator
alone), and the calibration choices side by side. Every number comes from
`swarmpose odometry` (it evaluates against the ground truth and prints the summary).

    cargo build --release -p swarmpose-cli
    python3 tools/table1/table1.py [--data DIR] [--out DIR] > table1.md
"""

import argparse
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SEQUENCES = ["kitti_vo_seq2", "euroc_v1_01_easy_micro", "karlsruhe_2010_03_09_drive_0023"]
METHODS = [
    ("PSO/SVD (pso-paper, δ = 0.1 m)", ["--method", "pso-paper"]),
    ("PSO/SVD (pso-paper, δ = 0.3 m)", ["--method", "pso-paper", "--threshold", "0.3"]),
    ("MSAC", ["--method", "msac"]),
    ("SVD", ["--method", "svd"]),
    ("robust PSO (default)", []),
]
VARIANTS = [
    ("default (window of 10, calibration principal-point+yaw+focal)", []),
    ("no correction (--calibrate none)", ["--calibrate", "none"]),
    ("constant only (--calibrate principal-point)", ["--calibrate", "principal-point"]),
    ("no right-camera focal (--calibrate principal-point+yaw)",
     ["--calibrate", "principal-point+yaw"]),
    ("roll and pitch too", ["--calibrate", "principal-point+yaw+focal+roll+pitch"]),
    ("evidence memory 0.5 s (--calibration-memory 0.5)", ["--calibration-memory", "0.5"]),
    ("evidence memory 3 s", ["--calibration-memory", "3"]),
    ("all evidence kept (--calibration-memory inf)", ["--calibration-memory", "inf"]),
    ("SURF front end", ["--detector", "surf"]),
    ("frame to frame, no window (--window 0)", ["--window", "0"]),
    ("window of 20 keyframes (--window 20)", ["--window", "20"]),
]


def run(binary, seq, out, extra):
    p = subprocess.run([binary, "odometry", seq, "--out", out, "--quiet", *extra],
                       capture_output=True, text=True)
    text = p.stdout
    r = {"exit": p.returncode, "stderr": p.stderr.strip()}
    m = re.search(r"(\d+) of (\d+) motions tracked, (\d+) at constant velocity, (\d+) lost", text)
    if m:
        r["untracked"] = int(m.group(2)) - int(m.group(1))
    m = re.search(r"final drift ([\d.]+) m \(([^)]*)\), RMS eq\. \(20\) ([\d.]+), ATE [\d.]+ m raw / ([\d.]+) m aligned", text)
    if m:
        r.update(final_m=float(m.group(1)), drift=m.group(2), eq20=float(m.group(3)), ate=float(m.group(4)))
    m = re.search(r"ATE ([\d.]+) m \(([\d.]+) % of the path\), final position error ([\d.]+) m \(([\d.]+) %\)", text)
    if m:
        r.update(ins_ate_m=float(m.group(1)), ins_ate=float(m.group(2)), ins_final=float(m.group(4)))
    m = re.search(r"disparity correction: (.*?) \(([^;]*);", text)
    if m:
        r.update(correction=m.group(1), model=m.group(2))
    m = re.search(r"\(([\d.]+) frames/s\)", text)
    if m:
        r["fps"] = float(m.group(1))
    return r


def cell(r):
    if r.get("exit") not in (0, 3):
        return "failed: " + r.get("stderr", "")[:80]
    if "ins_ate" in r:
        return f"{r['ins_ate']:.2f} % ({r['ins_ate_m']:.3f} m) | {r['ins_final']:.2f} %"
    drift = r.get("drift", "n/a")
    if drift == "n/a":
        drift = f"{1e3 * r['final_m']:.1f} mm"
    return f"{r['eq20']:.5f} | {drift} | {r['ate']:.3f} m"


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", default=os.environ.get("SWARMPOSE_DATA", os.path.join(ROOT, "..", "shared", "data")))
    p.add_argument("--out", default="/tmp/swarmpose-table1")
    p.add_argument("--swarmpose", default=os.path.join(ROOT, "target", "release", "swarmpose"))
    a = p.parse_args()
    for name in SEQUENCES:
        seq = os.path.join(a.data, name)
        if not os.path.isdir(seq):
            print(f"skipped {name}: not found", file=sys.stderr)
            continue
        ins = name.startswith("karlsruhe")
        head = "ATE vs INS | final error" if ins else "RMS eq. (20) | final drift | ATE aligned"
        print(f"\n### {name}\n")
        cols = head.count("|") + 1
        print(f"| method | pipeline: {head} | untracked | estimator alone: {head} |")
        print("|---" * (2 + 2 * cols) + "|")
        for label, extra in METHODS:
            tag = label.split(" ")[0]
            full = run(a.swarmpose, seq, os.path.join(a.out, name, tag), extra)
            alone = run(a.swarmpose, seq, os.path.join(a.out, name, tag + "-alone"), extra + ["--no-refine"])
            print(f"| {label} | {cell(full)} | {full.get('untracked', 'n/a')} | {cell(alone)} |")
        print(f"\n| robust PSO, pipeline | {head} | untracked | correction | frames/s |")
        print("|---" * (4 + cols) + "|")
        for label, extra in VARIANTS:
            r = run(a.swarmpose, seq, os.path.join(a.out, name, "variant"), extra)
            print(f"| {label} | {cell(r)} | {r.get('untracked', 'n/a')} | {r.get('correction', '?')} ({r.get('model', '?')}) | {r.get('fps', 0):.1f} |")


if __name__ == "__main__":
    main()
