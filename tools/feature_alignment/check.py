#!/usr/bin/env python3
"""The Python extension's dependencies resolve to the test build's features.

`.ci/run` builds the test suite (`cargo test --workspace`) and then the Python wheel
(maturin, `-p swarmpose-py` in the dev profile) into the same target folder. Cargo
resolves features per build: `--workspace` with dev-dependencies unifies the features
every member and test asks for, while `-p swarmpose-py` sees only the extension's own
graph. A dependency resolved with fewer features is a different artifact, and every crate
above it is compiled again: before this check, 60 crates (nearly 4 minutes of a CI run).

swarmpose-py's Cargo.toml therefore names the few dependencies whose features differ,
with the workspace's features (its "feature alignment" block). This script fails when
that block is out of date: each package of the extension's graph, with its features,
must be one the workspace build compiles. It compares `cargo tree` listings twice: the
target side alone (normal edges without proc macros and build scripts), and every edge
(the compile-time side: proc macros and build scripts, whose features cargo resolves
separately).

Usage: python3 tools/feature_alignment/check.py   (exit 0: aligned; 1: the packages to
add to the block are listed, with the features the workspace build gives them)."""

import subprocess
import sys


def tree(selection, edges):
    run = subprocess.run(
        ["cargo", "tree", "--locked", *selection, "-e", edges, "--prefix", "none",
         "-f", "{p} [{f}]"],
        capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"feature alignment: cargo tree failed: {run.stderr.strip()}")
    out = run.stdout
    return {line.replace(" (*)", "").strip() for line in out.splitlines() if line.strip()}


def main():
    missing = []
    for side, ws_edges, py_edges in [
        ("target", "normal,dev,no-proc-macro", "normal,no-proc-macro"),
        ("compile-time and target", "normal,build,dev", "normal,build"),
    ]:
        workspace = tree(["--workspace"], ws_edges)
        extension = tree(["-p", "swarmpose-py"], py_edges)
        for line in sorted(extension - workspace):
            name = line.split(" ")[0]
            built = sorted(w for w in workspace if w.split(" ")[0] == name)
            missing.append(f"{side}: {line}; the workspace build has: {'; '.join(built)}")
    if missing:
        print("swarmpose-py's dependencies resolve to features the test build does not "
              "compile, so the wheel would compile them and everything above them again. "
              "Add them, with the workspace's features, to the feature alignment block of "
              "crates/swarmpose-py/Cargo.toml:", file=sys.stderr)
        for m in missing:
            print(f"  {m}", file=sys.stderr)
        return 1
    print("feature alignment: the Python extension's dependencies match the test build's")
    return 0


if __name__ == "__main__":
    sys.exit(main())
