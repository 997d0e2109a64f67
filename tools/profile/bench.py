#!/usr/bin/env python3
"""The pipeline bench (`crates/swarmpose-runs/benches/pipeline.rs`, group `odometry`) on
the shared KITTI clip, as one Markdown section: criterion's median and interval of each
mode, in frames per second, the per-frame latency and the stage split the bench's first
pass prints, the CPU time of the whole run, with the commit, the machine and its load.

    python3 tools/profile/bench.py [--data DIR] [--reuse LOG] [--update FILE]

--reuse LOG: read the criterion results already in the target folder and the bench's
output kept in LOG (written by an earlier run, `pipeline_bench.log` in the target folder)
instead of running the bench.
"""

import argparse
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "generated"))
from generated import provenance, publish  # noqa: E402

NAME = "pipeline-bench"
COMMAND = "python3 tools/profile/bench.py --update crates/swarmpose-odometry/RESULTS.md"
FRAMES = 51  # kitti_vo_seq2
MODES = [
    ("kitti_vo_seq2/load+engine", "one thread, default (window of 10), loading included"),
    ("kitti_vo_seq2/engine", "one thread, default, images already in memory"),
    ("kitti_vo_seq2/load+engine, two threads", "two threads, default, loading included"),
    ("kitti_vo_seq2/load+engine, frame to frame", "one thread, frame to frame, loading included"),
    ("kitti_vo_seq2/load+engine, frame to frame, two threads",
     "two threads, frame to frame, loading included"),
]


def target_dir():
    meta = json.loads(subprocess.run(["cargo", "metadata", "--format-version", "1", "--no-deps"],
                                     cwd=ROOT, capture_output=True, text=True, check=True).stdout)
    return meta["target_directory"]


def run_bench(data, log):
    """Runs the bench's `odometry` group; keeps its output in LOG; returns the CPU
    seconds (user, system) and wall seconds of the run, build excluded."""
    env = dict(os.environ, SWARMPOSE_DATA=data)
    subprocess.run(["cargo", "bench", "-p", "swarmpose-runs", "--bench", "pipeline", "--no-run"],
                   cwd=ROOT, env=env, check=True)
    start = "LOAD-AT-START " + " / ".join(f"{v:.1f}" for v in os.getloadavg())
    p = subprocess.run(["/usr/bin/time", "-f", "CPU %U %S %e", "cargo", "bench", "-p",
                        "swarmpose-runs", "--bench", "pipeline", "--", "odometry/"],
                       cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    text = start + "\n" + p.stdout + p.stderr
    with open(log, "w", encoding="utf-8") as f:
        f.write(text)
    return text


def estimates(target):
    """criterion's median and its interval (seconds) per benchmark title."""
    root = os.path.join(target, "criterion", "odometry")
    found = {}
    for d in os.listdir(root) if os.path.isdir(root) else []:
        bench = os.path.join(root, d, "new", "benchmark.json")
        est = os.path.join(root, d, "new", "estimates.json")
        if not (os.path.exists(bench) and os.path.exists(est)):
            continue
        with open(bench, encoding="utf-8") as f:
            fid = json.load(f)["function_id"]
        with open(est, encoding="utf-8") as f:
            m = json.load(f)["median"]
        found[fid] = (m["point_estimate"] * 1e-9, m["confidence_interval"]["lower_bound"] * 1e-9,
                      m["confidence_interval"]["upper_bound"] * 1e-9)
    return found


def section(log, found):
    out = [f"Generated {provenance()}.", "",
           "`cargo bench -p swarmpose-runs --bench pipeline -- odometry/`, release build, 10 samples "
           f"of the whole {FRAMES}-frame kitti_vo_seq2 each (frames/s = {FRAMES} / median). The "
           "machine's load is the line above: with a load above 1 another process shared the "
           "two cores, and the figures are lower than a quiet machine's (the two-thread modes "
           "most).", "",
           "| mode | time for 51 frames (criterion median, interval) | frames/s |", "|---|---|---|"]
    for fid, label in MODES:
        if fid in found:
            med, lo, hi = found[fid]
            out.append(f"| {label} | {med:.3f} s ({lo:.3f}-{hi:.3f}) | {FRAMES / med:.1f} |")
    start = re.findall(r"^LOAD-AT-START (.*)$", log, re.M)
    if start:
        out[0] = out[0].rstrip(".") + f" (at the start of the bench: {start[0]})."
    cpu = re.findall(r"^CPU ([\d.]+) ([\d.]+) ([\d.]+)$", log, re.M)
    lines = [l.strip() for l in log.splitlines() if "kitti_vo_seq2, orb + pso" in l]
    if lines:
        out += ["", "The bench's first pass (one thread, images in memory, per frame):", ""]
        out += [f"    {l}" for l in lines]
    if cpu:
        user, system, wall = (float(v) for v in cpu[-1])
        out += ["", f"The bench's run: {user:.1f} s user and {system:.1f} s system CPU time in "
                f"{wall:.1f} s wall (the two-thread modes use both cores)."]
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=os.environ.get("SWARMPOSE_DATA",
                                                     os.path.join(ROOT, "..", "shared", "data")),
                    help="the shared data root [$SWARMPOSE_DATA or ../shared/data]")
    ap.add_argument("--reuse", metavar="LOG", help="use the results of an earlier run")
    ap.add_argument("--update", metavar="FILE", help="write the section into FILE")
    args = ap.parse_args()
    target = target_dir()
    if args.reuse:
        with open(args.reuse, encoding="utf-8") as f:
            log = f.read()
    else:
        log = run_bench(args.data, os.path.join(target, "pipeline_bench.log"))
    found = estimates(target)
    if not found:
        raise SystemExit(f"no criterion result under {target}/criterion/odometry")
    publish(args.update, NAME, COMMAND, section(log, found))


if __name__ == "__main__":
    main()
