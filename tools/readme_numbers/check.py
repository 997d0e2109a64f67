#!/usr/bin/env python3
"""README figures that cannot go stale (issue 32).

RESULTS.md (crates/swarmpose-odometry/RESULTS.md) holds the generated tables: each between
`<!-- generated: NAME (COMMAND) -->` and `<!-- end generated: NAME -->`, written by the
script its marker names from measured runs, with the commit and machine. The README quotes
figures only through its own generated sections, which this script derives from RESULTS.md's
(a column selection of a table; no arithmetic):

    <!-- generated: readme-results (python3 tools/readme_numbers/check.py --update) -->

Checks (exit 1 with the offending lines listed):
1. each generated section of README.md is what this script derives from RESULTS.md today;
2. every figure in README.md's prose and tables (outside code blocks and inline code): a
   number with a decimal point or a percentage, appears verbatim in a generated section of
   RESULTS.md. Integers without a unit (frame counts, versions, cores) are not figures here;
3. README.md has at most README_MAX_LINES lines (a manual, not a history).

`--update` rewrites README.md's generated sections (run it after regenerating RESULTS.md).
This checks that the README agrees with RESULTS.md, not that RESULTS.md agrees with a new
run: regenerating RESULTS.md's tables is its generators' job (tools/*/README.md)."""

import argparse
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
README = os.path.join(ROOT, "README.md")
RESULTS = os.path.join(ROOT, "crates", "swarmpose-odometry", "RESULTS.md")
SECTION = re.compile(r"<!-- generated: ([\w-]+) \((.*?)\) -->\n(.*?)<!-- end generated: \1 -->", re.S)
FIGURE = re.compile(r"(?<![\w.\-])[-+]?\d+(?:\.\d+)?(?:\s?%)|(?<![\w.\-])[-+]?\d+\.\d+(?![\w.])")
README_COMMAND = "python3 tools/readme_numbers/check.py --update"
# Issue 32: the README is a manual of about 200 lines, under 250; the rest is in docs/.
README_MAX_LINES = 249


def sections(text):
    return {m.group(1): m.group(3) for m in SECTION.finditer(text)}


def table_rows(block):
    """The rows of the first Markdown table in `block`, as lists of cells."""
    rows = []
    for line in block.splitlines():
        if line.startswith("|"):
            rows.append([c.strip() for c in line.strip().strip("|").split("|")])
        elif rows:
            break
    return rows


def readme_results(results):
    """The README's table of current results: from RESULTS.md's peer table, each clip's
    final drift and aligned ATE, swarmpose against the competent OpenCV peer."""
    peer = results["peer-table"]
    provenance = peer.splitlines()[0]
    m = re.match(r"Generated (at \S+, [^,]+), on .*?, load average", provenance)
    when = m.group(1) if m else "at an unknown commit"
    rows = table_rows(peer)
    header, body = rows[0], rows[2:]
    drift, ate = header.index("final drift swarmpose / peer"), header.index("ATE aligned RMS swarmpose / peer")
    lines = [
        f"From RESULTS.md's peer table (generated {when}): swarmpose's default against a competent",
        "OpenCV stereo PnP pipeline (`tools/peers/opencv_vo.py`), one run each, scored by the same code.",
        "",
        "| clip | final drift swarmpose / peer | ATE aligned RMS swarmpose / peer |",
        "|---|---|---|",
    ]
    for r in body:
        lines.append(f"| {r[0]} | {r[drift]} | {r[ate]} |")
    return "\n".join(lines) + "\n"


GENERATORS = {"readme-results": readme_results}


def prose(text):
    """README.md without its code blocks, inline code and HTML comments."""
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    text = re.sub(r"<!--.*?-->", "", text, flags=re.S)
    text = re.sub(r"`[^`\n]*`", "", text)
    # Versions are not figures.
    return re.sub(r"(Rust|Python|version|v)\s?\d+\.\d+(\.\d+)?", "", text)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--update", action="store_true", help="rewrite README.md's generated sections")
    args = parser.parse_args()
    readme = open(README, encoding="utf-8").read()
    results = sections(open(RESULTS, encoding="utf-8").read())
    problems = []
    lines = readme.count("\n")
    if lines > README_MAX_LINES:
        problems.append(f"README.md: {lines} lines, over {README_MAX_LINES}: move detail to docs/")
    for m in reversed(list(SECTION.finditer(readme))):
        name, body = m.group(1), m.group(3)
        if name not in GENERATORS:
            problems.append(f"README.md: generated section {name!r}: no generator in this script")
            continue
        want = GENERATORS[name](results)
        if body != want:
            if args.update:
                readme = readme[:m.start(3)] + want + readme[m.end(3):]
            else:
                problems.append(f"README.md: generated section {name!r} differs from RESULTS.md (run {README_COMMAND})")
    if args.update:
        with open(README, "w", encoding="utf-8") as f:
            f.write(readme)
    known = "\n".join(results.values())
    for n, line in enumerate(prose(readme).splitlines(), 1):
        for fig in FIGURE.findall(line):
            if fig.replace(" ", "") not in known.replace(" %", "%"):
                problems.append(f"README.md: {fig!r} is in no generated table of RESULTS.md: {line.strip()[:100]}")
    for p in problems:
        print(p)
    if not problems:
        print(f"readme numbers: README.md ({lines} lines) quotes only RESULTS.md's generated tables")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
