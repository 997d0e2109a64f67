#!/usr/bin/env python3
"""Where the pipeline's time goes: a `perf record --call-graph dwarf` profile of the
pipeline bench (`crates/swarmpose-runs/benches/pipeline.rs`, its one-thread mode with
loading, `odometry/kitti_vo_seq2/load+engine`) on the shared KITTI clip, folded here
(no tool to install), as one Markdown section: the share of the CPU samples per stage
of the engine and the top functions by self time, with the commit, the machine and its
load (see tools/profile/README.md).

    python3 tools/profile/flame.py [--seconds 20] [--frequency 499] [--out DIR]
                                   [--data DIR] [--reuse] [--update FILE]

Writes into DIR (default: the system's temporary folder, `swarmpose-flame`): perf.data,
stacks.folded (one line per distinct stack, `frame;frame;... count`, the input of any
flame graph drawer: `inferno-flamegraph < stacks.folded > flame.svg`, drawn here when
`inferno-flamegraph` is on the PATH) and profile.md (the section).
"""

import argparse
import collections
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
from generated import provenance, publish  # noqa: E402

NAME = "pipeline-profile"
COMMAND = "python3 tools/profile/flame.py --update crates/swarmpose-odometry/RESULTS.md"
# The criterion filter: the one-thread mode with loading, not its two-thread or
# frame-to-frame siblings.
BENCH_FILTER = r"odometry/kitti_vo_seq2/load\+engine$"
# The bench's measured routine: the samples below this frame are the pipeline's (not
# criterion's, not the bench's setup or its first pass that prints the latencies).
MARKER = "swarmpose_runs::batch::collect"
# Stages by the functions that run them (a function is named by its module, read off its
# source file, and its own name: the line tables name inlined functions without their
# path); the innermost of these on a stack names its stage. They are the functions the
# engine's stage timers (`StageTimes`) wrap: features and stereo in
# swarmpose_odometry::frontend::stereo_frame, the rest in tracker/measure.rs.
MEASURE = r"^swarmpose_odometry::tracker::measure::"
STAGES = [
    ("loading", [r"^swarmpose_datasets::"]),
    ("stereo", [r"^swarmpose_odometry::frontend::stereo_frame$"]),
    ("features", [r"^swarmpose_vision::frontend::extract(_right)?$"]),
    ("temporal matching", [MEASURE + r"match_step$"]),
    ("estimator", [MEASURE + r"estimate_step$"]),
    ("refinement", [MEASURE + r"(aligned_observations|refine_step)$",
                    r"^swarmpose_odometry::tracker::predict::prediction$"]),
    ("self-calibration", [MEASURE + r"calibrate_step$"]),
    ("window", [MEASURE + r"window_step$"]),
    ("covariance and split check", [MEASURE + r"take_refined$"]),
]
STAGE_ORDER = [s for s, _ in STAGES] + ["other (engine bookkeeping, results, memory)"]
TOP = 15


def run(args, **kw):
    return subprocess.run(args, check=True, **kw)


def build_bench():
    """Builds the pipeline bench (release, line tables) and returns its executable."""
    out = run(["cargo", "bench", "-p", "swarmpose-runs", "--bench", "pipeline", "--no-run",
               "--message-format=json-render-diagnostics"], cwd=ROOT, capture_output=True,
              text=True).stdout
    for line in out.splitlines():
        try:
            msg = json.loads(line)
        except json.JSONDecodeError:
            continue
        if msg.get("reason") == "compiler-artifact" and msg.get("executable") \
                and msg["target"]["name"] == "pipeline":
            return msg["executable"]
    raise SystemExit("cargo did not name the pipeline bench's executable")


def record(exe, out, seconds, frequency, data):
    """perf record of the bench's one-thread mode; returns the bench's stderr lines."""
    env = dict(os.environ, SWARMPOSE_DATA=data)
    perf_data = os.path.join(out, "perf.data")
    # The largest stack copy perf takes (64 KiB): the tracker's frame alone is 31 KiB.
    p = run(["perf", "record", "--call-graph", "dwarf,65528", "-F", str(frequency), "-o", perf_data,
             "--", exe, "--bench", "--profile-time", str(seconds), BENCH_FILTER],
            cwd=ROOT, env=env, capture_output=True, text=True)
    return [l for l in p.stderr.splitlines() if "kitti_vo_seq2, orb + pso" in l]


FRAME = re.compile(r"^\s+([0-9a-f]+) (.*) \((.*)\)$")


def load_segments(exe):
    """The executable's LOAD segments: (file offset, virtual address, file size)."""
    out = run(["readelf", "-lW", exe], capture_output=True, text=True).stdout
    segs = []
    for line in out.splitlines():
        f = line.split()
        if f and f[0] == "LOAD":
            segs.append((int(f[1], 16), int(f[2], 16), int(f[4], 16)))
    return segs


def to_vaddr(offset, segs):
    """The link-time address of a file offset of the executable, or None."""
    for s_off, s_vaddr, s_size in segs:
        if s_off <= offset < s_off + s_size:
            return offset - s_off + s_vaddr
    return None


def samples(perf_data):
    """Yields each sample's frames, leaf first: (address, symbol, dso). perf gives the
    address of a frame in a position-independent executable as its offset into the file
    (`to_vaddr` makes it a link-time address); its own inline frames are left out
    (`--no-inline`): `inline_chains` names them with their modules."""
    p = subprocess.Popen(["perf", "script", "-i", perf_data, "--no-inline",
                          "-F", "comm,tid,ip,sym,dso"], stdout=subprocess.PIPE,
                         stderr=subprocess.DEVNULL, text=True, errors="replace")
    frames = []
    for line in p.stdout:
        f = FRAME.match(line.rstrip("\n"))
        if f:
            frames.append((int(f.group(1), 16), f.group(2), f.group(3)))
        elif not line.strip():
            if frames:
                yield frames
            frames = []
    if frames:
        yield frames
    p.wait()


def module_of(path):
    """The Rust module path of a source file: crates/swarmpose-vision/src/orb/fast.rs ->
    swarmpose_vision::orb::fast; a registry crate's file -> crate::module; the standard
    library's -> core::..., std::..., alloc::..."""
    parts = path.split("/")
    if "src" not in parts:
        return os.path.splitext(parts[-1])[0]
    i = len(parts) - 1 - parts[::-1].index("src")
    krate = parts[i - 1] if i >= 1 else "?"
    if i < 2 or parts[i - 2] != "library":
        # crates.io sources are in NAME-VERSION folders.
        krate = re.sub(r"-\d+(\.\d+)*(-[\w.]+)?$", "", krate)
    mods = parts[i + 1:]
    mods[-1] = os.path.splitext(mods[-1])[0]
    if mods[-1] in ("mod", "lib", "main"):
        mods.pop()
    return "::".join([krate.replace("-", "_")] + mods)


def short_name(name):
    """A function's own name, without path, hash or generics; a closure keeps the name
    of the function it is in."""
    name = re.sub(r" \(\.llvm\.\d+\)$", "", name.strip())
    name = re.sub(r"::h[0-9a-f]{16}$", "", name)
    prev = None
    while prev != name:
        prev = name
        name = re.sub(r"<[^<>]*>", "", name)
    segs = [s for s in name.split("::") if s]
    if not segs:
        return name
    segs = [re.sub(r"^\{\{?closure\}?(#\d+)?\}$", "{closure}", s) for s in segs]
    if segs[-1] == "{closure}" and len(segs) > 1:
        return "::".join(segs[-2:])
    return segs[-1]


def inline_chains(exe, addrs):
    """For each link-time address, its functions, innermost first (inlined frames
    included), each named by its module and own name, from the line tables
    (`llvm-addr2line -a`: each answer starts with the address asked, then pairs of
    function and file:line)."""
    tool = shutil.which("llvm-addr2line")
    if not tool:
        raise SystemExit("llvm-addr2line is needed (Debian: apt-get install llvm)")
    text = "\n".join(hex(a) for a in sorted(addrs)) + "\n"
    out = run([tool, "-a", "-f", "-i", "-C", "-e", exe], input=text, capture_output=True,
              text=True).stdout.splitlines()
    chains = {}
    cur = None
    k = 0
    while k < len(out):
        line = out[k].strip()
        if line.startswith("0x"):
            cur = chains.setdefault(int(line, 16), [])
            k += 1
            continue
        where = out[k + 1].strip().rsplit(":", 2)[0] if k + 1 < len(out) else "??"
        where = re.sub(r":\d+.*$", "", where)
        k += 2
        if cur is None:
            continue
        if line == "??":
            cur.append(None)
        elif where.startswith("??"):
            cur.append(short_name(line))
        else:
            cur.append(f"{module_of(where)}::{short_name(line)}")
    return chains


def folded(perf_data, exe):
    """The samples below MARKER as stacks of function names, root first, counted; and
    the number of samples in all."""
    real = os.path.realpath(exe)
    segs = load_segments(exe)
    raw = []
    total = 0
    for frames in samples(perf_data):
        total += 1
        resolved = []
        for depth, (ip, sym, dso) in enumerate(frames):
            # A caller's address is its return address: the call is the byte before.
            off = ip if depth == 0 else ip - 1
            v = to_vaddr(off, segs) if os.path.realpath(dso) == real else None
            resolved.append((v, sym, dso))
        raw.append(resolved)
    addrs = {v for s in raw for v, _, _ in s if v is not None}
    chains = inline_chains(exe, addrs)
    stacks = collections.Counter()
    for s in raw:
        names = []  # leaf first
        for v, sym, dso in s:
            chain = chains.get(v) if v is not None else None
            if chain and None not in chain:
                names.extend(chain)
            elif sym and sym != "[unknown]":
                names.append(short_name(sym) if "::" not in sym else
                             re.sub(r"::h[0-9a-f]{16}$", "", sym))
            else:
                names.append(f"[{os.path.basename(dso)}]")
        names.reverse()
        if MARKER not in names:
            continue
        names = names[names.index(MARKER):]
        stacks[tuple(names)] += 1
    return stacks, total


def stage_of(stack):
    """The stage of a stack (root first): its innermost stage function."""
    found = STAGE_ORDER[-1]
    for name in stack:
        for stage, patterns in STAGES:
            if any(re.search(p, name) for p in patterns):
                found = stage
    return found


STD = ("core::", "alloc::", "std::")


def leaf_frame(stack):
    """The innermost function on a stack (root first) outside the standard library (whose
    small inlined helpers, `mul`, `add`, `clone`, ..., count in their caller)."""
    for name in reversed(stack):
        if not name.startswith(STD):
            return name
    return stack[-1]


def project_frame(stack):
    """The innermost function of this project's code on a stack (root first)."""
    for name in reversed(stack):
        if name.startswith("swarmpose_"):
            return name
    return stack[-1]


def section(stacks, total, bench_lines, seconds, frequency):
    n = sum(stacks.values())
    by_stage = collections.Counter()
    self_leaf = collections.Counter()
    self_project = collections.Counter()
    leaf_stage = collections.defaultdict(collections.Counter)
    for st, c in stacks.items():
        stage = stage_of(st)
        by_stage[stage] += c
        self_leaf[leaf_frame(st)] += c
        self_project[project_frame(st)] += c
        leaf_stage[leaf_frame(st)][stage] += c
    pct = lambda c: f"{100.0 * c / n:.1f} %"
    out = [
        f"Generated {provenance()}.",
        "",
        f"`perf record --call-graph dwarf -F {frequency}` of the pipeline bench's one-thread mode "
        f"with loading (`{BENCH_FILTER}`, criterion `--profile-time {seconds}`), release build with "
        f"line tables; stacks unwound from DWARF, inlined functions resolved from the line tables "
        f"and folded by `tools/profile/flame.py`. {n} of the run's {total} samples lie below "
        f"`{MARKER}` (the measured routine: loading and the engine; the rest are the bench's setup "
        f"and first pass, and criterion). Shares are of those {n} CPU samples, which hold under "
        f"load; the machine's load is the line above.",
        "",
        "| stage | share of the samples |",
        "|---|---|",
    ]
    for stage in STAGE_ORDER:
        if by_stage[stage]:
            out.append(f"| {stage} | {pct(by_stage[stage])} |")
    out += ["", f"Top {TOP} functions by self time (the innermost function of each sample, inlined "
            "ones included; the standard library's small helpers, `mul`, `add`, `clone`, "
            "`count_ones`, ..., counted in their caller):", "", "| function | stage (most of its samples) | self |", "|---|---|---|"]
    for fn, c in self_leaf.most_common(TOP):
        stage = leaf_stage[fn].most_common(1)[0][0]
        out.append(f"| `{fn}` | {stage} | {pct(c)} |")
    out += ["", f"Top {TOP} functions of this project by self time, the library code they call "
            "(std, nalgebra, png, ...) counted in them:", "", "| function | self and libraries |",
            "|---|---|"]
    for fn, c in self_project.most_common(TOP):
        out.append(f"| `{fn}` | {pct(c)} |")
    if bench_lines:
        out += ["", "The bench's first pass in the same run (the engine's own timers, images in "
                "memory, under perf):", ""]
        out += [f"    {l.strip()}" for l in bench_lines]
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=int, default=20, help="criterion --profile-time [20]")
    ap.add_argument("--frequency", type=int, default=499, help="samples per second [499]")
    ap.add_argument("--out", default=os.path.join(tempfile.gettempdir(), "swarmpose-flame"),
                    help="folder for perf.data, stacks.folded and profile.md")
    ap.add_argument("--data", default=os.environ.get("SWARMPOSE_DATA",
                                                     os.path.join(ROOT, "..", "shared", "data")),
                    help="the shared data root [$SWARMPOSE_DATA or ../shared/data]")
    ap.add_argument("--reuse", action="store_true",
                    help="fold the perf.data already in --out instead of recording")
    ap.add_argument("--update", metavar="FILE", help="write the section into FILE")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    exe = build_bench()
    bench_lines = []
    if not args.reuse:
        bench_lines = record(exe, args.out, args.seconds, args.frequency, args.data)
        with open(os.path.join(args.out, "bench_lines.txt"), "w", encoding="utf-8") as f:
            f.write("\n".join(bench_lines))
    else:
        path = os.path.join(args.out, "bench_lines.txt")
        if os.path.exists(path):
            bench_lines = open(path, encoding="utf-8").read().splitlines()
    stacks, total = folded(os.path.join(args.out, "perf.data"), exe)
    if not stacks:
        raise SystemExit(f"no sample below {MARKER}: is kitti_vo_seq2 under {args.data}?")
    with open(os.path.join(args.out, "stacks.folded"), "w", encoding="utf-8") as f:
        for st, c in sorted(stacks.items()):
            f.write(";".join(n.replace(";", ":") for n in st) + f" {c}\n")
    if shutil.which("inferno-flamegraph"):
        with open(os.path.join(args.out, "stacks.folded"), "rb") as src, \
                open(os.path.join(args.out, "flame.svg"), "wb") as dst:
            run(["inferno-flamegraph"], stdin=src, stdout=dst)
    other = sum(c for st, c in stacks.items() if stage_of(st) == STAGE_ORDER[-1])
    if other > 0.1 * sum(stacks.values()):
        # A stage function renamed or moved: STAGES no longer names it.
        print(f"warning: {100 * other / sum(stacks.values()):.0f} % of the samples in no stage; "
              "check STAGES against the engine's code", file=sys.stderr)
    text = section(stacks, total, bench_lines, args.seconds, args.frequency)
    with open(os.path.join(args.out, "profile.md"), "w", encoding="utf-8") as f:
        f.write(text)
    publish(args.update, NAME, COMMAND, text)


if __name__ == "__main__":
    main()
