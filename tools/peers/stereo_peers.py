#!/usr/bin/env python3
"""Peers and swarmpose side by side on the stereo-noise scenes, in one run.

The scenes come from swarmpose-sim's StereoSpec (street, 600 correspondences, 90 / 95 /
97 % wrong matches onto other scene points, seeds 1000 onwards), exported in the peers'
suite format by

    cargo run --release -p swarmpose-sim --example export_stereo -- DIR [RUNS] [FIRST_SEED]

(DIR/plain: coordinates only, what the peers read; DIR/cov: the same with covariance
columns). This script runs the peers of ../shared/peers/run_peers.py (same calls, same
timer around the estimation call only) at each threshold of --thresholds (stereo noise
has no single sigma, so each peer is shown at every threshold tried), then
`swarmpose bench` on DIR/plain (pso-auto: plain coordinates) and on DIR/cov (pso-auto with
the covariances, and oracle-weighted, the ceiling), and prints one Markdown table:
success / runs and median milliseconds per outlier fraction. Success: rotation error
< 2 deg and translation error < 0.2 m, as everywhere.
"""
import argparse
import csv
import glob
import json
import math
import os
import statistics
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
DEFAULT_PEERS = os.path.join(
    os.environ.get("SWARMPOSE_DATA", os.path.join(REPO, "..", "shared", "data")), "..", "peers"
)


def fractions_of(rows):
    return sorted({r["fraction"] for r in rows})


def run_peers(suite, methods, thresholds, max_runs, rp):
    rows = []
    files = sorted(glob.glob(os.path.join(suite, "plain", "*.csv")))
    for path in files:
        run = int(os.path.basename(path)[:-4].split("_r")[-1])
        src, dst, tr = rp.load(path)
        R_true = rp.quat_wxyz_to_R(tr["rotation_wxyz"])
        t_true = np.array(tr["translation"])
        for name in methods:
            limit = max_runs.get(name)
            if limit is not None and run >= limit:
                continue
            for thr in thresholds:
                try:
                    R, t, dt = rp.METHODS[name](src, dst, thr, tr["seed"])
                except Exception as e:  # a misbehaving peer must not stop the run
                    print(f"{name} {path}: {type(e).__name__}: {e}", file=sys.stderr)
                    R, t, dt = None, None, math.nan
                rot, trans, _ = rp.errors(R, t, R_true, t_true)
                rows.append({
                    "method": f"{name} (threshold {thr:g} m)",
                    "fraction": tr["outlier_fraction"],
                    "success": rot < rp.SUCCESS_ROT_DEG and trans < rp.SUCCESS_TRANS_M,
                    "ms": dt * 1e3,
                })
        print(f"[{time.strftime('%H:%M:%S')}] {os.path.basename(path)}", file=sys.stderr, flush=True)
    return rows


def run_ours(binary, suite, sub, methods, label):
    out = os.path.join(suite, f"runs_{sub}.csv")
    subprocess.run(
        [binary, "bench", os.path.join(suite, sub), "--methods", ",".join(methods), "--runs-csv", out],
        check=True, stdout=subprocess.DEVNULL,
    )
    rows = []
    with open(out) as f:
        for r in csv.DictReader(f):
            with open(os.path.join(suite, sub, r["scenario"] + ".json")) as t:
                fraction = json.load(t)["outlier_fraction"]
            rows.append({
                "method": f"`{r['method']}`{label}",
                "fraction": fraction,
                "success": r["success"] == "1",
                "ms": float(r["time_ms"]),
            })
    return rows


def table(rows):
    fr = fractions_of(rows)
    lines = [
        "| success / runs (median ms) | " + " | ".join(f"{f:.0%} outliers" for f in fr) + " |",
        "|---|" + "---|" * len(fr),
    ]
    for m in dict.fromkeys(r["method"] for r in rows):
        cells = []
        for f in fr:
            rs = [r for r in rows if r["method"] == m and r["fraction"] == f]
            if not rs:
                cells.append("")
                continue
            ok = sum(r["success"] for r in rs)
            ms = statistics.median(r["ms"] for r in rs)
            cells.append(f"{ok} / {len(rs)} ({ms:.3g})")
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("suite", help="folder written by the export_stereo example (plain/ and cov/)")
    ap.add_argument("--peers", default=DEFAULT_PEERS, help="folder of run_peers.py")
    ap.add_argument("--swarmpose", default=os.path.join(REPO, "target", "release", "swarmpose"))
    ap.add_argument("--methods", nargs="*",
                    default=["magsacpp", "gcransac", "cv2_affine3d_ransac+refit", "o3d_ransac_default"])
    ap.add_argument("--thresholds", nargs="*", type=float, default=[0.3, 1.0])
    ap.add_argument("--max-runs", action="append", default=[],
                    help="METHOD:RUNS: only runs below RUNS for METHOD (repeatable; slow peers)")
    args = ap.parse_args()
    sys.path.insert(0, os.path.abspath(args.peers))
    import run_peers as rp  # noqa: E402

    max_runs = {}
    for c in args.max_runs:
        m, n = c.rsplit(":", 1)
        max_runs[m] = int(n)
    started = time.time()
    load = os.getloadavg()
    rows = run_ours(args.swarmpose, args.suite, "plain", ["pso-auto"], ", plain coordinates")
    rows += run_ours(args.swarmpose, args.suite, "cov", ["pso-auto", "oracle-weighted"], ", covariances")
    rows += run_peers(args.suite, args.methods, args.thresholds, max_runs, rp)
    print(table(rows))
    end_load = os.getloadavg()
    print(f"\n{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {time.time() - started:.0f} s; "
          f"load average {load[0]:.2f} at the start, {end_load[0]:.2f} at the end "
          f"({os.cpu_count()} cores)")


if __name__ == "__main__":
    main()
