"""Python overhead of swarmpose.register for 600 correspondences.

Times, interleaved call by call on the same data and seed (so both do the same work):
  rust    the estimator call that register wraps, timed inside Rust
          (swarmpose._register_timing: Estimator::estimate_seeded on correspondences
          built beforehand);
  python  swarmpose.register(src, dst) timed from Python: argument parsing, reading the
          numpy arrays, building the correspondences, the same estimator call, the
          result object.
Prints the medians, the overhead (python - rust) and whether it is within the budget
of issue 15: at most 5 % or 20 us, whichever is larger.

Usage: python bench/overhead.py [--repeats N] [--method pso]
"""

import argparse
import statistics
import time

import numpy as np

import swarmpose


def scene(n, seed=1):
    rng = np.random.default_rng(seed)
    a = 0.35
    r = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    src = rng.uniform([-8, -3, 2], [8, 3, 20], size=(n, 3))
    dst = src @ r.T + [0.8, -0.3, 1.5] + rng.normal(0, 0.005, size=(n, 3))
    bad = rng.choice(n, n // 4, replace=False)
    dst[bad] = rng.uniform([-8, -3, 2], [8, 3, 20], size=(len(bad), 3))
    return src, dst


def measure(src, dst, method, repeats):
    rust, python = [], []
    for _ in range(repeats):
        rust.append(swarmpose._register_timing(src, dst, method=method, seed=0, repeats=1)[0])
        t = time.perf_counter()
        swarmpose.register(src, dst, method=method, seed=0)
        python.append(time.perf_counter() - t)
    return rust, python


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=300)
    p.add_argument("--method", default="pso", choices=swarmpose.METHODS)
    p.add_argument("-n", type=int, default=600, help="correspondences")
    args = p.parse_args()
    src, dst = scene(args.n)
    print(f"swarmpose {swarmpose.__version__}, method {args.method}, {args.n} correspondences, "
          f"{args.repeats} calls each, interleaved")
    worst = True
    for label, s, d in [
        ("float64, C order", src, dst),
        ("float32, Fortran order", np.asfortranarray(src, np.float32),
         np.asfortranarray(dst, np.float32)),
    ]:
        measure(s, d, args.method, 5)  # warm up
        rust, python = measure(s, d, args.method, args.repeats)
        r, q = statistics.median(rust), statistics.median(python)
        over = q - r
        budget = max(0.05 * r, 20e-6)
        ok = over <= budget
        worst = worst and ok
        print(f"{label:24s} rust median {r * 1e6:9.1f} us   python median {q * 1e6:9.1f} us   "
              f"overhead {over * 1e6:7.1f} us = {100 * over / r:5.2f} %   "
              f"(budget {budget * 1e6:.1f} us: {'within' if ok else 'OVER'})")
    print("within budget" if worst else "OVER budget")


if __name__ == "__main__":
    main()
