#!/usr/bin/env python3
"""The minimum supported Rust version (MSRV), checked without installing that toolchain.

The workspace declares `rust-version` (README: 1.89). Two things could break it:
- our own code using a newer standard-library API or language feature: clippy's
  `incompatible_msrv` lint (on by default, denied by `.ci/run`'s `-D warnings`) reads the
  declared `rust-version` and flags any std API stabilised after it;
- a dependency that needs a newer compiler: this script reads `cargo metadata` and fails
  when any package of the build (ours or a dependency, locked versions) declares a
  `rust-version` above the workspace's.

Usage: python3 tools/msrv/check.py   (exit 0: every package builds with the MSRV as far as
its own manifest says; 1: the offenders are listed)."""

import json
import subprocess
import sys


def version(text):
    return tuple(int(p) for p in text.split(".")[:3]) + (0,) * (3 - len(text.split(".")[:3]))


def main():
    meta = json.loads(subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--locked"],
        check=True, capture_output=True, text=True).stdout)
    ours = {p["id"]: p for p in meta["packages"] if p["id"] in meta["workspace_members"]}
    declared = {p.get("rust_version") for p in ours.values()}
    if len(declared) != 1 or None in declared:
        print(f"msrv: workspace members declare {sorted(map(str, declared))}: one rust-version expected")
        return 1
    msrv = declared.pop()
    used = {n["id"] for n in meta["resolve"]["nodes"]}
    too_new = sorted(
        (p["name"], p["version"], p["rust_version"])
        for p in meta["packages"]
        if p["id"] in used and p.get("rust_version") and version(p["rust_version"]) > version(msrv))
    for name, ver, rv in too_new:
        print(f"msrv: {name} {ver} needs Rust {rv}, above the workspace's {msrv}")
    if too_new:
        return 1
    print(f"msrv: every one of {len(used)} packages declares at most Rust {msrv} (or nothing)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
