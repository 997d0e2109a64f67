"""Generated sections of the RESULTS files: where a table came from (commit, machine) and
the replacement of a section between its markers, so that no figure is typed by hand.

A section of a Markdown file is delimited by

    <!-- generated: NAME (COMMAND) -->
    ...
    <!-- end generated: NAME -->

and `replace_section(path, name, command, text)` rewrites what lies between (adding the
markers at the end of the file the first time).
"""

import os
import platform
import re
import subprocess
from datetime import datetime, timezone

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def common_arguments(parser):
    """The options every generator takes: --data, --swarmpose, --update."""
    parser.add_argument("--data", default=os.environ.get("SWARMPOSE_DATA", os.path.join(ROOT, "..", "shared", "data")),
                        help="the shared data root [$SWARMPOSE_DATA or ../shared/data]")
    parser.add_argument("--swarmpose", default=os.path.join(ROOT, "target", "release", "swarmpose"),
                        help="the CLI [target/release/swarmpose]")
    parser.add_argument("--update", metavar="FILE", help="write the section into FILE instead of printing it")


def provenance():
    """One line: the commit (with "+ uncommitted changes" when a file other than
    Markdown differs from it), the
    date, the machine (CPU model, cores, memory) and its load average."""
    def git(*args):
        return subprocess.run(["git", "-C", ROOT, *args], capture_output=True, text=True).stdout.strip()

    commit = git("rev-parse", "--short", "HEAD") or "unknown commit"
    # Changes to documentation (the file being regenerated) do not change a figure.
    if git("status", "--porcelain", "--untracked-files=no", "--", ".", ":!*.md"):
        commit += " + uncommitted changes"
    cpu = platform.processor() or platform.machine()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
        mem_kb = next(int(line.split()[1]) for line in open("/proc/meminfo") if line.startswith("MemTotal"))
        mem = f", {mem_kb / 2**20:.0f} GiB"
    except (OSError, StopIteration):
        mem = ""
    load = " / ".join(f"{v:.1f}" for v in os.getloadavg())
    when = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return (f"at {commit}, {when}, on {platform.system()} {platform.machine()} ({cpu}, "
            f"{os.cpu_count()} cores{mem}), load average {load}")


def replace_section(path, name, command, text):
    """Replaces the generated section NAME of the Markdown file PATH by TEXT."""
    begin = f"<!-- generated: {name} ({command}) -->"
    end = f"<!-- end generated: {name} -->"
    with open(path, encoding="utf-8") as f:
        doc = f.read()
    block = f"{begin}\n{text.rstrip()}\n{end}"
    pattern = re.compile(re.escape(f"<!-- generated: {name} (") + r".*?" + re.escape(end), re.S)
    if pattern.search(doc):
        doc = pattern.sub(lambda _: block, doc, count=1)
    else:
        doc = doc.rstrip("\n") + "\n\n" + block + "\n"
    tmp = f"{path}.partial-{os.getpid()}"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(doc)
    if not os.path.isfile(path) or os.path.islink(path):
        os.remove(tmp)
        raise SystemExit(f"{path}: not a regular file; not replaced")
    os.replace(tmp, path)


def publish(update, name, command, text):
    """Writes TEXT as the section NAME of the file UPDATE, or prints it when UPDATE is None."""
    if update:
        replace_section(update, name, command, text)
    else:
        print(text, end="")
