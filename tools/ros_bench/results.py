#!/usr/bin/env python3
"""The speed of swarmpose's ROS 2 input and output (the criterion bench
`crates/swarmpose-ros/benches/bags.rs`) and what the bag support adds to the default
build (the crates only `swarmpose-ros` brings in, and their compile time), as one
Markdown section: printed, or written into a RESULTS file with `--update FILE` (between
the section's markers; see tools/generated).

    python3 tools/ros_bench/results.py [--data DIR] [--timings HTML] [--update FILE]

--timings: a `cargo build --timings` report (target/cargo-timings/cargo-timing.html) of a
build from an empty target directory, whose unit times give the compile time of the
crates the bag support adds; without it, that line is left out.

--build-cost: measures the CPU time (user + system, `/usr/bin/time`, children included)
that the bag support adds to a clean release build, in an empty target directory under
the system's temporary folder (removed after): first the workspace crates swarmpose-ros
depends on (and their dependencies), then swarmpose-ros (its own dependencies, and the
features it adds to shared ones, e.g. `image`'s JPEG decoder), then swarmpose-ros alone
again after touching it; the added cost is the second minus the third. Kept in
TARGET/ros_bench_build_cost.json and reused by later runs without the option.
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "generated"))
from generated import common_arguments, provenance, publish  # noqa: E402

COMMAND = "python3 tools/ros_bench/results.py --update crates/swarmpose-ros/RESULTS.md"
# The bench's frames per clip (benches/bags.rs, FRAMES).
FRAMES = 10
READ_MORE_TARGET = 0.05
# The runs on bags (benches/bags.rs, run/* and open/*): bench name, row label.
BAG_RUNS = (("bag_mcap", "MCAP, chunks uncompressed"), ("bag_mcap_zstd", "MCAP, zstd chunks"),
            ("bag_db3", "SQLite `.db3`"))
# The zstd bag read with no decompressed chunk kept but the last: a bag much longer than
# the chunk cache (swarmpose_ros::bag::DEFAULT_CHUNK_CACHE_BYTES).
LONG_RUN = ("bag_mcap_zstd_uncached", "MCAP, zstd chunks, a bag longer than the chunk cache")
CACHE_MIB = 64
# Stereo frames of the clip (two 1241 x 376 mono8 images) in the chunk cache.
CACHE_FRAMES = CACHE_MIB * 2**20 // (2 * 1241 * 376)
WRITE_TARGET_MS = 1.0


def bench(data):
    env = dict(os.environ, SWARMPOSE_DATA=data)
    subprocess.run(["cargo", "bench", "-p", "swarmpose-ros", "--bench", "bags"], cwd=ROOT,
                   env=env, check=True)


def median_ms(target, group, name):
    path = os.path.join(target, "criterion", group, name, "new", "estimates.json")
    with open(path, encoding="utf-8") as f:
        return json.load(f)["median"]["point_estimate"] * 1e-6


def crate_set(package):
    """The crates (name version) a package depends on in a normal build."""
    out = subprocess.run(["cargo", "tree", "-p", package, "-e", "normal,build", "--prefix", "none"],
                         cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return {" ".join(line.split()[:2]) for line in out.splitlines() if line.strip()}


def added_by_ros():
    """The crates only swarmpose-ros brings into the CLI's build."""
    meta = json.loads(subprocess.run(["cargo", "metadata", "--format-version", "1", "--no-deps"],
                                     cwd=ROOT, capture_output=True, text=True, check=True).stdout)
    cli = next(p for p in meta["packages"] if p["name"] == "swarmpose-cli")
    others = set()
    for dep in cli["dependencies"]:
        if dep["kind"] is None and dep["name"] != "swarmpose-ros":
            others |= crate_set(dep["name"])
    added = crate_set("swarmpose-ros") - others
    return sorted(c for c in added if not c.startswith("swarmpose-ros "))


def cli_crate_count():
    """The crates (name version, the workspace's own included) of the CLI's build."""
    return len(crate_set("swarmpose-cli"))


# The workspace crates swarmpose-ros depends on (Cargo.toml [dependencies]).
ROS_WORKSPACE_DEPS = ["swarmpose-vision", "swarmpose-datasets", "swarmpose-odometry"]


def cpu_seconds(args, env):
    """User + system CPU seconds of a command and its children, and its wall seconds
    (`/usr/bin/time`)."""
    out = subprocess.run(["/usr/bin/time", "-f", "CPU %U %S %e", *args], cwd=ROOT, env=env,
                         capture_output=True, text=True, check=True)
    line = [l for l in out.stderr.splitlines() if l.startswith("CPU ")][-1]
    user, system, wall = (float(x) for x in line.split()[1:4])
    return user + system, wall


def measure_build_cost(target):
    """The CPU seconds of the three clean release builds (see --build-cost)."""
    scratch = tempfile.mkdtemp(prefix="swarmpose-ros-build-cost-")
    env = dict(os.environ, CARGO_TARGET_DIR=scratch)
    try:
        base, base_wall = cpu_seconds(["cargo", "build", "--release", "--quiet",
                                       *(a for p in ROS_WORKSPACE_DEPS for a in ("-p", p))], env)
        with_ros, with_ros_wall = cpu_seconds(
            ["cargo", "build", "--release", "--quiet", "-p", "swarmpose-ros"], env)
        os.utime(os.path.join(ROOT, "crates", "swarmpose-ros", "src", "lib.rs"))
        ros_alone, ros_alone_wall = cpu_seconds(
            ["cargo", "build", "--release", "--quiet", "-p", "swarmpose-ros"], env)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    cost = {"base_s": base, "with_ros_s": with_ros, "ros_alone_s": ros_alone,
            "base_wall_s": base_wall, "with_ros_wall_s": with_ros_wall,
            "ros_alone_wall_s": ros_alone_wall,
            "load": " / ".join(f"{v:.1f}" for v in os.getloadavg())}
    with open(os.path.join(target, "ros_bench_build_cost.json"), "w", encoding="utf-8") as f:
        json.dump(cost, f)
    return cost


def compile_seconds(html, crates):
    """The summed unit times (seconds) of `crates` in a cargo timings report."""
    text = open(html, encoding="utf-8").read()
    units = json.loads(re.search(r"const UNIT_DATA = (\[.*?\]);", text, re.S).group(1))
    names = {c.split()[0].replace("-", "_") for c in crates}
    return sum(u["duration"] for u in units if u["name"].replace("-", "_") in names)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    common_arguments(parser)
    parser.add_argument("--target", default=os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")),
                        help="the cargo target directory [$CARGO_TARGET_DIR or target]")
    parser.add_argument("--timings", help="a cargo --timings report of a clean build")
    parser.add_argument("--no-run", action="store_true", help="use the bench's last results")
    parser.add_argument("--build-cost", action="store_true",
                        help="measure the CPU time of the bag support's clean build (minutes)")
    a = parser.parse_args()
    if not a.no_run:
        bench(a.data)
    cost_file = os.path.join(a.target, "ros_bench_build_cost.json")
    cost = measure_build_cost(a.target) if a.build_cost else None
    if cost is None and os.path.exists(cost_file):
        with open(cost_file, encoding="utf-8") as f:
            cost = json.load(f)
    m = lambda g, n: median_ms(a.target, g, n)  # noqa: E731
    # A run: open the input and read every frame once, in order (benches/bags.rs, run/*).
    folder = m("run", "folder") / FRAMES
    rows = [f"| folder (two PNGs) | {folder:.2f} | | |"]
    verdicts = []
    for name, label in BAG_RUNS:
        run, opened = m("run", name) / FRAMES, m("open", name) / FRAMES
        more = run / folder - 1.0
        rows.append(f"| {label} | {run:.2f} | {opened:.2f} | {100 * more:+.1f} % |")
        verdicts.append(more <= READ_MORE_TARGET)
    name, label = LONG_RUN
    long_run, long_open = m("run", name) / FRAMES, m("open", name) / FRAMES
    long_more = long_run / folder - 1.0
    rows.append(f"| {label} | {long_run:.2f} | {long_open:.2f} | {100 * long_more:+.1f} % |")
    write = m("write", "odometry_mcap_frame")
    added = added_by_ros()
    total = cli_crate_count()
    lines = [
        "Speed of the ROS 2 input and output (`cargo bench -p swarmpose-ros --bench bags`, "
        + ("medians, one thread, of an earlier run read with `--no-run` (its commit and load "
           f"are not recorded); this text generated {provenance()}; "
           if a.no_run else f"medians, one thread; generated {provenance()}; ")
        + "the machine was shared with other builds while it ran, so the times are not quiet).",
        "",
        f"Reading the first {FRAMES} KITTI frames (1241 x 376, `sensor_msgs/Image` mono8 with "
        "`camera_info`) as a run does: open the input, then read every stereo frame once, in "
        "order; the time divided by the frames:",
        "",
        "| from | open and read, ms a frame | of which opening | more than the folder |",
        "|---|---:|---:|---:|",
        *rows,
        "",
        f"Target: at most {100 * READ_MORE_TARGET:.0f} % more than the folder: "
        + ("met" if all(verdicts) else "NOT met") + " for the clip; for a zstd bag longer than "
        f"the chunk cache (its last row: {CACHE_MIB} MiB of decompressed chunks kept, {CACHE_FRAMES} of "
        "these frames; beyond them a chunk is decompressed at opening only up to its last header): "
        + ("met" if long_more <= READ_MORE_TARGET else "NOT met") + ". The opening and the whole run "
        "are separate medians: a bag whose chunks are all kept when it is opened reads its frames "
        "at next to no cost after, so the two are within the noise of each other.",
        "",
        f"Writing one frame of `odometry.mcap` without images: {write:.3f} ms "
        f"(target at most {WRITE_TARGET_MS:.0f} ms: {'met' if write <= WRITE_TARGET_MS else 'NOT met'}).",
        "",
        f"The bag support adds {len(added)} crates to the default build of the CLI "
        f"(`cargo tree -e normal,build`: {total} crates with it, the workspace's own included; "
        f"{total - len(added) - 1} without it and swarmpose-ros): "
        + ", ".join(f"`{c}`" for c in added) + ".",
    ]
    if cost:
        added_s = cost["with_ros_s"] - cost["ros_alone_s"]
        lines += [
            "",
            f"CPU time (user + system, `/usr/bin/time`) they add to a clean release build: {added_s:.0f} s "
            f"(building swarmpose-ros and what it brings after its workspace dependencies: "
            f"{cost['with_ros_s']:.0f} s, of which swarmpose-ros itself {cost['ros_alone_s']:.0f} s; "
            f"the workspace dependencies before: {cost['base_s']:.0f} s). Measured with `--build-cost` "
            f"while the machine was shared with other builds (load average {cost['load']}), one clean "
            "build each.",
        ]
        if "with_ros_wall_s" in cost:
            wall = cost["with_ros_wall_s"] - cost["ros_alone_wall_s"]
            lines.append(
                f"Wall time, secondary (2 cores shared with other builds, so it says more about the "
                f"load than the build): {wall:.0f} s added ({cost['with_ros_wall_s']:.0f} s with "
                f"swarmpose-ros itself, which took {cost['ros_alone_wall_s']:.0f} s; "
                f"{cost['base_wall_s']:.0f} s for the workspace dependencies before).")
    if a.timings:
        secs = compile_seconds(a.timings, added)
        lines.append(f"Their compile time, summed over the units of `{os.path.basename(a.timings)}` "
                     f"(a clean build, 2 cores shared with other builds): {secs:.0f} s.")
    publish(a.update, "ros-bench", COMMAND, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
