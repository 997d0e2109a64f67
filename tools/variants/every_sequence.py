#!/usr/bin/env python3
"""One setting of `swarmpose odometry` on every sequence we have, side by side with the
default: the shared real sequences, the exact variants of kitti_vo_seq2 written by
`kitti_variants.py`, and the built-in synthetic street. A change is judged on all of them,
never on one clip (the developers' guide: "Generalise, never tune to one sequence").

    cargo build --release -p swarmpose-cli
    python3 tools/variants/kitti_variants.py ../shared/data/kitti_vo_seq2 /tmp/kv
    python3 tools/variants/every_sequence.py --variants /tmp/kv -- --window 20

Prints one Markdown row per setting: kitti_vo_seq2's final drift / RMS eq. (20) / aligned
ATE, the mean drift and aligned ATE of the variants, Karlsruhe's ATE and final error
against its INS (percent of the path), the still EuRoC clip's final error (millimetres) and
the built-in street's drift. Every number is parsed from the summary the CLI prints (the
parser of tools/table1). About 25 s a setting on two cores.
"""

import argparse
import json
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "table1"))
from table1 import run  # noqa: E402  (the one parser of the CLI's summary)

VARIANTS = ["reversed", "mirrored", "mirrored-reversed", "first-half", "second-half", "every-2nd"]
# kitti_vo_seq2 has no times.txt: the clip at half its frame rate needs its period.
FRAME_PERIOD = {"every-2nd": ["--frame-period", "0.2"]}


def runs(binary, data, variants, out, extra):
    jobs = {
        "kitti": (os.path.join(data, "kitti_vo_seq2"), []),
        "karlsruhe": (os.path.join(data, "karlsruhe_2010_03_09_drive_0023"), []),
        "euroc": (os.path.join(data, "euroc_v1_01_easy_micro"), []),
    }
    if variants:
        for v in VARIANTS:
            jobs[v] = (os.path.join(variants, v), FRAME_PERIOD.get(v, []))
    found = {k: j for k, j in jobs.items() if os.path.isdir(j[0])}
    for k in jobs.keys() - found.keys():
        print(f"skipped {k}: {jobs[k][0]} not found", file=sys.stderr)

    def one(item):
        name, (seq, more) = item
        r = run(binary, seq, os.path.join(out, name), more + extra)
        # The summary prints metres to the millimetre; the still clip needs more digits.
        try:
            with open(os.path.join(out, name, "evaluation.json")) as f:
                r["final_m"] = json.load(f)["final_drift_m"]
        except (OSError, KeyError, ValueError):
            pass
        return name, r

    with ThreadPoolExecutor(max_workers=2) as pool:
        results = dict(pool.map(one, found.items()))
    results["street"] = street(binary, os.path.join(out, "street"), extra)
    return results


def street(binary, out, extra):
    """`swarmpose odometry` without a sequence: the built-in synthetic street."""
    p = subprocess.run([binary, "odometry", "--out", out, "--quiet", *extra],
                       capture_output=True, text=True)
    m = re.search(r"final drift [\d.]+ m \(([\d.]+) %\)", p.stdout)
    return {"exit": p.returncode, "drift": m.group(1) if m else "n/a"}


def row(label, r):
    def get(name, key, fmt):
        v = r.get(name, {}).get(key)
        return fmt(v) if v is not None else "n/a"

    k = r.get("kitti", {})
    kitti = (f"{k['drift']} / {k['eq20']:.5f} / {k['ate']:.3f} m" if "eq20" in k else "n/a")
    drifts = [float(r[v]["drift"].rstrip(" %")) for v in VARIANTS if "eq20" in r.get(v, {})]
    ates = [r[v]["ate"] for v in VARIANTS if "eq20" in r.get(v, {})]
    var = (f"{sum(drifts) / len(drifts):.3f} % / {sum(ates) / len(ates):.4f} m ({len(drifts)})"
           if drifts else "n/a")
    karl = (f"{get('karlsruhe', 'ins_ate', '{:.2f}'.format)} % / "
            f"{get('karlsruhe', 'ins_final', '{:.2f}'.format)} %")
    euroc = get("euroc", "final_m", lambda v: f"{1e3 * v:.2f} mm")
    return f"| {label} | {kitti} | {var} | {karl} | {euroc} | {r['street'].get('drift')} |"


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", default=os.environ.get("SWARMPOSE_DATA", os.path.join(ROOT, "..", "shared", "data")))
    p.add_argument("--variants", help="the folder kitti_variants.py wrote (optional)")
    p.add_argument("--out", default="/tmp/swarmpose-every-sequence")
    p.add_argument("--swarmpose", default=os.path.join(ROOT, "target", "release", "swarmpose"))
    p.add_argument("--no-default", action="store_true", help="skip the default's row")
    p.add_argument("--label", help="the setting's row label (default: its options); with no options, "
                   "a row for the binary and environment as they are (a development build's switch)")
    p.add_argument("extra", nargs="*", help="options of `swarmpose odometry` (after --)")
    a = p.parse_args()
    print("| setting | kitti_vo_seq2 drift / RMS eq. (20) / ATE | variants: mean drift / ATE (how many) "
          "| Karlsruhe ATE / final vs INS | EuRoC final | street drift |")
    print("|---|---|---|---|---|---|")
    settings = ([] if a.no_default else [("default", [])])
    if a.extra or a.label:
        settings.append((a.label or " ".join(a.extra), a.extra))
    for label, extra in settings:
        out = os.path.join(a.out, "default" if label == "default" else "setting")
        print(row(label, runs(a.swarmpose, a.data, a.variants, out, extra)), flush=True)


if __name__ == "__main__":
    main()
