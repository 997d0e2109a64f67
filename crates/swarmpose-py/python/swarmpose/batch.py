"""Many sequences at once: the items of a ``swarmpose batch`` manifest run from Python,
in a local process pool (the default) or on a Ray cluster, into the same folders and
``summary.json`` files as the command line, so that ``merge`` (or ``swarmpose batch
merge``) makes the same table.

    import swarmpose.batch
    summaries = swarmpose.batch.run("fleet.toml", "out/fleet")               # processes
    summaries = swarmpose.batch.run("fleet.toml", "out/fleet", executor="ray")
    swarmpose.batch.merge("out/fleet")                                       # batch.csv, .md

Each item runs the engine through the extension (the GIL is released while it runs);
items whose summary says they finished with the same input, options and version are
skipped, as by the command line. With Ray, ``out`` (and the inputs) must be on a file
system every node sees; ``ray`` is the optional extra ``pip install swarmpose[ray]``.
"""

from __future__ import annotations

import json
import os
from concurrent.futures import Executor, ProcessPoolExecutor
from multiprocessing import get_context
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

from . import _swarmpose

__all__ = ["run", "merge", "run_item"]

PathLike = Union[str, "os.PathLike[str]"]


def run_item(manifest: PathLike, out: PathLike, name: str) -> Dict[str, Any]:
    """Runs item ``name`` of ``manifest`` into ``out/name`` (or skips it when done);
    returns its summary (``summary.json``) with ``"skipped"``. A failure that keeps the
    item from running at all (its folder cannot be written or is in use) is returned as
    a summary with status ``"not-run"`` rather than raised, so one item never stops the
    others."""
    try:
        text, skipped = _swarmpose._batch_item(os.fspath(manifest), os.fspath(out), name)
    except (OSError, RuntimeError, ValueError) as e:
        return {"item": name, "status": "not-run", "message": str(e), "skipped": False}
    summary = json.loads(text)
    summary["skipped"] = skipped
    return summary


def _ray_run(manifest: str, out: str, names: Sequence[str]) -> List[Dict[str, Any]]:
    try:
        import ray
    except ImportError as e:
        raise ImportError(
            "executor='ray' needs ray: pip install 'swarmpose[ray]'"
        ) from e
    if not ray.is_initialized():
        ray.init()
    task = ray.remote(num_cpus=1)(run_item)
    return list(ray.get([task.remote(manifest, out, n) for n in names]))


def run(
    manifest: PathLike,
    out: PathLike,
    *,
    executor: Union[str, Executor] = "process",
    jobs: Optional[int] = None,
    shard: Optional[Tuple[int, int]] = None,
) -> List[Dict[str, Any]]:
    """Runs the items of ``manifest`` (a ``swarmpose batch`` TOML manifest) into ``out``
    and returns their summaries in the manifest's order.

    ``executor``: ``"process"`` (a local process pool of ``jobs`` processes, default one
    per core), ``"ray"`` (one Ray task per item; ``ray.init()`` is called if Ray is not
    initialised yet), ``"serial"`` (this process), or any ``concurrent.futures.Executor``.
    ``shard=(i, n)`` runs only the i-th of n shares, as ``--shard i/n``. Bad manifests
    raise ``ValueError`` before anything runs."""
    manifest = os.path.abspath(os.fspath(manifest))
    out = os.path.abspath(os.fspath(out))
    index, count = shard if shard is not None else (1, 1)
    names = _swarmpose._batch_prepare(manifest, out, index, count)
    if isinstance(executor, Executor):
        futures = [executor.submit(run_item, manifest, out, n) for n in names]
        return [f.result() for f in futures]
    if executor == "serial":
        return [run_item(manifest, out, n) for n in names]
    if executor == "ray":
        return _ray_run(manifest, out, names)
    if executor == "process":
        workers = max(1, min(jobs or os.cpu_count() or 1, len(names) or 1))
        # "spawn": a fresh interpreter per worker, never a fork of a process whose
        # threads (Ray's, the engine's) may hold locks.
        with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as pool:
            return list(pool.map(run_item, [manifest] * len(names), [out] * len(names), names))
    raise ValueError(
        f"executor {executor!r}: use 'process', 'ray', 'serial' or a concurrent.futures.Executor"
    )


def merge(*dirs: PathLike, out: Optional[PathLike] = None) -> Tuple[int, str]:
    """``swarmpose batch merge DIRS --out OUT``: writes ``batch.csv`` and ``batch.md``
    (into the first folder by default) and returns ``(status, message)``: 0 when every
    item succeeded, 3 when some did not or are missing (the message names them)."""
    if not dirs:
        raise ValueError("merge needs at least one batch output folder")
    return _swarmpose._batch_merge(
        [os.fspath(d) for d in dirs], None if out is None else os.fspath(out)
    )
