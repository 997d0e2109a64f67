#!/usr/bin/env python3
"""The split-feature NEES of the rendered synthetic street over other draws of its textures
(and other paths): runs the example `street_split_nees` of swarmpose-runs once per given
path and prints its tables (or writes them as a generated section of a Markdown file), so
that the built-in street's figure (one 19-pair mean) can be told from the sampling noise
of a short mean.

    cargo build --release -p swarmpose-runs --example street_split_nees
    python3 tools/covariance/street.py [--seeds 0..40] [--path 20,0.6,1 ...] \
        [--update crates/swarmpose-odometry/RESULTS.md --name NAME]

A path is FRAMES,METRES,DEGREES (per frame); the default is the built-in street's
(20 frames, 0.6 m and 1 degree to the right per frame). Standard library only.
"""

import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "generated"))
from generated import provenance, publish  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "examples",
                                                     "street_split_nees"),
                    help="the example's binary [target/release/examples/street_split_nees]")
    ap.add_argument("--seeds", default="0..40", help="texture seeds A..B (B excluded) [0..40]")
    ap.add_argument("--path", action="append", metavar="FRAMES,METRES,DEGREES",
                    help="a path of the street (repeatable) [20,0.6,1: the built-in street's]")
    ap.add_argument("--update", metavar="FILE",
                    help="write the tables as the generated section --name of FILE")
    ap.add_argument("--name", default="covariance-street", help="the section's name")
    a = ap.parse_args()
    if not os.path.isfile(a.binary):
        sys.exit(f"street.py: {a.binary} not found (cargo build --release -p swarmpose-runs "
                 "--example street_split_nees)")
    parts = [f"Texture seeds {a.seeds} of each path; {provenance()}."]
    for path in a.path or ["20,0.6,1"]:
        try:
            frames, step, yaw = path.split(",")
            int(frames), float(step), float(yaw)
        except ValueError:
            sys.exit(f"street.py: --path {path}: FRAMES,METRES,DEGREES expected")
        cmd = [a.binary, "--seeds", a.seeds, "--frames", frames, "--step", step, "--yaw", yaw]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"street.py: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()}")
        parts.append(p.stdout.strip())
    command = " ".join(["python3 tools/covariance/street.py", *sys.argv[1:]])
    publish(a.update, a.name, command, "\n\n".join(parts) + "\n")


if __name__ == "__main__":
    main()
