#!/usr/bin/env python3
"""swarmpose's default odometry against the OpenCV PnP peer (opencv_vo.py), side by side
on every shared sequence and every exact variant of kitti_vo_seq2, with a seeded paired
bootstrap interval of each difference, as one Markdown section (printed, or written into
a RESULTS file with --update FILE). "Lower" is claimed only where the interval excludes 0.

Per clip, both trajectories are scored by the same code against the same ground truth
(`swarmpose evaluate --json`; Karlsruhe: against its INS positions after an SE(3)
alignment, as compare.py): the per-frame aligned ATE (m), the per-frame RPE translation
(m, one frame) and eq. (20) of the relative rotations. The difference of their RMS
(swarmpose minus peer) gets a 95 % percentile interval from a moving-block bootstrap over
frames (blocks of round(n^(1/3)) consecutive frames, so that correlated neighbours are
resampled together; both systems resampled with the same frames; 2000 resamples, seed 0).
The pooled row averages the per-clip differences over kitti_vo_seq2 and its variants,
resampling each clip's frames independently. Final drift (one number per run) is shown
without an interval.

With --shared-peer PATH (../shared/peers/opencv_pnp_vo.py, its "pnp" pipeline; KITTI
layouts and Karlsruhe, it cannot read EuRoC), two more tables, with the same intervals:
swarmpose against that script itself, and the repo's peer against it (where the script is
the stronger, the comparison with it is the one that counts).

    python3 tools/peers/peer_table.py --variants DIR [--data DIR] [--out DIR]
        [--shared-peer ../shared/peers/opencv_pnp_vo.py] [--reuse] [--update FILE]

--variants DIR: the output of tools/variants/kitti_variants.py. --reuse: keep the runs
already in --out (a trajectory file and its JSON line) instead of running again.
"""

import argparse
import glob
import json
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "generated"))
from compare import evaluate, ins_errors  # noqa: E402  (this folder)
from generated import common_arguments, provenance, publish  # noqa: E402

COMMAND = ("python3 tools/peers/peer_table.py --variants /tmp/kv --shared-peer "
           "../shared/peers/opencv_pnp_vo.py --update crates/swarmpose-odometry/RESULTS.md")
VARIANTS = ["reversed", "mirrored", "mirrored-reversed", "first-half", "second-half", "every-2nd"]
SEQUENCES = ["kitti_vo_seq2", "karlsruhe_2010_03_09_drive_0023", "euroc_v1_01_easy_micro"]
METRICS = (("ate", "ATE aligned", "m", 3), ("rpe", "RPE translation", "m", 4), ("eq20", "eq. (20)", "", 5))
RESAMPLES = 2000
SEED = 0


def clips(data, variants):
    """(label, directory, swarmpose options, kitti family) of every clip that exists."""
    out = []
    for name in SEQUENCES:
        out.append((name, os.path.join(data, name), [], name == "kitti_vo_seq2"))
        if name == "kitti_vo_seq2":
            for v in VARIANTS:
                opts = ["--frame-period", "0.2"] if v == "every-2nd" else []
                out.append((f"{name} {v}", os.path.join(variants, v), opts, True))
    missing = [d for _, d, _, _ in out if not os.path.isdir(d)]
    if missing:
        sys.exit(f"not found: {', '.join(missing)} (--data, --variants)")
    return out


def run(cmd, log, reuse, result):
    """Runs CMD (stdout to LOG) unless --reuse and RESULT exists; exits on failure."""
    if reuse and os.path.exists(result) and os.path.exists(log):
        return
    os.makedirs(os.path.dirname(log), exist_ok=True)
    with open(log, "w") as f:
        p = subprocess.run(["nice", "-n", "10", *cmd], stdout=f, stderr=subprocess.PIPE, text=True)
    if p.returncode not in (0, 3) or not os.path.exists(result):
        sys.exit(f"{' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()[-500:]}")


def trajectories(a, label, seq, opts):
    """Runs swarmpose, the peer and (optionally) the shared peer on SEQ; their files."""
    out = os.path.join(a.out, label.replace(" ", "_"))
    ours = os.path.join(out, "swarmpose")
    run([a.swarmpose, "odometry", seq, "--out", ours, "--quiet", *opts],
        os.path.join(out, "swarmpose.log"), a.reuse, os.path.join(ours, "trajectory.kitti.txt"))
    peer = os.path.join(out, "opencv")
    run([sys.executable, os.path.join(HERE, "opencv_vo.py"), seq, peer], os.path.join(out, "opencv.json"),
        a.reuse, os.path.join(peer, "trajectory.kitti.txt"))
    files = {"swarmpose": os.path.join(ours, "trajectory.kitti.txt"),
             "peer": os.path.join(peer, "trajectory.kitti.txt")}
    is_euroc = os.path.isdir(os.path.join(seq, "mav0"))
    if a.shared_peer and not is_euroc:
        shared = os.path.join(out, "shared")
        layout = ["--karlsruhe"] if glob.glob(os.path.join(seq, "*_Images")) else []
        name = ("karlsruhe_" if layout else "kitti_") + os.path.basename(os.path.normpath(seq))
        result = os.path.join(shared, f"{name}_pnp.kitti.txt")
        run([sys.executable, a.shared_peer, "--dir", seq, *layout, "--pipeline", "pnp", "--out", shared],
            os.path.join(out, "shared.json"), a.reuse, result)
        files["shared peer"] = result
    gt = os.path.join(ours, "groundtruth.kitti.txt")
    return files, (gt if os.path.exists(gt) else None)


def scores(a, traj, gt, seq):
    """Per-frame errors (arrays) and the final drift (text) of one trajectory."""
    if gt is None:
        err, length = ins_errors(traj, seq)
        return {"ate": err, "drift": f"{100 * err[-1] / length:.2f} % (vs INS)"}
    e = evaluate(a.swarmpose, traj, gt)
    drift = e["final_drift_percent"]
    return {"ate": np.array(e["ate_aligned_per_frame"]), "rpe": np.array(e["rpe_translation_per_frame"]),
            "eq20": np.array(e["eq20_per_frame"]),
            "drift": f"{drift:.3f} %" if drift is not None else f"{1e3 * e['final_drift_m']:.1f} mm"}


def rms(v, axis=-1):
    return np.sqrt(np.mean(v ** 2, axis=axis))


def block_indices(n, rng):
    """RESAMPLES x n frame indices of a moving-block bootstrap."""
    length = max(1, round(n ** (1 / 3)))
    blocks = -(-n // length)
    starts = rng.integers(0, n - length + 1, size=(RESAMPLES, blocks))
    return (starts[:, :, None] + np.arange(length)).reshape(RESAMPLES, -1)[:, :n]


def differences(pairs, rng):
    """Mean over clips of RMS(a) - RMS(b), and its bootstrap resamples."""
    point = np.mean([rms(x) - rms(y) for x, y in pairs])
    boot = np.zeros(RESAMPLES)
    for x, y in pairs:
        idx = block_indices(len(x), rng)
        boot += rms(x[idx]) - rms(y[idx])
    return point, boot / len(pairs)


def cell(point, boot, unit, digits):
    lo, hi = np.percentile(boot, [2.5, 97.5])
    return f"{point:+.{digits}f} [{lo:+.{digits}f}, {hi:+.{digits}f}]{' ' + unit if unit else ''}", lo, hi


def table(rows, a_name, b_name, rng):
    """Markdown rows of A against B: ROWS is [(label, {metric: (a, b)}, drifts)]."""
    head = f"| clip | final drift {a_name} / {b_name} |"
    sep = "|---|---|"
    for _, name, unit, _ in METRICS:
        head += f" {name} RMS {a_name} / {b_name} | difference [95 % interval] | lower |"
        sep += "---|---|---|"
    lines = [head, sep]
    pooled = {}
    for label, pairs, drifts, kitti in rows:
        line = f"| {label} | {drifts[0]} / {drifts[1]} |"
        for key, _, unit, digits in METRICS:
            if key not in pairs:
                line += " n/a | | |"
                continue
            x, y = pairs[key]
            if kitti:
                pooled.setdefault(key, []).append((x, y))
            if unit == "m" and max(rms(x), rms(y)) < 0.01:  # millimetres (the still EuRoC clip)
                x, y, unit = 1e3 * x, 1e3 * y, "mm"
            text, lo, hi = cell(*differences([(x, y)], rng), unit, digits)
            lower = a_name if hi < 0 else b_name if lo > 0 else "not resolved"
            line += f" {rms(x):.{digits}f} / {rms(y):.{digits}f}{' ' + unit if unit else ''} | {text} | {lower} |"
        lines.append(line)
    if pooled:
        n = len(next(iter(pooled.values())))
        line = f"| **kitti_vo_seq2 and its variants ({n} clips), mean** | |"
        for key, _, unit, digits in METRICS:
            pairs = pooled[key]
            text, lo, hi = cell(*differences(pairs, rng), unit, digits)
            lower = a_name if hi < 0 else b_name if lo > 0 else "not resolved"
            mean_a = np.mean([rms(x) for x, _ in pairs])
            mean_b = np.mean([rms(y) for _, y in pairs])
            line += f" {mean_a:.{digits}f} / {mean_b:.{digits}f}{' ' + unit if unit else ''} | {text} | **{lower}** |"
        lines.append(line)
    return lines


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    common_arguments(p)
    p.add_argument("--variants", required=True, help="the folder of tools/variants/kitti_variants.py")
    p.add_argument("--out", default="/tmp/swarmpose-peer-table")
    p.add_argument("--shared-peer", help="../shared/peers/opencv_pnp_vo.py, to compare the peer with")
    p.add_argument("--reuse", action="store_true", help="keep the runs already in --out")
    a = p.parse_args()
    comparisons = {("swarmpose", "peer"): [], ("swarmpose", "shared peer"): [], ("peer", "shared peer"): []}
    for label, seq, opts, kitti in clips(a.data, a.variants):
        files, gt = trajectories(a, label, seq, opts)
        s = {k: scores(a, f, gt, seq) for k, f in files.items()}
        keys = [m[0] for m in METRICS if m[0] in s["swarmpose"]]
        for (x, y), rows in comparisons.items():
            if x in s and y in s:
                rows.append((label, {k: (s[x][k], s[y][k]) for k in keys}, (s[x]["drift"], s[y]["drift"]), kitti))
        print(f"{label}: done", file=sys.stderr)
    rng = np.random.default_rng(SEED)
    text = [f"Generated {provenance()}. Differences are the first system minus the second (negative: "
            "the first lower); \"lower\" names a system only where the 95 % interval excludes 0.", "",
            "swarmpose's default against the peer (`tools/peers/opencv_vo.py`):", ""]
    text += table(comparisons[("swarmpose", "peer")], "swarmpose", "peer", rng)
    if comparisons[("peer", "shared peer")]:
        text += ["", "swarmpose's default against `../shared/peers/opencv_pnp_vo.py` itself (its `pnp` pipeline, "
                 "called where it lies; it cannot read EuRoC):", ""]
        text += table(comparisons[("swarmpose", "shared peer")], "swarmpose", "shared", rng)
        text += ["", "The peer against that script, the same way:", ""]
        text += table(comparisons[("peer", "shared peer")], "peer", "shared", rng)
    out = "\n".join(text) + "\n"
    publish(a.update, "peer-table", COMMAND, out)


if __name__ == "__main__":
    main()
