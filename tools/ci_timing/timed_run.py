#!/usr/bin/env python3
"""Times `.ci/run` as CI runs it (issue 32): a fresh clone of HEAD, `CI=true`, every output
line stamped with the seconds since the start, then the stages and totals as one Markdown
section, printed or written into docs/testing.md's generated section (--update).

    python3 tools/ci_timing/timed_run.py [--data DIR] [--log FILE] [--update docs/testing.md]
    python3 tools/ci_timing/timed_run.py --from-log FILE [--update docs/testing.md]

The stages are read off the log by the lines cargo, pytest and the script print (see
STAGES); wall time is measured here, CPU time is that of every process the run started
(getrusage of the children), and the load average is read before the start: a run on a
busy machine says so. --from-log summarises a log written earlier by this script.
"""

import argparse
import os
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SECTION = "ci-timing"
COMMAND = "python3 tools/ci_timing/timed_run.py --update docs/testing.md"

# (stage, the regular expression of the line that ends it), in the order .ci/run prints
# them; each stage starts where the one before it ended.
STAGES = [
    ("checks: fmt, module cycles, function length, MSRV, README, feature alignment, publish dry-run",
     r"^\s+Compiling "),
    ("test build, the benches with the lints", r"^\s+Finished `test` profile"),
    ("test build, the rest (libraries, binaries, tests, examples)", r"^\s+Finished `test` profile"),
    ("`cargo test --workspace` running the tests", r"^the slow tests that cargo test --workspace leaves out"),
    ("the slow tests it leaves out (`--ignored`)", r"=+ test session starts =+"),
    ("the ROS 2 node's pytest (Cyclone DDS)", r"^=+ .*\b(passed|failed)\b.* in [\d.]+s"),
    ("the Python wheel (dev profile) and its import", r"^swarmpose \d"),
    ("the Python package's pytest", r"^=+ .*\b(passed|failed)\b.* in [\d.]+s"),
    ("the fuzzing's tail (9 targets; built in the background)", r"^exit \d+$"),
]


def stamped_run(clone, data, log):
    """Runs .ci/run in `clone`, writing `SECONDS<TAB>line` to `log`; its exit status."""
    env = dict(os.environ, CI="true", SWARMPOSE_DATA=data)
    commit = subprocess.run(["git", "-C", clone, "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, check=True).stdout.strip()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    with open(log, "w", encoding="utf-8", buffering=1) as out:  # line by line: a killed run keeps its log
        load = " ".join(f"{x:.2f}" for x in os.getloadavg())
        out.write(f"0.0\tstart {commit} load {load}\n")
        proc = subprocess.Popen([".ci/run"], cwd=clone, env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True, errors="replace")
        for line in proc.stdout:
            out.write(f"{time.monotonic() - start:.1f}\t{line.rstrip()}\n")
        status = proc.wait()
        wall = time.monotonic() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        out.write(f"{wall:.1f}\texit {status}\n{wall:.1f}\ttotals wall {wall:.1f} cpu {cpu:.1f}\n")
    return status


def summary(log):
    """The Markdown section of a log written by stamped_run."""
    lines = []
    for raw in open(log, encoding="utf-8"):
        t, _, text = raw.rstrip("\n").partition("\t")
        lines.append((float(t), text))
    _, commit, load = lines[0][1].split(" ", 2)
    totals = re.match(r"totals wall ([\d.]+) cpu ([\d.]+)", lines[-1][1])
    status = lines[-2][1]
    rows, begin, i = [], 0.0, 1
    for name, pattern in STAGES:
        rx = re.compile(pattern)
        while i < len(lines) and not rx.search(lines[i][1]):
            i += 1
        if i == len(lines):
            rows.append(f"| {name} | not found in the log |")
            break
        rows.append(f"| {name} | {minutes(lines[i][0] - begin)} |")
        begin = lines[i][0]
        i += 1
    cargo = sum(int(m.group(1)) for _, s in lines if (m := re.search(r"test result: ok\. (\d+) passed", s)))
    pytests = [s.strip("= ") for _, s in lines if re.match(r"^=+ .*\b(passed|failed)\b.* in [\d.]+s", s)]
    head = (f"`.ci/run` on a fresh clone of {commit}, `CI=true`, timed by `{COMMAND}` on "
            f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime(os.path.getmtime(log)))}, "
            f"{platform.system()} {platform.machine()} ({os.cpu_count()} cores), {load} (1, 5, 15 min) at the start: "
            f"**{minutes(float(totals.group(1)))}** wall, {float(totals.group(2)):.0f} s of CPU; {status}. "
            f"`cargo test`: {cargo} tests passed; pytest: {'; '.join(pytests)}.")
    return "\n".join([head, "", "| stage | wall time |", "|---|---|", *rows]) + "\n"


def minutes(s):
    return f"{int(s // 60)} min {s % 60:04.1f} s" if s >= 60 else f"{s:.1f} s"


def update(path, body):
    text = open(path, encoding="utf-8").read()
    marker = re.compile(rf"(<!-- generated: {SECTION} \(.*?\) -->\n)(.*?)(<!-- end generated: {SECTION} -->)", re.S)
    if not marker.search(text):
        sys.exit(f"{path}: no generated section {SECTION!r}")
    with open(path, "w", encoding="utf-8") as f:
        f.write(marker.sub(lambda m: m.group(1) + body + m.group(3), text))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--data", default=os.environ.get("SWARMPOSE_DATA", os.path.join(ROOT, "..", "shared", "data")))
    p.add_argument("--log", help="where to write the stamped log (default: a temporary file)")
    p.add_argument("--from-log", help="summarise this log instead of running")
    p.add_argument("--update", help="write the section into this Markdown file")
    a = p.parse_args()
    log = a.from_log
    status = 0
    if log is None:
        work = tempfile.mkdtemp(prefix="ci-timing-")
        clone = os.path.join(work, "repo")
        subprocess.run(["git", "clone", "--quiet", ROOT, clone], check=True)
        log = a.log or os.path.join(work, "ci.log")
        print(f"running .ci/run in {clone}; log {log}", flush=True)
        status = stamped_run(clone, os.path.abspath(a.data), log)
    body = summary(log)
    print(body)
    if a.update:
        update(a.update, body)
    return status


if __name__ == "__main__":
    sys.exit(main())
